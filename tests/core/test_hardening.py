"""Reproducers of the hardening issue's findings: each bad input ends in a clear InputError
(or a one-line CLI error), and nothing wrong is ever written."""

import io
import json
import math
import os
import re
import struct
import subprocess
import sys

import numpy as np
import pytest
from cli import run_cli as _cli_main
from PIL import Image

from holo_core.io.acquired import import_acquired
from holo_core.io.hologram import HologramFileError, read_hologram, write_hologram
from holo_core.io.image import write_exr
from holo_core.io.mesh import MeshFileError, read_mesh
from holo_core.io.view import write_view
from holo_core.plate.record import record_points
from holo_core.plate.view import NoDepthWarning, render_view
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.hologram import Hologram
from holo_core.validate import InputError
from holo_core.view import RenderResult

CUBE_OBJ = ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")


def cli(*args, env=None):
    return subprocess.run([sys.executable, "-m", "holo_core", *map(str, args)],
                          capture_output=True, text=True, timeout=300,
                          env={**os.environ, **(env or {})})


@pytest.fixture(scope="module")
def hologram():
    """A point 3 mm behind a 128 µm plate (the geometry of the pinhole physics test)."""
    return record_points([[0, 0, -3e-3]], [[1.0]], shape=(128, 128), pitch=1e-6,
                         wavelengths=(633e-9,))


def camera(resolution=(16, 16)):
    return Camera(matrix_world=look_at((0, 0, 4e-3), (0, 0, -3e-3)), lens=50,
                  sensor_width=50 * 48 * 4e-3 * resolution[0] / 48, resolution=resolution)


CAMERA_ARGS = ["--camera", 0, 0, 4e-3, "--sensor-width", 50 * 16 * 4e-3, "--resolution", 16, 16]


# --- recording ----------------------------------------------------------------------------

def test_points_nearer_than_the_plate_samples_are_refused_with_the_safe_distance():
    with pytest.raises(InputError, match=r"points need \|z\| >= 0.000\d+ m"):
        record_points([[0, 0, -4e-6]], [[1.0]], shape=(64, 64), pitch=8e-6,
                      wavelengths=(633e-9,))


def test_no_points_and_max_points_0_are_refused(tmp_path):
    with pytest.raises(InputError, match="nothing to record"):
        record_points(np.zeros((0, 3)), np.zeros((0, 1)), shape=(8, 8), pitch=8e-6,
                      wavelengths=(633e-9,))
    (tmp_path / "q.obj").write_text(CUBE_OBJ)
    run = cli("record", tmp_path / "q.obj", "-o", tmp_path / "h.exr", "--max-points", 0)
    assert run.returncode == 2 and "--max-points" in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1 and not (tmp_path / "h.exr").exists()


def test_a_non_finite_or_empty_hologram_is_never_written(tmp_path, hologram):
    bad = Hologram(intensity=np.full((1, 4, 4), np.nan, np.float32), wavelengths=(633e-9,),
                   pitch=8e-6)
    with pytest.raises(HologramFileError, match="NaN"):
        write_hologram(tmp_path / "h.exr", bad)
    empty = Hologram(intensity=np.zeros((1, 0, 4), np.float32), wavelengths=(633e-9,), pitch=8e-6)
    with pytest.raises(HologramFileError, match="no samples"):
        write_hologram(tmp_path / "h.exr", empty)
    assert not list(tmp_path.iterdir())


def test_sizes_are_refused_before_allocation(tmp_path, hologram):
    with pytest.raises(InputError, match=r"needs [\d.e+]+ GiB of memory; [\d.]+ GiB is available"):
        record_points([[0, 0, -1.0]], [[1.0]], shape=(200000, 200000), pitch=8e-6,
                      wavelengths=(633e-9,))
    with pytest.raises(InputError, match="20000x20000 view"):
        render_view(hologram, camera((20000, 20000)))
    # an EXR header declaring 100000² pixels: refused from the header alone
    path = write_hologram(tmp_path / "h.exr", hologram)
    data = path.read_bytes()
    at = data.find(b"dataWindow\x00box2i\x00") + len(b"dataWindow\x00box2i\x00") + 4
    path.write_bytes(data[:at + 8] + struct.pack("<ii", 99999, 99999) + data[at + 16:])
    with pytest.raises(HologramFileError, match="100000x100000 pixels"):
        read_hologram(path)


# --- mesh files ----------------------------------------------------------------------------

