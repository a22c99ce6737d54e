"""Propagation onto another pitch and size: the angular spectrum's ``out_pitch`` against direct
Rayleigh–Sommerfeld on the same output grid, and both it and Fresnel against the analytic
Gaussian beam."""

import numpy as np
import pytest
from accuracy import ASM_VS_RS, GAUSSIAN_BEAM, rel_err
from beams import gaussian_beam

from holo_core import to_device
from holo_core.propagation import angular_spectrum, fresnel, grid, rayleigh_sommerfeld
from holo_core.scene import Field

LAM, PITCH, N = 633e-9, 2e-6, 128


def square(half_width=30e-6):
    x = grid.coords(N, PITCH)
    return ((np.abs(x)[None, :] < half_width) & (np.abs(x)[:, None] < half_width)).astype(
        np.complex64
    )


@pytest.mark.parametrize(
    "distance, out_pitch, out_shape, offset",
    [
        (2e-3, 1e-6, (128, 128), (0.0, 0.0)),  # finer, half the window: measured 1.7e-5
        (2e-3, 1.5e-6, (64, 80), (2e-5, -1e-5)),  # finer, shifted: 1.4e-5
        (5e-3, 3e-6, (96, 96), (0.0, 0.0)),  # coarser, larger window: 7.2e-4
    ],
)
def test_out_pitch_equals_direct_rayleigh_sommerfeld(distance, out_pitch, out_shape, offset):
    kw = {
        "wavelength": LAM,
        "pitch": PITCH,
        "distance": distance,
        "offset": offset,
        "out_pitch": out_pitch,
        "out_shape": out_shape,
    }
    got = angular_spectrum(square(), **kw)
    ref = rayleigh_sommerfeld(square(), **kw)
    assert got.shape == out_shape
    err = rel_err(got, ref)
    assert err <= ASM_VS_RS["fresnel 1-5"], f"{err:.3g}"


@pytest.mark.parametrize("method", [angular_spectrum, fresnel])
def test_a_beam_lands_on_the_output_grid(method, rt):
    """A Gaussian beam of w0 = 20 µm carried 3 mm onto 0.7 µm samples shifted by 15 µm: the
    paraxial formula there, from the host and from the device."""
    x, y = grid.coords(N, PITCH)[None, :], grid.coords(N, PITCH)[:, None]
    src = gaussian_beam(x, y, 0.0, w0=20e-6, wavelength=LAM).astype(np.complex64)
    op, shape, (x0, y0) = 0.7e-6, (100, 120), (15e-6, 0.0)
    xo, yo = grid.coords(shape[1], op)[None, :] + x0, grid.coords(shape[0], op)[:, None] + y0
    ref = gaussian_beam(xo, yo, 3e-3, w0=20e-6, wavelength=LAM)
    kw = {
        "wavelength": LAM,
        "pitch": PITCH,
        "distance": 3e-3,
        "offset": (x0, y0),
        "out_pitch": op,
        "out_shape": shape,
    }
    assert rel_err(method(src, **kw), ref) <= GAUSSIAN_BEAM
    assert rel_err(method(to_device(src), **kw).get(), ref) <= GAUSSIAN_BEAM
    f = method(Field(samples=src, wavelength=LAM, pitch=PITCH), distance=3e-3, out_pitch=op)
    assert f.pitch == (op, op) and f.shape == (round(N * PITCH / op),) * 2
