"""Reproducers of the findings of "stores and lab files that cannot be turned against their
user" outside the tiled store: every file the command line writes renders, memory is refused
up front with its size, and the planner names what the user gave."""

import numpy as np
import pytest
from cli import run_cli as cli

from holo_core.io.image import read_exr
from holo_core.plate.points import record_points
from holo_core.plate.view import render_view
from holo_core.scene.camera import Camera, look_at
from holo_core.validate import InputError
from holo_core.view import as_rgb, channel_colours

TRIANGLE_OBJ = "v -0.002 -0.002 0\nv 0.002 -0.002 0\nv 0 0.002 0\nf 1 2 3\n"


# --- every file written can be rendered ------------------------------------------------------

@pytest.mark.parametrize("count", [1, 2, 3, 4, 5, 16])
def test_every_channel_count_has_stated_colours(count):
    """One channel is grey, three are R, G, B as recorded, any other count spreads the
    channels over the hues; equal radiance in every channel is white of that radiance."""
    m = channel_colours(count)
    assert m.shape == (count, 3) and (m >= 0).all()
    assert np.allclose(np.ones(count) @ m, 1), np.ones(count) @ m
    if count in (1, 3):
        assert np.array_equal(m, np.ones((1, 3)) if count == 1 else np.eye(3))
    if count == 2:  # red and its complement, cyan
        assert np.array_equal(m, [[1, 0, 0], [0, 1, 1]])
    radiance = np.random.default_rng(count).random((4, 5, count))
    assert as_rgb(radiance).shape == (4, 5, 3)


@pytest.mark.parametrize("wavelengths", [["633", "532"], ["633", "532", "473", "450"]])
def test_record_any_number_of_wavelengths_then_render(tmp_path, capsys, wavelengths):
    """``record --wavelengths 633 532`` wrote a file whose render failed with IndexError, and
    four wavelengths gave a 4-channel rgb the view writer refused; both render now."""
    (tmp_path / "tri.obj").write_text(TRIANGLE_OBJ)
    status, _, err = cli(capsys, "record", tmp_path / "tri.obj", "-o", tmp_path / "h.exr",
                         "--method", "auto", "--resolution", 256, 256, "--wavelengths",
                         *wavelengths,
                         "--distance", 0.02, "--max-points", 500)
    assert status == 0, err
    status, out, err = cli(capsys, "render", tmp_path / "h.exr", "-o", tmp_path / "v.exr",
                           "--resolution", 32, 32)
    assert status == 0, err
    _, channels = read_exr(tmp_path / "v.exr")
    rgb = np.stack([channels[f"ViewLayer.Combined.{c}"] for c in "RGB"], -1)
    assert rgb.shape == (32, 32, 3) and rgb.max() > 0, rgb.shape


def test_a_two_channel_view_shows_the_first_red_and_the_second_cyan():
    """A point lit in the first channel only shows red: its G and B are exactly zero."""
    h = record_points([[0, 0, -3e-3]], [[1.0, 0.0]], shape=(128, 128), pitch=1e-6,
                      wavelengths=(633e-9, 532e-9))
    cam = Camera(matrix_world=look_at((0, 0, 4e-3), (0, 0, -3e-3)), lens=50,
                 sensor_width=50 * 16 * 4e-3, resolution=(16, 16))
    with pytest.warns(UserWarning, match="no depth channel"):
        view = render_view(h, cam, supersample=1)
    assert view.rgb.shape == (16, 16, 3)
    assert view.rgb[..., 0].max() > 0 and not view.rgb[..., 1:].any()


# --- the planner names what the user gave ---------------------------------------------------