def test_ply_with_an_empty_face_skips_it_with_a_warning(tmp_path):
    ply = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
           "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
           "end_header\n0 0 0\n1 0 0\n0 1 0\n0\n3 0 1 2\n")
    (tmp_path / "m.ply").write_text(ply)
    with pytest.warns(UserWarning, match="1 face"):
        assert read_mesh(tmp_path / "m.ply").triangles.tolist() == [[0, 1, 2]]


@pytest.mark.parametrize("body, problem", [
    ("element vertex 3\nproperty float x\nend_header\n0    1\n", "truncated"),
    ("element vertex 1\nproperty float y\nend_header\n0\n", "x, y, z"),
    ("element vertex 1\nproperty int64 x\nend_header\n0\n", "cannot read"),
    ("element junk 1000000000000\nend_header\n", "no properties"),
    ("element vertex 1000000000000\nproperty float x\nend_header\n0\n", "more than the file"),
    ("element vertex 1\nproperty float x\nproperty float x\nend_header\n0 0\n", "twice"),
])
def test_damaged_ply_names_the_file_and_the_problem(tmp_path, body, problem):
    path = tmp_path / "m.ply"
    path.write_bytes(b"ply\nformat ascii 1.0\n" + body.encode())
    with pytest.raises(MeshFileError, match=f"{path}.*{problem}"):
        read_mesh(path)
    path.write_bytes(b"ply\nformat ascii 1.0\n\xff\xfe" + body.encode())
    with pytest.raises(MeshFileError, match="ASCII"):
        read_mesh(path)


def test_binary_big_endian_ply_reads_as_little_endian(tmp_path):
    verts = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)]
    meshes = []
    for fmt, e in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
        head = (f"ply\nformat {fmt} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                f"property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                f"end_header\n").encode()
        body = b"".join(struct.pack(e + "fff", *v) for v in verts)
        (tmp_path / f"{fmt}.ply").write_bytes(head + body + struct.pack(e + "B4i", 4, 0, 1, 3, 2))
        meshes.append(read_mesh(tmp_path / f"{fmt}.ply"))
    assert np.array_equal(meshes[0].vertices, meshes[1].vertices)
    assert meshes[0].triangles.tolist() == meshes[1].triangles.tolist() == [[0, 1, 3], [0, 3, 2]]


def test_obj_with_a_byte_order_mark_reads_the_same_geometry(tmp_path):
    (tmp_path / "a.obj").write_text(CUBE_OBJ)
    (tmp_path / "b.obj").write_bytes(b"\xef\xbb\xbf" + CUBE_OBJ.encode())
    a, b = read_mesh(tmp_path / "a.obj"), read_mesh(tmp_path / "b.obj")
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.triangles, b.triangles)


