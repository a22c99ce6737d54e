"""OpenCL drivers installed as Python packages, made visible to the ICD loader.

pyopencl's wheel carries an ICD loader that finds PoCL (``pocl-binary-distribution``) by itself
and reads the other drivers' vendor files from ``/etc/OpenCL/vendors``, or from the folder named
by ``OCL_ICD_VENDORS`` instead. Intel's CPU runtime (``intel-opencl-rt``) installs
``libintelocl.so`` into ``<prefix>/lib`` with a vendor file naming a placeholder path, so the
loader never finds it. :func:`register_vendors` writes a vendor folder in the user cache that
names the installed drivers' real paths beside every vendor file the system (or the user's own
``OCL_ICD_VENDORS``) has, and points ``OCL_ICD_VENDORS`` at it. The loader reads the variable
at the first platform query, so this runs when ``holo_core.opencl`` is imported; nothing
system-wide is changed.
"""

from __future__ import annotations

import hashlib
import logging
import os
import sys
import tempfile
from pathlib import Path

log = logging.getLogger(__name__)

SYSTEM_VENDORS = Path("/etc/OpenCL/vendors")
# vendor file name -> the driver library a Python package installs into <prefix>/lib
PACKAGED_DRIVERS = {"intel-cpu.icd": "libintelocl.so"}


def _prefixes() -> list[Path]:
    """Install prefixes of this interpreter's packages: the environment's, the user's, and
    each ``.../lib/pythonX.Y/site-packages`` on ``sys.path`` (Blender's extensions install
    their wheels under such a folder of their own)."""
    found = [Path(sys.prefix)]
    for entry in sys.path:
        p = Path(entry)
        if p.name == "site-packages" and len(p.parents) > 2:
            found.append(p.parents[2])
    return list(dict.fromkeys(found))


def packaged_drivers() -> dict[str, str]:
    """Vendor file name -> library path of each OpenCL driver installed as a package."""
    found = {}
    for name, lib in PACKAGED_DRIVERS.items():
        for prefix in _prefixes():
            path = prefix / "lib" / lib
            if path.is_file():
                found[name] = str(path.resolve())
                break
    return found


def _existing_vendors(previous: str) -> dict[str, str]:
    """The vendor files the loader would read without us: the user's ``OCL_ICD_VENDORS`` (a
    folder or one file), else the system folder."""
    source = Path(previous) if previous else SYSTEM_VENDORS
    files = (
        [source] if source.is_file() else sorted(source.glob("*.icd")) if source.is_dir() else []
    )
    vendors = {}
    for f in files:
        try:
            vendors[f.name] = f.read_text().strip()
        except OSError as e:
            log.debug("vendor file %s unreadable: %s", f, e)
    return vendors


def _write_folder(vendors: dict[str, str]) -> Path | None:
    digest = hashlib.sha256(repr(sorted(vendors.items())).encode()).hexdigest()[:16]
    try:
        from platformdirs import user_cache_dir

        bases = [Path(user_cache_dir("holo"))]
    except ImportError:
        bases = []
    bases.append(Path(tempfile.gettempdir()) / f"holo-{getattr(os, 'getuid', lambda: 0)()}")
    for base in bases:
        folder = base / "opencl-vendors" / digest
        try:
            folder.mkdir(parents=True, exist_ok=True)
            for name, content in vendors.items():
                target = folder / name
                if not target.is_file() or target.read_text().strip() != content:
                    tmp = folder / f".{name}.{os.getpid()}"
                    tmp.write_text(content + "\n")
                    os.replace(tmp, target)
            return folder
        except OSError as e:
            log.debug("OpenCL vendor folder not written in %s: %s", base, e)
    return None


def register_vendors() -> Path | None:
    """Point ``OCL_ICD_VENDORS`` at a folder naming the packaged drivers and the existing
    vendors; returns the folder, or None when no packaged driver is installed (the loader's
    own search is then left as it is)."""
    drivers = packaged_drivers()
    if not drivers:
        return None
    # a child process finds our folder here and writes the same one again
    vendors = {**_existing_vendors(os.environ.get("OCL_ICD_VENDORS", "")), **drivers}
    folder = _write_folder(vendors)
    if folder is not None:
        os.environ["OCL_ICD_VENDORS"] = str(folder)
        log.debug("OpenCL vendors: %s (%s)", folder, ", ".join(sorted(vendors)))
    return folder
