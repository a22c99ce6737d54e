"""Build the Blender extension zip(s) with Blender's own builder (``make extension``).

The repository root is the extension root. This stages ``__init__.py``, ``holo_addon/`` and
the manifest into ``build/extension/``, adds wheels — the core as the ``holo`` wheel, and the
runtime dependencies from ``pyproject.toml`` downloaded from the package index for each
platform and Python that Blender 4.2 … 5.x uses (numpy comes with Blender) — lists them in the
staged manifest, and runs ``blender_ext.py build --split-platforms`` from the bpy wheel, once per
Python: each zip holds one Python's wheels and names the Blender releases that run that Python
(``BLENDERS``), because Blender 4.2.0's installer installs every wheel of a zip whatever its
Python tag (4.2.23 and 4.5 skip the others). Wheels are fetched at build time and never
committed.

    python -m holo_addon.build [--platform linux-x64 ...] [--python 3.11 ...] [-o dist]
"""

from __future__ import annotations

import argparse
import importlib.util
import logging
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
log = logging.getLogger("holo_addon.build")

# Blender's platform names → pip platform tags (newest first).
PLATFORMS = {
    "linux-x64": ["manylinux_2_28_x86_64", "manylinux_2_17_x86_64", "manylinux2014_x86_64"],
    "windows-x64": ["win_amd64"],
    "macos-arm64": ["macosx_11_0_arm64", "macosx_12_0_arm64", "macosx_14_0_arm64"],
    "macos-x64": ["macosx_10_9_x86_64", "macosx_10_15_x86_64", "macosx_11_0_x86_64"],
}
PYTHONS = ("3.11", "3.13")  # Blender 4.2-5.0 and 5.1+
# Per Python, the Blender releases that run it: blender_version_min and blender_version_max (the
# first release that does not) of its zips.
BLENDERS = {"3.11": ("4.2.0", "5.1.0"), "3.13": ("5.1.0", None)}
PROVIDED = {"numpy"}  # Blender bundles these
# Intel's CPU OpenCL runtime is 276 MB of wheels (intel-opencl-rt 225 MB, intel-cmplr-lib-rt
# 41 MB, tbb 7 MB, tcmlib 3 MB): with the rest, a Linux zip of about 360 MB, over what
# extensions.blender.org accepts. The add-on's preferences install it on demand instead.
ON_DEMAND = {"intel-opencl-rt", "intel-cmplr-lib-rt"}


def runtime_requirements() -> list[str]:
    """pyproject's dependencies, less those Blender provides and their environment markers
    (pip evaluates markers for the host, not the target; a package with no wheel for a target
    is left out there and reported)."""
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    reqs = [d.split(";")[0].strip() for d in deps]
    return [r for r in reqs if re.split(r"[<>=!~ \[]", r)[0].lower() not in PROVIDED | ON_DEMAND]


def _pip(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "pip", *args], capture_output=True, text=True)


def download_wheels(dest: Path, platform: str, python: str) -> list[str]:
    """Download the runtime wheels for one target into ``dest``; returns what had no wheel."""
    tags = [a for t in PLATFORMS[platform] for a in ("--platform", t)]
    common = [
        "download",
        "--only-binary=:all:",
        "--python-version",
        python,
        "--implementation",
        "cp",
        *tags,
        "-d",
        str(dest),
        "--quiet",
    ]
    missing = []
    for req in runtime_requirements():
        if _pip(*common, req).returncode != 0:
            missing.append(req)
    for whl in dest.glob("*.whl"):
        if whl.name.split("-")[0].lower() in PROVIDED:
            whl.unlink()
    return missing


def blender_builder() -> Path:
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        raise SystemExit(
            "the bpy module is needed for Blender's extension builder (make extension installs it)"
        )
    found = sorted(
        Path(spec.submodule_search_locations[0]).glob(
            "*/scripts/addons_core/bl_pkg/cli/blender_ext.py"
        )
    )
    if not found:
        raise SystemExit("Blender's extension builder (blender_ext.py) is not in the bpy wheel")
    return found[-1]