@pytest.mark.parametrize("text, problem", [
    ("", "no vertices"), ("hello world\n", "no vertices"), ("v 0 0 0\n", "no faces"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "out of range"),
    ("v 0 0 x\n", "line 1"), ("v 0 0 0\nf 0 1 2\n", "line 2: OBJ indices start at 1"),
    ("v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "finite"),
])
def test_bad_obj_names_the_file_and_the_problem(tmp_path, text, problem):
    (tmp_path / "m.obj").write_text(text)
    with pytest.raises(MeshFileError, match=problem):
        read_mesh(tmp_path / "m.obj")


# --- hologram files --------------------------------------------------------------------------

def _with_meta(path, edit):
    import OpenEXR
    with OpenEXR.File(str(path), separate_channels=True) as f:
        header = dict(f.header())
        chans = {n: np.array(c.pixels) for n, c in f.channels().items()}
    meta = json.loads(header["holo"])
    edit(meta, chans)
    header["holo"] = json.dumps(meta)
    with OpenEXR.File(header, chans) as f:
        f.write(str(path))


@pytest.mark.parametrize("edit, problem", [
    (lambda m, c: m.pop("pitch_m"), r"pitch_m must be a number \[m\]; got 'missing'"),
    (lambda m, c: m.update(pitch_m=0), "pitch_m"),
    (lambda m, c: m.update(pitch_m=-8e-6), "pitch_m"),
    (lambda m, c: m.update(pitch_m=float("nan")), "pitch_m"),
    (lambda m, c: m.update(pitch_m="8e-6"), "pitch_m"),
    (lambda m, c: m.update(wavelengths_m=[0.0]), "wavelengths_m"),
    (lambda m, c: m.update(band_sin=2.0), r"band_sin must be in \[0, 1\)"),
    (lambda m, c: m.update(size_px=[16.5, 16]), "size_px"),
    (lambda m, c: m["reference"].update(angle_rad=2.0), "reference.angle_rad"),
    (lambda m, c: m.update(plate_to_world=(2 * np.eye(4)).ravel().tolist()), "rotation"),
    (lambda m, c: m.update(bounds_m=[[0, 0, 0], [-1, 0, 0]]), "bounds_m"),
    (lambda m, c: m.update(channels=["Q"]), "channels"),
    (lambda m, c: c["c0.H"].__setitem__((3, 3), np.nan), "NaN"),
])
def test_hologram_metadata_and_pixels_are_checked(tmp_path, hologram, edit, problem):
    path = write_hologram(tmp_path / "h.exr", hologram)
    _with_meta(path, edit)
    with pytest.raises(HologramFileError, match=f"{path}.*{problem}"):
        read_hologram(path)


# --- scans -----------------------------------------------------------------------------------

def _scan(tmp_path, image, name="s.png", **save):
    path = tmp_path / name
    image.save(path, **save)
    return import_acquired(path, pitch=5e-6, wavelength=532e-9).intensity


def test_scans_are_read_by_image_mode(tmp_path, rng):
    grey = rng.integers(0, 256, (6, 7), dtype=np.uint8)
    want = grey / 255.0
    rgb = Image.fromarray(np.repeat(grey[..., None], 3, 2))
    assert np.allclose(_scan(tmp_path, rgb.convert("P", palette=Image.ADAPTIVE)), want, atol=1e-6)      # the colours
    la = Image.fromarray(np.stack([grey, 255 - grey], -1), "LA")
    assert np.allclose(_scan(tmp_path, la), want, atol=1e-6)                     # alpha dropped
    cmyk = _scan(tmp_path, rgb.convert("CMYK"), "s.tif")
    assert np.allclose(cmyk, want, atol=1 / 255)
    sixteen = rng.integers(0, 65536, (6, 7)).astype(np.int32)                  # int32 TIFF
    assert np.allclose(_scan(tmp_path, Image.fromarray(sixteen), "i.tif"), sixteen / 65535)
    exr = write_exr(tmp_path / "s.exr", {c: want * (i + 1) for i, c in enumerate("RGB")})
    assert import_acquired(exr, pitch=5e-6, wavelength=532e-9).intensity.shape == (1, 6, 7)
    assert np.allclose(import_acquired(exr, pitch=5e-6, wavelength=532e-9).intensity, 2 * want)


def test_a_decompression_bomb_is_refused_from_its_header(tmp_path, monkeypatch):
    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "1G")
    out = io.BytesIO()
    Image.new("L", (12000, 12000)).save(out, "PNG")
    (tmp_path / "bomb.png").write_bytes(out.getvalue())
    with pytest.raises(InputError, match="12000x12000 pixels"):
        import_acquired(tmp_path / "bomb.png", pitch=5e-6, wavelength=532e-9)


# --- rendering -------------------------------------------------------------------------------

def test_render_settings_are_checked(hologram):
    cam = camera()
    for kwargs, problem in [({"exposure": float("nan")}, "exposure"),
                            ({"exposure": -1.0}, "exposure"),
                            ({"opacity_threshold": float("nan")}, "opacity_threshold")]:
        with pytest.raises(InputError, match=problem):
            render_view(hologram, cam, **kwargs)
    other = Hologram(intensity=hologram.intensity, wavelengths=(532e-9,), pitch=1e-6)
    with pytest.raises(InputError, match=r"holograms\[1\] has wavelengths"):
        render_view([hologram, other], cam)
    with pytest.raises(InputError, match="singular"):
        Camera(matrix_world=np.diag([1.0, 0.0, 1.0, 1.0]))
    with pytest.warns(NoDepthWarning, match="no depth channel"):
        render_view(hologram, cam)


def test_a_non_finite_view_is_not_written(tmp_path):
    view = RenderResult(rgb=np.full((2, 2, 3), np.nan, np.float32), alpha=np.ones((2, 2)),
                        depth=np.ones((2, 2)))
    with pytest.raises(InputError, match="rgb is empty or not finite"):
        write_view(view, tmp_path / "v.exr")
    assert not list(tmp_path.iterdir())


# --- command line --------------------------------------------------------------------------

