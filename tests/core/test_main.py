"""The command line (``python -m holo_core``): a bad argument, an output it cannot write, an
interrupt or any failure is one line and a status (2, 130, 1), and the output is checked
before the work."""

import re
import subprocess
import sys

import numpy as np
import pinhole
import pytest
from cli import CUBE_OBJ, run_cli, run_process

from holo_core.io.hologram import write_hologram
from holo_core.io.image import read_exr


def test_max_points_0_is_refused_on_one_line(tmp_path):
    (tmp_path / "q.obj").write_text(CUBE_OBJ)
    run = run_process("record", tmp_path / "q.obj", "-o", tmp_path / "h.exr", "--max-points", 0)
    assert run.returncode == 2 and "--max-points" in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1 and not (tmp_path / "h.exr").exists()


def test_cli_bad_arguments_name_the_argument_and_its_range(tmp_path):
    (tmp_path / "q.obj").write_text(CUBE_OBJ)
    for args, problem in [
        (["--pitch", "0"], "--pitch: '0' is out of range (metres, from 1e-13"),
        (["--resolution", "0", "0"], "--resolution: '0' is out of range"),
        (["--wavelengths", "nan"], "--wavelengths: 'nan' is out of range"),
    ]:
        run = run_process("record", tmp_path / "q.obj", "-o", tmp_path / "h.exr", *args)
        assert run.returncode == 2 and problem in run.stderr, run.stderr
        assert len(run.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("output, status", [("/proc/holo.exr", 2), ("below/a/file", 2)])
def test_cli_unwritable_output_is_one_line(tmp_path, point_hologram, output, status):
    path = write_hologram(tmp_path / "h.exr", point_hologram)
    (tmp_path / "below").write_text("a file")
    run = run_process(
        "render",
        path,
        "-o",
        output if output.startswith("/") else tmp_path / output,
        *pinhole.CAMERA_ARGS,
    )
    assert run.returncode == status, run.stderr
    lines = [l for l in run.stderr.strip().splitlines() if not l.startswith("warning: ")]
    assert "Traceback" not in run.stderr and len(lines) == 1, run.stderr


def test_cli_render_into_a_folder_writes_inside_it(tmp_path, point_hologram):
    path = write_hologram(tmp_path / "h.exr", point_hologram)
    (tmp_path / "views").mkdir()
    run = run_process("render", path, "-o", tmp_path / "views", *pinhole.CAMERA_ARGS)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "views" / "h_view.exr").is_file() and not (tmp_path / "views.exr").exists()


def test_cli_sigint_ends_in_one_line(tmp_path):
    import signal

    proc = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import time, sys\nfrom holo_core.__main__ import main\n"
            "import holo_core.__main__ as m\n"
            "m.info = lambda a: time.sleep(30)\n"
            "sys.exit(main(['info', 'x']))",
        ],
        stderr=subprocess.PIPE,
        text=True,
    )
    import time

    time.sleep(1.5)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130 and err.strip() == "interrupted", err


def test_cli_unexpected_failure_is_one_line_and_debug_shows_the_traceback(tmp_path):
    code = (
        "import sys\nimport holo_core.__main__ as m\n"
        "def boom(a): raise RuntimeError('driver fault')\nm.info = boom\n"
        "sys.exit(m.main(sys.argv[1:]))"
    )
    quiet = subprocess.run(
        [sys.executable, "-c", code, "info", "x"], capture_output=True, text=True
    )
    assert quiet.returncode == 1 and quiet.stderr.strip().splitlines() == [
        "error: RuntimeError: driver fault (--debug shows the traceback)"
    ]
    loud = subprocess.run(
        [sys.executable, "-c", code, "--debug", "info", "x"], capture_output=True, text=True
    )
    assert "Traceback" in loud.stderr and loud.returncode == 1


def test_cli_wavelengths_below_1_are_refused_as_nanometres(tmp_path, capsys):
    """The CLI's --wavelengths is the one length in nm: 633e-9 (metres) is refused."""
    (tmp_path / "q.obj").write_text(CUBE_OBJ)
    status, _, err = run_cli(
        capsys, "record", tmp_path / "q.obj", "-o", tmp_path / "h.exr", "--wavelengths", "633e-9"
    )
    assert status == 2 and "--wavelengths: '633e-9' is out of range (nm, from 1" in err, err
    assert "633 is red light" in err and not list(tmp_path.glob("*.exr"))


