"""Point sources summed onto a plate (holo_core.plate.point_sources) against analytic waves and
float64 NumPy (Sect. V): one point is the spherical wave, many are the float64 sum within
its sampling cone, the wavefront recording planes match the direct sum, colours in one pass
equal separate passes; points behind the plate are refused and the safe distance is the
cone's."""

import math

import numpy as np
import pytest
from accuracy import POINT_SUM, WRP_VS_DIRECT, rel_err
from point_sums import LAM, PITCH

from holo_core.plate.point_sources import Grid, cone_weight, point_wave
from holo_core.propagation import grid


def numpy_point_wave(pos, amp, shape, obliquity=False, lam=LAM, pitch=PITCH):
    """Eq. 3 summed in float64, each point weighted by its sampling cone."""
    g = Grid(shape, pitch, lam)
    y, x = grid.coords(shape[0], pitch)[:, None], grid.coords(shape[1], pitch)[None, :]
    out = np.zeros(shape, np.complex128)
    for (px, py, pz), a in zip(pos, amp):
        rho2 = (x - px) ** 2 + (y - py) ** 2
        r = np.sqrt(rho2 + pz * pz)
        w = a * np.exp(2j * np.pi / lam * r) / r * cone_weight(rho2, (g.cone * pz) ** 2)
        out += w * (abs(pz) / r if obliquity else 1)
    return out


def max_rel(a, ref):
    return float(np.abs(a - ref).max() / np.abs(ref).max())


def test_one_point_is_the_spherical_wave():
    shape, z = (128, 160), -0.03
    o = point_wave([[1e-4, -5e-5, z]], [2.0], wavelength=LAM, pitch=PITCH, shape=shape)
    y, x = grid.coords(shape[0], PITCH)[:, None], grid.coords(shape[1], PITCH)[None, :]
    r = np.sqrt((x - 1e-4) ** 2 + (y + 5e-5) ** 2 + z * z)
    inner = (x - 1e-4) ** 2 + (y + 5e-5) ** 2 <= (0.5 * Grid(shape, PITCH, LAM).cone * z) ** 2
    analytic = 2.0 * np.exp(2j * np.pi / LAM * r) / r
    err = max_rel(o[inner], analytic[inner])
    assert err < POINT_SUM, f"point wave vs 2·exp(ikr)/r inside the cone: {err:.2e}"


@pytest.mark.parametrize("obliquity", [False, True])
def test_device_sum_equals_float64_numpy(rng, obliquity):
    shape = (96, 136)
    g = Grid(shape, PITCH, LAM)
    z = rng.uniform(-0.05, -0.004, 40)
    near_axis = np.c_[rng.normal(0, 2e-4, 20), rng.normal(0, 2e-4, 20)]
    edge = rng.uniform(-1, 1, (20, 2))  # at the rim of the cone over the hologram's centre
    edge = edge / np.linalg.norm(edge, axis=1)[:, None] * (0.95 * g.cone * np.abs(z[20:]))[:, None]
    pos = np.c_[np.r_[near_axis, edge], z]
    amp = rng.uniform(0.5, 1, 40) * np.exp(2j * np.pi * rng.random(40))
    o = point_wave(
        pos, amp, wavelength=LAM, pitch=PITCH, shape=shape, obliquity=obliquity, method="direct"
    )
    err = max_rel(o, numpy_point_wave(pos, amp, shape, obliquity))
    assert err < POINT_SUM, f"OpenCL point sum vs float64 NumPy: max relative error {err:.2e}"


def test_recording_planes_match_the_direct_sum(rng):
    shape, n = (256, 256), 3000
    half = shape[0] * PITCH / 2
    pos = np.c_[rng.uniform(-half, half, (n, 2)), rng.uniform(-0.2, -0.1, n)]
    amp = np.exp(2j * np.pi * rng.random(n))
    direct = point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=shape, method="direct")
    wrp = point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=shape, method="wrp")
    err = rel_err(wrp, direct)
    assert err < WRP_VS_DIRECT, f"wavefront recording planes vs direct sum: {err:.2e}"


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
    from holo_core.plate.point_sources import CONE_FILL, Grid, safe_distance

    p, lam = 8e-6, 633e-9
    s = CONE_FILL * lam / (2 * p)
    assert math.isclose(safe_distance(Grid((8, 8), p, lam)), 2 * p * math.sqrt(1 - s * s) / s)