def test_cli_bad_arguments_name_the_argument_and_its_range(tmp_path):
    (tmp_path / "q.obj").write_text(CUBE_OBJ)
    for args, problem in [(["--pitch", "0"], "--pitch: '0' is out of range (metres, from 1e-12"),
                          (["--resolution", "0", "0"], "--resolution: '0' is out of range"),
                          (["--wavelengths", "nan"], "--wavelengths: 'nan' is out of range")]:
        run = cli("record", tmp_path / "q.obj", "-o", tmp_path / "h.exr", *args)
        assert run.returncode == 2 and problem in run.stderr, run.stderr
        assert len(run.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("output, status", [("/proc/holo.exr", 2), ("below/a/file", 2)])
def test_cli_unwritable_output_is_one_line(tmp_path, hologram, output, status):
    path = write_hologram(tmp_path / "h.exr", hologram)
    (tmp_path / "below").write_text("a file")
    run = cli("render", path, "-o", output if output.startswith("/") else tmp_path / output,
              *CAMERA_ARGS)
    assert run.returncode == status, run.stderr
    lines = [l for l in run.stderr.strip().splitlines() if not l.startswith("warning: ")]
    assert "Traceback" not in run.stderr and len(lines) == 1, run.stderr


def test_cli_render_into_a_folder_writes_inside_it(tmp_path, hologram):
    path = write_hologram(tmp_path / "h.exr", hologram)
    (tmp_path / "views").mkdir()
    run = cli("render", path, "-o", tmp_path / "views", *CAMERA_ARGS)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "views" / "h_view.exr").is_file() and not (tmp_path / "views.exr").exists()


def test_cli_sigint_ends_in_one_line(tmp_path):
    import signal
    proc = subprocess.Popen([sys.executable, "-c",
                             "import time, sys\nfrom holo_core.__main__ import main\n"
                             "import holo_core.__main__ as m\n"
                             "m.info = lambda a: time.sleep(30)\n"
                             "sys.exit(main(['info', 'x']))"],
                            stderr=subprocess.PIPE, text=True)
    import time
    time.sleep(1.5)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130 and err.strip() == "interrupted", err


def test_cli_unexpected_failure_is_one_line_and_debug_shows_the_traceback(tmp_path):
    code = ("import sys\nimport holo_core.__main__ as m\n"
            "def boom(a): raise RuntimeError('driver fault')\nm.info = boom\n"
            "sys.exit(m.main(sys.argv[1:]))")
    quiet = subprocess.run([sys.executable, "-c", code, "info", "x"], capture_output=True,
                           text=True)
    assert quiet.returncode == 1 and quiet.stderr.strip().splitlines() == [
        "error: RuntimeError: driver fault (--debug shows the traceback)"]
    loud = subprocess.run([sys.executable, "-c", code, "--debug", "info", "x"],
                          capture_output=True, text=True)
    assert "Traceback" in loud.stderr and loud.returncode == 1


def test_math_of_the_safe_distance():
    """2 samples across the cone: |z| = 2p/tan θ, θ the cone's edge (CONE_FILL of Nyquist)."""
    from holo_core.plate.point_sources import CONE_FILL, Grid, safe_distance
    p, lam = 8e-6, 633e-9
    s = CONE_FILL * lam / (2 * p)
    assert math.isclose(safe_distance(Grid((8, 8), p, lam)), 2 * p * math.sqrt(1 - s * s) / s)


def test_a_cropped_camera_keeps_every_pixels_ray():
    cam = Camera(matrix_world=look_at((0.3, -3, 0.2), (0, 0, 0)), resolution=(64, 48),
                 shift_x=0.1, shift_y=-0.05, pixel_aspect=(1, 1.2), sensor_fit="VERTICAL")
    crop = cam.cropped(10, 5, 30, 20)
    (tx, ty), (cx, cy) = cam.pixel_tangents(), crop.pixel_tangents()
    assert np.allclose(tx[5:25, 10:40], cx, atol=1e-12) and np.allclose(ty[5:25, 10:40], cy,
                                                                        atol=1e-12)
    with pytest.raises(InputError, match="inside the 64x48 image"):
        cam.cropped(50, 0, 30, 10)


# --- the reliability audit (issue 26): one reproducer per finding ----------------------------
# Finding 1 (writes follow links) is in io/test_atomic_writes.py; the API tables of findings
# 6-10 are in test_validation.py; the fuzz suite (tools/fuzz.py) enumerates files and calls.

