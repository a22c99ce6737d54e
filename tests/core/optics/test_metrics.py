"""PSNR and SSIM against their definitions: an analytic PSNR and a brute-force float64 SSIM,
window by window."""

import math

import numpy as np
import pytest

from holo_core.optics.metrics import K1, K2, gaussian_window, psnr, ssim
from holo_core.validate import InputError


def test_psnr_of_a_constant_error_is_analytic(rng):
    ref = rng.random((32, 40))
    assert psnr(ref + 0.01, ref, data_range=1.0) == pytest.approx(40.0, abs=1e-9)
    assert psnr(ref * 255 + 2.55, ref * 255, data_range=255) == pytest.approx(40.0, abs=1e-9)
    assert psnr(ref, ref, data_range=1.0) == math.inf


def brute_ssim(a, b, r):
    """Wang et al.'s SSIM: each 11 x 11 window's weighted statistics, summed explicitly."""
    w = np.outer(gaussian_window(), gaussian_window())
    c1, c2 = (K1 * r) ** 2, (K2 * r) ** 2
    out = []
    for i in range(a.shape[0] - 10):
        for j in range(a.shape[1] - 10):
            x, y = a[i : i + 11, j : j + 11], b[i : i + 11, j : j + 11]
            mx, my = (w * x).sum(), (w * y).sum()
            vx, vy = (w * (x - mx) ** 2).sum(), (w * (y - my) ** 2).sum()
            cxy = (w * (x - mx) * (y - my)).sum()
            out.append(
                (2 * mx * my + c1) * (2 * cxy + c2) / ((mx**2 + my**2 + c1) * (vx + vy + c2))
            )
    return float(np.mean(out))


def test_ssim_equals_its_definition(rng):
    ref = rng.random((24, 30))
    noisy = np.clip(ref + 0.1 * rng.normal(size=ref.shape), 0, 1)
    got, want = ssim(noisy, ref, data_range=1.0), brute_ssim(noisy, ref, 1.0)
    assert abs(got - want) <= 1e-12, (got, want)
    assert ssim(ref, ref, data_range=1.0) == pytest.approx(1.0, abs=1e-12)
    worse = np.clip(ref + 0.3 * rng.normal(size=ref.shape), 0, 1)
    assert ssim(worse, ref, data_range=1.0) < got < 1


def test_colour_images_average_their_channels(rng):
    ref = rng.random((16, 16, 3))
    img = ref * 0.9
    want = np.mean([ssim(img[..., c], ref[..., c], data_range=1.0) for c in range(3)])
    assert ssim(img, ref, data_range=1.0) == pytest.approx(want, abs=1e-15)


def test_bad_images_are_refused():
    with pytest.raises(InputError, match="one shape"):
        psnr(np.ones((4, 4)), np.ones((4, 5)), data_range=1)
    with pytest.raises(InputError, match="data_range must be > 0"):
        psnr(np.ones((4, 4)), np.ones((4, 4)), data_range=0)
    with pytest.raises(InputError, match="at least 11x11"):
        ssim(np.ones((8, 8)), np.ones((8, 8)), data_range=1)
    with pytest.raises(InputError, match="real"):
        ssim(np.ones((16, 16)) + 0j, np.ones((16, 16)), data_range=1)


@pytest.mark.parametrize("a, b", [(0.2, 0.8), (0.5, 0.5), (1.0, 0.0)])
def test_ssim_of_two_flat_images_is_its_luminance_term(a, b):
    """Flat images have no variance: SSIM = (2ab + C1)/(a² + b² + C1), C1 = (K1·L)², the
    contrast-structure term C2/C2 = 1 (analytic)."""
    c1 = (K1 * 1.0) ** 2
    got = ssim(np.full((16, 20), a), np.full((16, 20), b), data_range=1.0)
    assert got == pytest.approx((2 * a * b + c1) / (a * a + b * b + c1), abs=1e-12)
