"""The display's focal stack: the block's transfer function is the angular spectrum's, a
Gaussian beam through it spreads as the analytic beam does, the adjoint is the adjoint, and
the comparison's PSNR and SSIM are those of the slices."""

import math

import numpy as np
import pytest

from holo_core.phase.stack import Optics, compare
from holo_core.propagation import grid
from holo_core.propagation.transfer import transfer_function

LAM, PITCH = 520e-9, 8e-6


def test_the_blocks_transfer_is_the_angular_spectrums():
    """Against transfer_function (float64, the band limit included) on the padded grid, the
    filter's rectangle cut from it: the same values to float32's precision."""
    op = Optics((48, 64), pitch=PITCH, wavelength=LAM, distances=[-4e-3, 7e-3])
    for k, z in enumerate(op.distances):
        full = transfer_function(op.padded, wavelength=LAM, pitch=PITCH, distance=z)
        err = np.abs(full[op.block] - op.transfer(k)).max()
        assert err <= 2e-6, err
    fy = grid.freqs(op.padded[0], PITCH)[op.rows]
    assert np.abs(fy).max() <= 0.5 / (2 * PITCH) and op.rows.size >= op.padded[0] // 2 - 1


def test_a_gaussian_beam_spreads_as_the_analytic_one():
    """A waist of 60 µm (its spectrum 1/(π·w0) = 5.3e3 cycles/m, far inside the filter's
    3.1e4) carried 20 mm: |U| = (w0/w)·exp(−r²/w²), w = w0·√(1 + (z/zR)²), zR = π·w0²/λ
    (paraxial: the next term is (w0/z)²·... ~1e-5 here)."""
    shape, w0, z = (128, 160), 60e-6, 20e-3
    y, x = (grid.coords(n, PITCH) for n in shape)
    r2 = y[:, None] ** 2 + x[None, :] ** 2
    u = np.exp(-r2 / w0**2)
    op = Optics(shape, pitch=PITCH, wavelength=LAM, distances=[z])
    got = op.stack(u)[0]
    zr = math.pi * w0**2 / LAM
    w = w0 * math.sqrt(1 + (z / zr) ** 2)
    want = w0 / w * np.exp(-r2 / w**2)
    err = np.abs(got - want).max()
    assert err <= 2e-4, err


def test_the_adjoint_is_the_adjoint(rng):
    """<A x, y> = <x, Aᴴ y> for A the display to one plane (pupil included)."""
    op = Optics((40, 56), pitch=PITCH, wavelength=LAM, distances=[3e-3],
                pupil=(0.5e-3, -0.2e-3, 2e-3, 0.1))
    x = (rng.normal(size=op.shape) + 1j * rng.normal(size=op.shape)).astype(np.complex64)
    y = (rng.normal(size=op.shape) + 1j * rng.normal(size=op.shape)).astype(np.complex64)
    ax = op.to_plane(op.spectrum(x), 0)
    ahy = op.back(op.from_plane(y, 0))
    left, right = np.vdot(ax, y), np.vdot(x, ahy)
    assert abs(left - right) <= 1e-5 * abs(left), (left, right)


def test_a_pupil_outside_the_band_is_refused():
    from holo_core.validate import InputError
    with pytest.raises(InputError, match="outside the band"):
        Optics((16, 16), pitch=PITCH, wavelength=LAM, distances=[0.0],
               pupil=(20e-3, 0, 1e-3, 0.1))


def test_the_comparison_is_the_slices_psnr_and_ssim(rng):
    """A stack at twice the brightness compares as equal (the fit takes the scale); one with
    noise of σ = 0.01 of the peak in each slice has PSNR 40 dB (10·log10(1/σ²))."""
    ref = rng.random((3, 32, 32)) + 0.5
    same = compare(2 * ref, ref)
    assert same.scale == pytest.approx(0.5) and same.psnr_db == [math.inf] * 3
    assert same.ssim == pytest.approx([1.0] * 3)
    noise = rng.normal(size=ref.shape)
    noise -= noise.mean()
    noise *= 0.01 * ref.max() / noise.std()
    c = compare(ref + noise, ref)
    assert c.mean_psnr_db == pytest.approx(40.0, abs=0.1), c.psnr_db
