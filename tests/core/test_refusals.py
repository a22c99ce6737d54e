"""Reproducers of the findings of "stores and lab files that cannot be turned against their
user" outside the tiled store: every file the command line writes renders, memory is refused
up front with its size, and the planner names what the user gave."""

import numpy as np
import pytest
from cli import run_cli as cli

from holo_core.io.image import read_exr
from holo_core.plate.record import record_points
from holo_core.plate.view import render_view
from holo_core.scene.camera import Camera, look_at
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
                         "--resolution", 256, 256, "--wavelengths", *wavelengths,
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
    (["--box", 1e-7, 1e-7, 1e-7, "--samples", 256],
     r"the objects' box \(1e-07 x 1e-07 x 1e-07 m\) is smaller than the wavelength a plate of "
     r"0.1 x 0.1 m at 256 samples needs \(λ = 7.9\de-05 m\)"),
    # a camera behind the plate said "zone half_extents must be >= 0"
    (["--box", 0.01, 0.01, 0.01, "--camera", 0, 0, -0.1],
     r"--camera must be in front of the plate \(z > 0 .*got \(0, 0, -0.1\) m, behind the plate"),
    # a plate too small to sample printed 4.83e12 GiB with exit 0
    (["--box", 0.01, 0.01, 0.01, "--plate-size", 1e-9, 1e-9],
     r"plate_size 1e-09 x 1e-09 m cannot be sampled by 256 samples along its longer side: the "
     r"pitch would be 3.91e-12 m"),
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
    assert "from (0.01, -0.001, 0.3) m" in out, out
