"""The direct point sum (holo_core.plate.point_sum) against analytic waves and float64 NumPy
(Eq. 3): one point is the spherical wave inside its cone, many are the float64 sum weighted by
each one's sampling cone, with and without the obliquity factor."""

import numpy as np
import pytest
from accuracy import POINT_SUM
from point_sums import LAM, PITCH

from holo_core.plate.point_sources import point_wave
from holo_core.plate.point_sum import Grid, cone_weight
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