@pytest.mark.parametrize(
    "output, problem",
    [
        ("/sys/holo.exr", "its folder /sys is not writable"),  # read-only, even for root
        ("{tmp}/a_file/h.exr", "is not a folder"),
        ("{tmp}/r.png", r"r.png: the file is written as OpenEXR; name it \*\.exr"),
    ],
)
@pytest.mark.parametrize("command", ["record", "render"])
def test_cli_output_is_checked_before_the_work(
    tmp_path, point_hologram, capsys, monkeypatch, output, problem, command
):
    """An output the command cannot write is refused before the work, naming it: a read-only
    folder before the recording, and an EXR view asked for under a .png name."""
    import holo_core.plate.points
    import holo_core.plate.view

    def never(*_, **__):
        raise AssertionError("the work started before the output was checked")

    monkeypatch.setattr(holo_core.plate.points, "record_points", never)
    monkeypatch.setattr(holo_core.plate.view, "render_view", never)
    (tmp_path / "q.obj").write_text(CUBE_OBJ)
    (tmp_path / "a_file").write_text("a file")
    source = (
        tmp_path / "q.obj"
        if command == "record"
        else write_hologram(tmp_path / "h.exr", point_hologram)
    )
    before = sorted(tmp_path.iterdir())
    status, out, err = run_cli(
        capsys, command, source, "-o", output.format(tmp=tmp_path), "--resolution", 16, 16
    )
    assert status == 2 and re.search(problem, err) and err.count("\n") == 1, err
    assert out == "" and sorted(tmp_path.iterdir()) == before


@pytest.mark.parametrize("method", ["zone", "direct"])
def test_a_hologram_beyond_the_disks_room_is_refused_before_the_recording(
    small_disk, capsys, monkeypatch, method
):
    """A hologram the output's disk cannot hold is refused in one line before the work (no
    recording runs), with the room it needs and the room there is."""
    import holo_core.plate.looks
    import holo_core.plate.points

    (small_disk / "q.obj").write_text(CUBE_OBJ)

    def never(*_, **__):
        raise AssertionError("the recording ran before the disk's room was checked")

    monkeypatch.setattr(holo_core.plate.looks, "record_plate", never)
    monkeypatch.setattr(holo_core.plate.points, "record_points", never)
    status, _, err = run_cli(
        capsys,
        "record",
        small_disk / "q.obj",
        "-o",
        small_disk / "h.exr",
        "--method",
        method,
        "--distance",
        "0.02",
        *(["--resolution", "1024", "1024"] if method == "direct" else []),
    )
    assert status == 2, err
    assert re.search(
        rf"the hologram \(\d+ x \d+ samples\) would need [\d.e-]+ GiB on disk, and "
        rf"{small_disk} has [\d.e-]+ GiB free",
        err,
    ), err
    assert not (small_disk / "h.exr").exists()


# a 6 cm cube whose nearest face is 5 cm behind the plate, off its axis
NEAR_CUBE_OBJ = (
    "".join(
        f"v {x + 0.01:g} {y:g} {z:g}\n"
        for x in (0, 0.06)
        for y in (0, 0.06)
        for z in (-0.11, -0.05)
    )
    + "f 1 2 4 3\nf 5 7 8 6\nf 1 5 6 2\nf 3 4 8 7\nf 1 3 7 5\nf 2 6 8 4\n"
)


@pytest.mark.parametrize("placement", [(), ("--distance", 0.3)], ids=["where it is", "moved"])
def test_plan_states_the_plate_record_makes(tmp_path, capsys, placement):
    """``plan MESH`` and ``record MESH`` with the same options place the mesh alike and plan
    one plate: the samples plan states are the recorded file's (plan moved a mesh 0.3 m
    behind the plate where record kept it where it was: 491² samples planned, 3597²
    recorded)."""
    from holo_core.io.hologram import read_hologram

    (tmp_path / "cube.obj").write_text(NEAR_CUBE_OBJ)
    common = (tmp_path / "cube.obj", "--resolution", 64, 36, *placement)
    status, out, err = run_cli(capsys, "plan", *common)
    assert status == 0, err
    planned = re.search(r"plate .*: (\d+) x (\d+) samples", out)
    status, _, err = run_cli(capsys, "record", *common, "-o", tmp_path / "h.exr")
    assert status == 0, err
    rows, cols = read_hologram(tmp_path / "h.exr").shape
    assert planned and (int(planned[1]), int(planned[2])) == (cols, rows), (out, rows, cols)


