"""The built extension in Blender's LTS releases, end to end (``make check-lts``).

    python tools/blender_lts.py 4.2.0 4.5.15 5.2.3           # from .venv: every release
    python tools/blender_lts.py --in-blender ZIP WORKDIR      # one release, run by its bpy

The first form builds the linux-x64 extension as ``make extension`` does (a zip per Python the
releases need), and per release: makes ``.venv-bpy<version>`` with the Python its bpy module
needs (3.11 up to Blender 5.0, 3.13 from 5.1), runs the second form there with that Python's
zip, then the add-on's whole test suite with the installed extension's packages on the path
and deprecation warnings as errors, and ends with a line per release (tests passed, seconds).
The Python is the one named by ``PYTHON311=`` / ``PYTHON313=``, else ``python3.X`` on the PATH,
else the newest of pyenv's versions; a release whose Python is found nowhere is skipped with a
line saying what to install.

The second form validates the zip with that release's extension tool and installs it with
Blender's own installer into a fresh user folder (``BLENDER_USER_RESOURCES``), then on a small
scene (a holographic sphere, a sun, a plate, a camera) records the hologram, renders the
holographic pass (the sphere lit by Cycles in a process of its own), sets up the compositing
(the pass filling the emitters' holdouts) on that release's compositor API and renders the
frame. It fails when any step fails, and on
any deprecation warning from the add-on's or the core's code. Not part of ``make test``: each
release is a 370 MB download.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BUILD = ROOT / "build" / "lts"
NUMPY = {"3.11": "numpy<2", "3.13": "numpy>=2.2"}  # what each line's bpy wheels were built on


def python_line(release: str) -> str:
    """The Python a Blender release's bpy module needs: 3.11 up to 5.0, 3.13 from 5.1."""
    major, minor = (int(n) for n in release.split(".")[:2])
    return "3.11" if (major, minor) < (5, 1) else "3.13"


def _runs(python: str, line: str) -> bool:
    """``python`` runs, is Python ``line`` and can make virtual environments (pyenv's shim for
    a version that is not selected exits with an error; Debian splits off venv)."""
    check = f"import sys, venv, ensurepip; sys.exit('%d.%d' % sys.version_info[:2] != {line!r})"
    try:
        return subprocess.run([python, "-c", check], capture_output=True).returncode == 0
    except OSError:
        return False


def find_python(line: str) -> str | None:
    """A working Python ``line`` ("3.13"): ``PYTHON313=`` when given (an error when it does not
    work), else ``python3.13`` on the PATH, else the newest of pyenv's versions, else the one
    running this (the project's .venv)."""
    var = "PYTHON" + line.replace(".", "")
    given = os.environ.get(var)
    if given:
        if not _runs(given, line):
            sys.exit(f"{var}={given} is not a working Python {line} with venv")
        return given
    pyenv = os.environ.get("PYENV_ROOT") or Path.home() / ".pyenv"
    if shutil.which("pyenv"):
        pyenv = subprocess.run(["pyenv", "root"], capture_output=True, text=True).stdout.strip()
    versions = sorted(
        Path(pyenv).glob(f"versions/{line}.*/bin/python{line}"),
        reverse=True,
        key=lambda p: [int(n) for n in re.findall(r"\d+", p.parts[-3])],
    )
    candidates = [shutil.which(f"python{line}"), *map(str, versions), sys.executable]
    return next((p for p in candidates if p and _runs(p, line)), None)


def _run(cmd, **kw) -> subprocess.CompletedProcess:
    print("+", " ".join(map(str, cmd)), flush=True)
    return subprocess.run([str(c) for c in cmd], **kw)


def bpy_environment(release: str, python: str) -> tuple[Path, str]:
    """``.venv-bpy<release>``'s Python, with that release's bpy and pytest installed, and what
    installing them took ("" when they were there)."""
    venv = ROOT / f".venv-bpy{release}"
    py = venv / "bin" / "python"
    ready = (
        f"import importlib.metadata as m, sys; sys.exit(m.version('bpy') != {release!r} "
        f"or '%d.%d' % sys.version_info[:2] != {python_line(release)!r} "
        "or not m.version('pytest'))"
    )
    if py.exists() and subprocess.run([py, "-c", ready], capture_output=True).returncode == 0:
        return py, ""
    start = time.monotonic()
    shutil.rmtree(venv, ignore_errors=True)  # none, half installed, or another Python's
    print(f"Blender {release}: bpy {release} into {venv.name} (a 370 MB download)", flush=True)
    if (
        _run([python, "-m", "venv", venv]).returncode
        or _run(
            [
                py,
                "-m",
                "pip",
                "install",
                "--quiet",
                f"bpy=={release}",
                NUMPY[python_line(release)],
                "pytest",
            ]
        ).returncode
    ):
        sys.exit(f"Blender {release}: installing bpy {release} failed")
    return py, f" (bpy installed in {time.monotonic() - start:.0f} s)"