def stage(dest: Path, platforms, python: str) -> Path:
    """The extension source tree with one Python's wheels and a manifest listing them, bounded
    to the Blender releases that run that Python."""
    if dest.exists():
        shutil.rmtree(dest)
    wheels = dest / "wheels"
    wheels.mkdir(parents=True)
    shutil.copy2(ROOT / "__init__.py", dest / "__init__.py")
    shutil.copytree(
        ROOT / "holo_addon",
        dest / "holo_addon",
        ignore=shutil.ignore_patterns("__pycache__", "build.py"),
    )
    result = _pip("wheel", str(ROOT), "--no-deps", "-w", str(wheels), "--quiet")
    if result.returncode != 0:
        raise SystemExit(f"building the holo wheel failed:\n{result.stderr}")
    for platform in platforms:
        missing = download_wheels(wheels, platform, python)
        if missing:
            log.warning("%s, Python %s: no wheel for %s", platform, python, ", ".join(missing))
    manifest = (ROOT / "blender_manifest.toml").read_text()
    first, last = BLENDERS[python]
    manifest, found = re.subn(
        r'(?m)^blender_version_min = ".*"$', f'blender_version_min = "{first}"', manifest
    )
    if found != 1:
        raise SystemExit("blender_manifest.toml has no blender_version_min")
    names = sorted(f"./wheels/{w.name}" for w in wheels.glob("*.whl"))
    keys = (
        "platforms = ["
        + ", ".join(f'"{p}"' for p in platforms)
        + "]\n"
        + (f'blender_version_max = "{last}"  # Python {python}\n' if last else "")
        + "wheels = [\n"
        + "".join(f'  "{n}",\n' for n in names)
        + "]\n\n"
    )
    first_table = manifest.index("\n[") + 1  # top-level keys go before the first table
    (dest / "blender_manifest.toml").write_text(
        manifest[:first_table] + keys + manifest[first_table:]
    )
    return dest


def build(out: Path, platforms=tuple(PLATFORMS), pythons=PYTHONS) -> list[Path]:
    """Build one zip per platform and Python into ``out``, named
    ``holo-<version>[-<platform>]-py<3xx>.zip``; returns their paths."""
    out.mkdir(parents=True, exist_ok=True)
    built = []
    for python in pythons:
        src = stage(ROOT / "build" / "extension", platforms, python)
        tmp = ROOT / "build" / "extension-zips"
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir(parents=True)
        cmd = [
            sys.executable,
            str(blender_builder()),
            "build",
            "--source-dir",
            str(src),
            "--output-dir",
            str(tmp),
        ]
        if len(platforms) > 1:
            cmd.append("--split-platforms")
        result = subprocess.run(cmd, capture_output=True, text=True)
        if result.returncode != 0:
            raise SystemExit(f"Blender's builder failed:\n{result.stdout}\n{result.stderr}")
        check = subprocess.run(
            [sys.executable, str(blender_builder()), "validate", str(src)],
            capture_output=True,
            text=True,
        )
        if check.returncode != 0:
            raise SystemExit(f"the extension does not validate:\n{check.stdout}{check.stderr}")
        for z in sorted(tmp.glob("*.zip")):
            built.append(out / f"{z.stem}-py{python.replace('.', '')}.zip")
            shutil.move(z, built[-1])
        shutil.rmtree(tmp)
    return built


def main(argv=None):
    p = argparse.ArgumentParser(
        prog="python -m holo_addon.build", description=__doc__.split("\n\n")[0]
    )
    p.add_argument(
        "--platform",
        action="append",
        choices=sorted(PLATFORMS),
        help="Blender platform (repeatable; default: all)",
    )
    p.add_argument("--python", action="append", help="Python version (default: 3.11 and 3.13)")
    p.add_argument("-o", "--output", type=Path, default=ROOT / "dist")
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    zips = build(args.output, tuple(args.platform or PLATFORMS), tuple(args.python or PYTHONS))
    for z in zips:
        print(f"built {z} ({z.stat().st_size / 1e6:.1f} MB)")


if __name__ == "__main__":
    main()