def test_a_long_wavelength_hologram_is_written_and_read_back(tmp_path):
    """Finding 2: λ long against the pitch chose a cone of sin θ >= 1, which the reader refuses
    (here λ = 1 mm on a 39 µm pitch: 0.95·λ2/8p = 1.69 before the cone was capped)."""
    from holo_core.plate.record import record_hologram
    from holo_core.scene.plate import Plate
    plate = Plate(matrix_world=np.eye(4), width=0.0025, height=0.0025)
    h = record_hologram(([[0.0, 0.0, -0.05]], [[1.0, 1.0, 1.0]]), plate=plate, resolution=64,
                        wavelength=1e-3)
    assert 0 < h.band < 1, f"band sin θ = {h.band}"
    back = read_hologram(write_hologram(tmp_path / "h.exr", h))
    assert back.band == h.band and back.wavelengths == h.wavelengths


def test_the_writer_refuses_what_the_reader_would(tmp_path, hologram):
    """Finding 2: the writer applies the reader's schema; a description bent after
    construction is refused with the file and the field named, and nothing is written."""
    import dataclasses
    for field, value, problem in [("band", 1.5, r"band_sin must be in \[0, 1\)"),
                                  ("pitch", 1e-300, r"pitch_m must be in \[1e-12, 1000\]"),
                                  ("reference_amplitudes", (0.0,), "amplitudes.*> 0")]:
        info = dataclasses.replace(hologram.info)
        object.__setattr__(info, field, value)
        bent = Hologram(info=info, intensity=hologram.intensity, object_wave=hologram.object_wave)
        with pytest.raises(HologramFileError, match=f"h.exr: metadata .*{problem}"):
            write_hologram(tmp_path / "h.exr", bent)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("edit, problem", [
    (lambda m: m.update(pitch_m=1e-300), r"pitch_m must be in \[1e-12, 1000\] \[m\]"),
    (lambda m: m.update(wavelengths_m=[1e300]), "wavelengths_m must be in"),
    (lambda m: m["reference"].update(amplitudes=[0.0]), "reference.amplitudes must be 1 numb"),
])
def test_a_file_of_absurd_optics_is_refused_by_the_reader_and_the_cli(tmp_path, hologram, capsys,
                                                                      edit, problem):
    """Findings 3 and 4: pitch 1e-300 passed the schema and rendered NaN (the CLI died with
    ZeroDivisionError); a zero reference amplitude was accepted and failed later, unnamed."""
    path = write_hologram(tmp_path / "h.exr", hologram)
    _with_meta(path, lambda m, c: edit(m))
    with pytest.raises(HologramFileError, match=f"{path}: metadata {problem}"):
        read_hologram(path)
    status, _, err = _cli_main(capsys, "render", path, "-o", tmp_path / "v.exr", *CAMERA_ARGS)
    assert status == 2 and err.count("\n") == 1 and str(path) in err, err
    assert not (tmp_path / "v.exr").exists()


def test_holograms_in_memory_are_held_to_the_file_schema():
    """Findings 3 and 4 at the API: the same fields are refused when a Hologram is made."""
    good = {"intensity": np.ones((1, 4, 4), np.float32), "wavelengths": (633e-9,),
            "pitch": 8e-6}
    for change, field in [({"pitch": 1e-300}, "pitch"), ({"wavelengths": (1e9,)}, "wavelengths"),
                          ({"reference_amplitudes": (0.0,)}, "reference_amplitudes"),
                          ({"band": 1.0}, "band"), ({"point_density": -1.0}, "point_density"),
                          ({"bounds": [[0, 0, 0], [-1, 0, 0]]}, "bounds"),
                          ({"channels": ("Q",)}, "channels"), ({"reference_angle": 2.0},
                                                                "reference_angle")]:
        with pytest.raises(InputError, match=field):
            Hologram(**{**good, **change})


def test_a_ply_with_a_scalar_face_property_names_it(tmp_path):
    """Finding 5: a scalar vertex_indices raised TypeError."""
    ply = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
           "property float z\nelement face 1\nproperty int vertex_indices\nend_header\n"
           "0 0 0\n1 0 0\n0 1 0\n0\n")
    (tmp_path / "m.ply").write_text(ply)
    with pytest.raises(MeshFileError, match="face property vertex_indices must be a list"):
        read_mesh(tmp_path / "m.ply")