@pytest.mark.parametrize("args, message", [
    # zero-size objects said "wavelength must be > 0; got -1.25e-09"
    (["--bounds", 0, 0, -0.3, 0, 0, -0.3],
     r"error: bounds: the objects' box \(0 x 0 x 0 m\) has no size"),
    (["--box", 1e-7, 1e-7, 1e-7],
     r"the objects' box \(1e-07 x 1e-07 x 1e-07 m\) is smaller than the wavelength its views "
     r"need \(λ = 1e-05 m\)"),
    # a camera behind the plate said "zone half_extents must be >= 0"
    (["--box", 0.01, 0.01, 0.01, "--camera", 0, 0, -0.1],
     r"--camera must be in front of the plate \(z > 0 .*got \(0, 0, -0.1\) m, behind the plate"),
    # a plate too small to sample printed 4.83e12 GiB with exit 0
    (["--box", 0.01, 0.01, 0.01, "--plate-size", 1e-9, 1e-9],
     r"plate_size 1e-09 x 1e-09 m: where the objects' light crosses it, it is narrower than one "
     r"sample"),
])
def test_the_planner_names_what_the_user_gave(capsys, args, message):
    status, out, err = cli(capsys, "plan", *args)
    assert status == 2 and out == "" and err.count("\n") == 1, (status, out, err)
    assert __import__("re").search(message, err), err


@pytest.mark.parametrize("y", ["-1e-3", "-1E-3", "-1.0e-3", "-.001", "-0.001", "-1e-03"])
def test_the_command_line_takes_negative_numbers_in_any_notation(capsys, y):
    """``--camera 0.01 -1e-3 0.3`` was refused as "expected 3 arguments": argparse took the
    exponent notation for an option."""
    status, out, err = cli(capsys, "plan", "--box", 0.01, 0.01, 0.01, "--camera", 0.01, y, 0.3)
    assert status == 0, err
    assert "for the camera at (0.01, -0.001, 0.3) m" in out, out


# --- memory refused up front, with the size ---------------------------------------------------

def _huge_mesh(vertices):
    """A mesh of ``vertices`` vertices and twice as many triangles that holds no memory of its
    own (broadcast views): what a refusal must see before any array of that size is made."""
    from holo_core.scene.mesh import Mesh
    return Mesh(vertices=np.broadcast_to(np.array([0.0, 0.0, -1.0]), (vertices, 3)),
                triangles=np.broadcast_to(np.array([0, 1, 2]), (2 * vertices, 3)))


def _never(*_, **__):
    raise AssertionError("the work started before its memory was counted")


def test_a_ten_million_vertex_mesh_is_refused_by_render_camera(monkeypatch):
    """It passed 8 GB in 16 s; rasterizing takes about 1000 bytes per triangle (measured 920
    at 10^6): 18.6 GiB for 2·10^7 triangles against an 8 GiB budget."""
    import holo_core.camera.raster as raster
    from holo_core.camera.render import render_camera
    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "8G")
    monkeypatch.setattr(raster, "across_shutter", _never)
    cam = Camera(matrix_world=look_at((0, 0, 0.5), (0, 0, -1)), resolution=(64, 64))
    with pytest.raises(InputError, match=r"rasterizing 20000000 triangles needs 1\d\.\d GiB of "
                                         r"memory; 6.4 GiB is available"):
        render_camera(_huge_mesh(10**7), cam, via="incoherent", supersample=1)


def test_ten_million_triangles_are_refused_by_the_plate_recording(monkeypatch):
    import holo_core.plate.recording as recording
    from holo_core.plate.looks import record_plate
    from holo_core.scene.plate import Plate
    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "2G")
    monkeypatch.setattr(recording, "zone_emitters", _never)
    with pytest.raises(InputError, match=r"moving 10000000 triangles onto the plate needs "
                                         r"\d\.\d+ GiB"):
        record_plate(_huge_mesh(5 * 10**6), plate=Plate(matrix_world=np.eye(4), width=0.05,
                                                          height=0.05))