def check_release(release: str, python: str, zip_path: Path) -> str:
    """The end-to-end check and the add-on's tests on one release: its summary, which starts
    with FAILED when either fails."""
    py, installed = bpy_environment(release, python)
    start = time.monotonic()
    work = BUILD / release
    user = work / "user"
    work.mkdir(parents=True)
    env = {**os.environ, "BLENDER_USER_RESOURCES": str(user), "PYTHONNOUSERSITE": "1"}
    env.pop("PYTHONPATH", None)
    if _run([py, __file__, "--in-blender", zip_path, work], env=env).returncode:
        return "FAILED: the end-to-end check"
    e2e, start = time.monotonic() - start, time.monotonic()
    # The suite's Blender gets a user folder of its own (tests/addon/conftest.py): in the one
    # that holds the extension, factory settings disable it and 4.5 then removes its wheels.
    env.pop("BLENDER_USER_RESOURCES")
    env["PYTHONPATH"] = str(
        user / f"extensions/.local/lib/python{python_line(release)}/site-packages"
    )
    cmd = [
        py,
        "-m",
        "pytest",
        "-q",
        "-p",
        "no:cacheprovider",
        "-W",
        "error::DeprecationWarning",
        "tests/addon",
    ]
    print("+", " ".join(map(str, cmd)), flush=True)
    last = "no summary"
    with subprocess.Popen(
        cmd, env=env, cwd=ROOT, text=True, stdout=subprocess.PIPE, stderr=subprocess.STDOUT
    ) as tests:
        for line in tests.stdout:
            print(line, end="", flush=True)
            if re.match(r"\d+ (passed|failed|error)", line):  # "45 passed in 150.2s"
                last = line
    counts = ", ".join(re.findall(r"\d+ \w+", last.split(" in ")[0]))
    if tests.returncode:
        return f"FAILED: the add-on's tests ({counts})"
    return f"end to end OK in {e2e:.0f} s, {counts} in {time.monotonic() - start:.0f} s{installed}"


def main(releases: list[str]) -> None:
    start = time.monotonic()
    pythons = {line: find_python(line) for line in dict.fromkeys(map(python_line, releases))}
    runs, summary = [], []
    for release in releases:
        line = python_line(release)
        if pythons[line]:
            runs.append(release)
            continue
        var = "PYTHON" + line.replace(".", "")
        summary.append(
            f"Blender {release}: skipped, its bpy needs Python {line} and none was "
            f"found; install it (pyenv install {line}, or the system's python{line} "
            f"with venv) or name it: make check-lts {var}=/path/to/python{line}"
        )
    if runs:
        shutil.rmtree(BUILD, ignore_errors=True)
        lines = sorted({python_line(r) for r in runs})
        if _run(
            [
                sys.executable,
                "-m",
                "holo_addon.build",
                "--platform",
                "linux-x64",
                *(a for line in lines for a in ("--python", line)),
                "-o",
                BUILD,
            ],
            cwd=ROOT,
        ).returncode:
            sys.exit("building the extension failed")
        zips = {line: next(BUILD.glob(f"holo-*-py{line.replace('.', '')}.zip")) for line in lines}
    for release in runs:
        python = pythons[python_line(release)]
        version = subprocess.run([python, "-V"], capture_output=True, text=True).stdout.split()
        summary.append(
            f"Blender {release} (Python {version[-1]}, {python}): "
            + check_release(release, python, zips[python_line(release)])
        )
    print("\n".join(["", *summary, f"check-lts: {time.monotonic() - start:.0f} s"]))
    if any("FAILED" in line for line in summary):
        sys.exit(1)


# The second form, run by one release's bpy module.