@pytest.mark.parametrize("text, index", [
    ("f 1 2 99999999999999999999999\n", "99999999999999999999999"),  # beyond int64: was -1
    ("f 1 2 9\n", "9"),                                                # OBJ's own numbering
])
def test_an_obj_index_out_of_range_is_reported_as_the_file_has_it(tmp_path, text, index):
    """Finding 10: a huge OBJ index was reported as "-1", others one less than in the file."""
    (tmp_path / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n" + text)
    with pytest.raises(MeshFileError, match=f"index {index} is out of range .*3 vertices, "
                                            f"numbered from 1"):
        read_mesh(tmp_path / "m.obj")


def test_a_camera_outside_the_viewing_zone_warns_that_the_view_is_black(hologram):
    """Finding 9: a camera far off the plate's axis rendered black without a word. The light
    of this hologram (pitch 1 µm, λ 633 nm) leaves within asin(λ/2p) = 18.5° of the normal."""
    from holo_core.plate.view import EmptyViewWarning
    for degrees in (30, 60, 89):
        a = math.radians(degrees)
        eye = 8e-3 * np.array([math.sin(a), 0, math.cos(a)])
        cam = Camera(matrix_world=look_at(eye, (0, 0, -3e-3)), lens=50, resolution=(16, 16),
                     sensor_width=50 * 16 * 4e-3)
        with pytest.warns(EmptyViewWarning, match=r"the view is black: the camera is "
                                                  r"\d+\.\d° off the plate's normal.*"
                                                  r"within 18.5°"):
            view = render_view(hologram, cam)
        assert not view.rgb.any() and not view.alpha.any()


def test_cli_wavelengths_below_1_are_refused_as_nanometres(tmp_path, capsys):
    """The CLI's --wavelengths is the one length in nm: 633e-9 (metres) is refused."""
    (tmp_path / "q.obj").write_text(CUBE_OBJ)
    status, _, err = _cli_main(capsys, "record", tmp_path / "q.obj", "-o", tmp_path / "h.exr",
                               "--wavelengths", "633e-9")
    assert status == 2 and "--wavelengths: '633e-9' is out of range (nm, from 1" in err, err
    assert "633 is red light" in err and not list(tmp_path.glob("*.exr"))


@pytest.mark.parametrize("output, problem", [
    ("/sys/holo.exr", "its folder /sys is not writable"),  # read-only, even for root
    ("{tmp}/a_file/h.exr", "is not a folder"),
    ("{tmp}/r.png", r"r.png: the file is written as OpenEXR; name it \*\.exr"),
])
@pytest.mark.parametrize("command", ["record", "render"])
def test_cli_output_is_checked_before_the_work(tmp_path, hologram, capsys, monkeypatch, output,
                                              problem, command):
    """Findings 11 and 12: a read-only folder was found only after the whole recording, and
    -o r.png wrote EXR bytes under a .png name."""
    import holo_core.plate.record
    import holo_core.plate.view

    def never(*_, **__):
        raise AssertionError("the work started before the output was checked")
    monkeypatch.setattr(holo_core.plate.record, "record_points", never)
    monkeypatch.setattr(holo_core.plate.view, "render_view", never)
    (tmp_path / "q.obj").write_text(CUBE_OBJ)
    (tmp_path / "a_file").write_text("a file")
    source = tmp_path / "q.obj" if command == "record" else \
        write_hologram(tmp_path / "h.exr", hologram)
    before = sorted(tmp_path.iterdir())
    status, out, err = _cli_main(capsys, command, source, "-o", output.format(tmp=tmp_path),
                                 "--resolution", 16, 16)
    assert status == 2 and re.search(problem, err) and err.count("\n") == 1, err
    assert out == "" and sorted(tmp_path.iterdir()) == before


def test_write_hologram_and_write_view_refuse_other_suffixes(tmp_path, hologram):
    """Finding 12 at the API: the EXR writers name the suffix instead of writing EXR bytes
    under another name (or silently under another one)."""
    with pytest.raises(InputError, match=r"r.png: the file is written as OpenEXR"):
        write_hologram(tmp_path / "r.png", hologram)
    view = RenderResult(rgb=np.ones((2, 2, 3)), alpha=np.ones((2, 2)), depth=np.ones((2, 2)))
    with pytest.raises(InputError, match=r"v.png: the file is written as OpenEXR"):
        write_view(view, tmp_path / "v.png")
    assert not list(tmp_path.iterdir())


def test_a_view_that_overflows_is_refused_not_nan(hologram):
    """Found by the fuzz suite: one pixel at 3e38 (finite, so the file reads) overflowed the
    view's float32 arithmetic and rendered NaN."""
    import dataclasses
    hot = hologram.intensity.copy()
    hot[0, 5, 7] = 3e38
    with pytest.raises(InputError, match=r"intensity must stay within float32 .* reaches 3e\+38"):
        render_view(dataclasses.replace(hologram, intensity=hot), camera())