def test_a_hundred_million_point_sum_is_refused_before_its_amplitudes(monkeypatch):
    """10^8 points of three colours: (200 + 3·96) bytes each, 45.4 GiB, counted before their
    amplitudes and random phases are drawn."""
    import holo_core.plate.points as points
    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "8G")
    monkeypatch.setattr(points, "point_wave", _never)
    n = 10**8
    with pytest.raises(InputError, match=r"100000000 point emitters of 3 wavelengths needs "
                                         r"45.4 GiB of memory"):
        record_points(np.broadcast_to(np.array([0.0, 0.0, -0.01]), (n, 3)),
                      np.broadcast_to(np.ones(3), (n, 3)), shape=(64, 64), pitch=8e-6,
                      wavelengths=(633e-9, 532e-9, 473e-9))


@pytest.fixture(scope="module")
def small_plate():
    """A point 3 cm behind a 0.5 mm plate of 64² at 8 µm, seen from 2 cm: the plate's light
    reaches 2.2 mm across on the pupil's plane."""
    return record_points([[0, 0, -0.03]], [[1.0]], shape=(64, 64), pitch=8e-6,
                         wavelengths=(633e-9,))


def _pupil_view(h, diameter, monkeypatch, *, crop=True):
    """(rgb at exposure 1, the pupil grid's samples per side) of a pinhole-less view through
    a pupil of ``diameter`` [m]."""
    from holo_core.optics.pupil import Pupil
    from holo_core.plate import pupil_images
    grids = []
    real = pupil_images.pupil_grid
    monkeypatch.setattr(pupil_images, "pupil_grid",
                        lambda *a: grids.append(real(*a)) or grids[-1])
    if not crop:
        monkeypatch.setattr(pupil_images, "lit_diameter", lambda h, p, r, d: d)
    cam = Camera(matrix_world=look_at((0, 0, 0.02), (0, 0, -0.03)), lens=50, sensor_width=2,
                 resolution=(16, 16))
    with pytest.warns(UserWarning, match="no depth channel"):
        rgb = render_view(h, cam, aperture=Pupil(diameter=diameter), supersample=1,
                          exposure=1.0).rgb
    monkeypatch.undo()
    return rgb, grids[-1][0]


def test_a_pupil_larger_than_the_plates_light_is_read_where_light_arrives(small_plate,
                                                                         monkeypatch):
    """A 4 mm pupil before the plate's 2.2 mm of light: its grid cut to the light (675
    samples a side instead of 1215) gives the same view (measured 1.8e-3 of the peak: the
    spectrum read on another bin spacing)."""
    cut, n_cut = _pupil_view(small_plate, 4e-3, monkeypatch)
    whole, n_whole = _pupil_view(small_plate, 4e-3, monkeypatch, crop=False)
    assert n_cut < 0.6 * n_whole, (n_cut, n_whole)
    err = np.abs(cut - whole).max() / whole.max()
    assert err <= 5e-3, err


def test_a_10_m_aperture_reads_only_the_light_and_dims_by_its_area(small_plate, monkeypatch):
    """render_view with a 10 m aperture took over 150 s and 5 GB: its pupil grid and window
    spanned 10 m. They now span the plate's light (the same 675 samples as a 4 mm pupil), and
    the view is the 4 mm one dimmed by the ratio of the irises' areas, (4 mm / 10 m)², the
    light the larger lens spreads over its whole iris."""
    small, n_small = _pupil_view(small_plate, 4e-3, monkeypatch)
    large, n_large = _pupil_view(small_plate, 10.0, monkeypatch)
    assert n_large == n_small, (n_large, n_small)
    err = np.abs(large * (10.0 / 4e-3) ** 2 - small).max() / small.max()
    assert err <= 1e-4, err


def test_a_batch_over_an_empty_field_is_the_projects_error():
    """Found by the fuzz suite's calls: two wavelengths over a 0x0 field failed reshaping."""
    from holo_core.propagation import angular_spectrum
    with pytest.raises(InputError, match=r"field must be \(\.\.\., H, W\) with H, W >= 1; got "
                                         r"shape \(0, 0\)"):
        angular_spectrum(np.zeros((0, 0), np.complex64), wavelength=[633e-9, 532e-9],
                         pitch=1e-6, distance=1e-4)