def install(zip_path: str):
    """The zip validated and then installed and enabled by this release's own extension tools;
    returns the add-on's module."""
    import bpy

    bl_pkg = Path(bpy.utils.system_resource("SCRIPTS")) / "addons_core" / "bl_pkg"
    check = subprocess.run(
        [sys.executable, bl_pkg / "cli" / "blender_ext.py", "validate", zip_path],
        capture_output=True,
        text=True,
    )
    if check.returncode:  # this release's own rules for the manifest and the zip
        sys.exit(f"the zip does not validate:\n{check.stdout}{check.stderr}")
    sys.path.insert(0, str(bl_pkg.parent))
    from bl_pkg import cli_extension

    bpy.ops.wm.read_homefile(app_template="")
    rc = cli_extension(["install-file", zip_path, "--repo", "user_default", "--enable"])
    if rc or not hasattr(bpy.types.Scene, "holo"):
        sys.exit(f"the extension did not install and register (exit {rc})")
    return sys.modules["bl_ext.user_default.holo"]


def scene(work: Path):
    import bpy

    s = bpy.context.scene
    for obj in list(s.objects):
        bpy.data.objects.remove(obj)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.3)
    bpy.context.object.holo.emitter = "POINTS"
    bpy.ops.object.light_add(type="SUN", rotation=(1.5708, 0, 0))  # from the camera's side
    bpy.context.object.data.energy = 3.0  # Lighting: Scene (the default) renders it with Cycles
    bpy.ops.object.camera_add(location=(0, -3, 0), rotation=(1.5708, 0, 0))
    s.camera = bpy.context.object
    bpy.ops.mesh.primitive_plane_add(size=0.8, location=(0, -1.5, 0), rotation=(1.5708, 0, 0))
    bpy.context.object.holo.is_plate = True  # its +Z faces the camera
    s.render.resolution_x, s.render.resolution_y, s.render.resolution_percentage = 48, 36, 100
    s.render.engine = "CYCLES"  # Workbench draws every object: the emitter too
    s.cycles.samples = 4
    s.holo.iterations, s.holo.max_resolution = 1, 512
    s.holo.output_dir = str(work / "holo") + os.sep
    s.render.filepath = str(work / "frame.png")
    return s


def end_to_end(zip_path: str, work: str) -> tuple[str, list[Path]]:
    """What was done, and the folders of the add-on's and the core's code."""
    import bpy

    work = Path(work)
    addon = install(zip_path)
    import pyopencl

    import holo_core

    s = scene(work)
    for op in (bpy.ops.holo.render_pass, bpy.ops.holo.setup_compositing):
        if op() != {"FINISHED"}:
            sys.exit(f"{op.idname_py()} did not finish")
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(s.render.filepath)
    w, h = image.size
    px = list(image.pixels)
    centre, corner = ((h // 2 * w + w // 2) * 4, 0)
    if not sum(px[centre : centre + 3]) > sum(px[corner : corner + 3]) + 0.1:
        sys.exit("the holographic sphere is missing from the composited frame")
    layers = sorted(work.glob("holo_frame*.exr"))
    if not layers or not layers[0].stat().st_size:
        sys.exit(f"no holographic layers beside the render in {work}")
    done = (
        f"Blender {bpy.app.version_string}: installed, registered (core at "
        f"{holo_core.__file__}, {len(pyopencl.get_platforms())} OpenCL platform), recorded, "
        f"pass rendered and composited, layers written beside the frame ({layers[0].name}), "
        "no deprecation warning from the extension: OK"
    )
    return done, [Path(addon.__file__).parent, Path(holo_core.__file__).parent]


def in_blender(zip_path: str, work: str) -> None:
    """The end-to-end check, failing on deprecation warnings from the extension's code (those
    raised in Blender's handlers and timers included, which an error filter would not stop)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DeprecationWarning)
        done, ours = end_to_end(zip_path, work)
    mine = [
        w
        for w in caught
        if issubclass(w.category, DeprecationWarning)
        and any(Path(w.filename).is_relative_to(d) for d in ours)
    ]
    for w in mine:
        print(f"{w.filename}:{w.lineno}: {w.category.__name__}: {w.message}", file=sys.stderr)
    if mine:
        sys.exit(f"{len(mine)} deprecation warning(s) from the extension's code")
    print(done)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--in-blender"] and len(sys.argv) == 4:
        in_blender(*sys.argv[2:4])
    elif sys.argv[1:] and not sys.argv[1].startswith("-"):
        main(sys.argv[1:])
    else:
        sys.exit(__doc__.split("\n\n")[1])