def test_plan_of_a_plate_no_machine_can_record_fails(tmp_path, capsys):
    """Objects a micrometre behind the plate need a plate beyond any memory: plan states its
    figures with the refusal second, and exits 2 (it said "sharp … about 1.5e+09 h", 0)."""
    (tmp_path / "cube.obj").write_text(NEAR_CUBE_OBJ)
    status, out, _ = run_cli(capsys, "plan", tmp_path / "cube.obj", "--distance", 1e-6)
    lines = out.splitlines()
    assert status == 2 and lines[0].startswith("verdict"), out
    assert re.match(
        r"refused +recording the plate needs .* of memory a tile at a time; the "
        r"memory budget is",
        lines[1],
    ), out


@pytest.mark.parametrize("command", ["record", "render"])
def test_cli_output_without_room_is_refused_before_the_work(
    tmp_path, point_hologram, capsys, monkeypatch, command
):
    """An output folder on a disk too small for the file (a 1 MiB file system): one line
    naming the folder and both sizes, before any recording or view (a full disk was found
    after the whole recording, named by a hidden temporary file)."""
    from mounts import small_disk

    import holo_core.plate.looks
    import holo_core.plate.view

    def never(*_, **__):
        raise AssertionError("the work started before the room was checked")

    monkeypatch.setattr(holo_core.plate.looks, "record_plate", never)
    monkeypatch.setattr(holo_core.plate.view, "render_view", never)
    (tmp_path / "cube.obj").write_text(NEAR_CUBE_OBJ)
    source, size = (
        (tmp_path / "cube.obj", (160, 90))
        if command == "record"
        else (write_hologram(tmp_path / "h.exr", point_hologram), (400, 400))
    )
    with small_disk(tmp_path / "disk") as disk:
        status, out, err = run_cli(
            capsys, command, source, "-o", disk / "out.exr", "--resolution", *size
        )
        assert status == 2 and err.count("\n") == 1, err
        assert re.search(rf"need [\d.]+ GiB on disk, and {disk} has 0.000977 GiB free", err), err
        assert not list(disk.iterdir())


TRIANGLE_OBJ = "v -0.002 -0.002 0\nv 0.002 -0.002 0\nv 0 0.002 0\nf 1 2 3\n"


@pytest.mark.parametrize("wavelengths", [["633", "532"], ["633", "532", "473", "450"]])
def test_record_any_number_of_wavelengths_then_render(tmp_path, capsys, wavelengths):
    """``record --wavelengths`` with two or four wavelengths writes a hologram whose render
    gives a three-channel view with light in it."""
    (tmp_path / "tri.obj").write_text(TRIANGLE_OBJ)
    status, _, err = run_cli(
        capsys,
        "record",
        tmp_path / "tri.obj",
        "-o",
        tmp_path / "h.exr",
        "--method",
        "auto",
        "--resolution",
        256,
        256,
        "--wavelengths",
        *wavelengths,
        "--distance",
        0.02,
        "--max-points",
        500,
    )
    assert status == 0, err
    status, out, err = run_cli(
        capsys, "render", tmp_path / "h.exr", "-o", tmp_path / "v.exr", "--resolution", 32, 32
    )
    assert status == 0, err
    _, channels = read_exr(tmp_path / "v.exr")
    rgb = np.stack([channels[f"ViewLayer.Combined.{c}"] for c in "RGB"], -1)
    assert rgb.shape == (32, 32, 3) and rgb.max() > 0, rgb.shape


@pytest.mark.parametrize("y", ["-1e-3", "-1E-3", "-1.0e-3", "-.001", "-0.001", "-1e-03"])
def test_the_command_line_takes_negative_numbers_in_any_notation(capsys, y):
    """``--camera 0.01 -1e-3 0.3`` takes the negative coordinate in every notation (argparse
    would read the exponent notation as an option)."""
    status, out, err = run_cli(capsys, "plan", "--box", 0.01, 0.01, 0.01, "--camera", 0.01, y, 0.3)
    assert status == 0, err
    assert "for the camera at (0.01, -0.001, 0.3) m" in out, out
