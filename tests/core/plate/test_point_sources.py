"""Point sources onto a plate (holo_core.plate.point_sources), whichever sum it takes: colours
in one pass equal separate passes; points behind the plate are refused and the safe distance
is the cone's."""

import math

import numpy as np
import pytest
from point_sums import LAM, PITCH

from holo_core.plate.point_sources import point_wave


def max_rel(a, ref):
    return float(np.abs(a - ref).max() / np.abs(ref).max())


@pytest.mark.parametrize("method", ["direct", "wrp"])
def test_colours_in_one_pass_equal_separate_passes(rng, method):
    """(N, C) amplitudes share the geometry; each colour must still be its own wave (float32
    rounding apart: the amplitude is applied per pixel instead of folded into the recurrence)."""
    shape, n = (96, 128), 400
    pos = np.c_[rng.uniform(-3e-4, 3e-4, (n, 2)), rng.uniform(-0.03, -0.01, n)]
    amp = rng.uniform(0, 1, (n, 3)) * np.exp(2j * np.pi * rng.random((n, 1)))
    amp[:, 1] = 0  # a colour absent from the scene
    together = point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=shape, method=method)
    assert together.shape == (3,) + shape
    for c in (0, 2):
        alone = point_wave(pos, amp[:, c], wavelength=LAM, pitch=PITCH, shape=shape, method=method)
        err = max_rel(together[c], alone)
        assert err < 1e-5, f"colour {c} in one pass vs alone ({method}): {err:.2e}"
    assert not together[1].any()


def test_points_behind_the_hologram_are_refused():
    with pytest.raises(ValueError, match="z must be < 0"):
        point_wave([[0, 0, 0.01]], [1], wavelength=LAM, pitch=PITCH, shape=(8, 8))


def test_math_of_the_safe_distance():
    """2 samples across the cone: |z| = 2p/tan θ, θ the cone's edge (CONE_FILL of Nyquist)."""
    from holo_core.plate.point_sources import safe_distance
    from holo_core.plate.point_sum import CONE_FILL, Grid

    p, lam = 8e-6, 633e-9
    s = CONE_FILL * lam / (2 * p)
    assert math.isclose(safe_distance(Grid((8, 8), p, lam)), 2 * p * math.sqrt(1 - s * s) / s)
