"""holo_core.plot: physical axes that put a feature where it is."""

import math

import numpy as np
import pytest

from holo_core.propagation import grid
from holo_core.scene import Camera, Hologram, look_at
from holo_core.validate import InputError
from holo_core.view import RenderResult

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
plot = pytest.importorskip("holo_core.plot")
import matplotlib.pyplot as plt  # noqa: E402

PITCH, N = 2e-6, 128


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def located(image) -> tuple[float, float]:
    """The axis coordinates (x, y) of the brightest pixel of an imshow with origin 'lower'."""
    a = np.asarray(image.get_array(), np.float64)
    i, j = np.unravel_index(np.nanargmax(a), a.shape)
    x0, x1, y0, y1 = image.get_extent()
    h, w = a.shape
    return x0 + (j + 0.5) * (x1 - x0) / w, y0 + (i + 0.5) * (y1 - y0) / h


def test_amplitude_puts_a_beam_where_it_is():
    """A Gaussian centred at (40, -24) µm is drawn there, on axes ±N·pitch/2 in µm."""
    y, x = grid.coords(N, PITCH)[:, None], grid.coords(N, PITCH)[None, :]
    beam = np.exp(-((x - 40e-6) ** 2 + (y + 24e-6) ** 2) / (10e-6) ** 2)
    image = plot.amplitude(beam, PITCH)
    assert image.get_extent() == pytest.approx((-128, 128, -128, 128))
    assert image.axes.get_xlabel() == "x [µm]"
    at = located(image)
    assert np.allclose(at, (40, -24), atol=PITCH * 1e6), at


def test_phase_follows_a_tilt_and_is_blank_where_dark():
    """A plane wave of 20 mrad along x: the plotted phase grows by 2π·sin θ/λ per metre."""
    lam, theta = 633e-9, 0.02
    x = grid.coords(N, PITCH)[None, :].repeat(N, 0)
    u = np.exp(2j * np.pi * math.sin(theta) / lam * x)
    u[:, :8] = 0
    image = plot.phase(u, PITCH)
    ph = np.asarray(image.get_array().filled(np.nan), np.float64)
    assert np.isnan(ph[:, :8]).all()
    slope = np.angle(np.exp(1j * np.diff(ph[0, 8:]))).mean() / PITCH
    assert slope == pytest.approx(2 * np.pi * math.sin(theta) / lam, rel=1e-6)


def test_spectrum_puts_a_carrier_at_its_frequency():
    """A tilted plane wave of fx = 50 /mm, fy = -25 /mm peaks there on the fx, fy axes."""
    y, x = grid.coords(N, PITCH)[:, None], grid.coords(N, PITCH)[None, :]
    step = 1 / (N * PITCH)
    fx, fy = 13 * step, -6 * step  # on bins: 50.8 and -23.4 1/mm
    image = plot.spectrum(np.exp(2j * np.pi * (fx * x + fy * y)), PITCH)
    at = located(image)
    assert np.allclose(at, (fx * 1e-3, fy * 1e-3), atol=1e-9), (at, fx * 1e-3, fy * 1e-3)


def test_hologram_and_view_axes():
    h = Hologram(intensity=np.ones((1, 32, 64), np.float32), wavelengths=(633e-9,), pitch=8e-6)
    image = plot.hologram(h)
    assert image.get_extent() == pytest.approx((-256, 256, -128, 128))
    cam = Camera(matrix_world=look_at((0, 0, 1), (0, 0, 0)), resolution=(64, 48))
    result = RenderResult(
        rgb=np.zeros((48, 64, 3)), alpha=np.ones((48, 64)), depth=np.ones((48, 64))
    )
    image = plot.view(result, camera=cam)
    half_x, half_y = (math.degrees(a) / 2 for a in cam.field_of_view())
    assert image.get_extent() == pytest.approx((-half_x, half_x, -half_y, half_y))
    with pytest.raises(InputError, match="camera resolution"):
        plot.view(result, camera=Camera(matrix_world=np.eye(4), resolution=(8, 8)))


def test_arrays_need_their_pitch():
    with pytest.raises(InputError, match="pitch must be given"):
        plot.amplitude(np.ones((4, 4)))
    with pytest.raises(InputError, match="pitch must be in"):
        plot.amplitude(np.ones((4, 4)), 8)
