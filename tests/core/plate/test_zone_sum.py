"""The carrier plate's samples as a sum over emitters (plate/zone_sum.py) against a float64
NumPy sum of the same definition: every emitter's spherical wave (Eq. 3) through its window
towards the zone and its visibility, times the conjugate carrier converging on the zone."""

import numpy as np
import pytest
from accuracy import ZONE_SUM, ZONE_SUM_ROUGH_VISIBILITY, rel_err

from holo_core.plate.zone_sum import ZoneEmitters, ZoneSum, ZoneWindow, footprints, zone_sum

WAVELENGTH = 5e-6
WINDOW = ZoneWindow(origin=(-0.03, -0.025), pitch=2.3e-5, row_pitch=3.1e-5, shape=(448, 704),
                    centre=(0.01, -0.005, 0.3), half_extents=(0.03, 0.02, 0.01), rim=0.15)


def rim(u, inner, width):
    t = np.clip((np.abs(u) - inner) / width, 0, 1)
    return (1 - t) ** 2 * (1 + 2 * t)


def reference(em: ZoneEmitters, win: ZoneWindow, wavelength) -> np.ndarray:
    """B(x) = exp(ik|x − Z|)·Σ a_j·w_j(x)·exp(ik·r_j)/r_j in float64, one emitter at a time."""
    k = 2 * np.pi / wavelength
    x = win.origin[0] + np.arange(win.shape[1]) * win.pitch
    y = win.origin[1] + np.arange(win.shape[0]) * win.row_pitch
    X, Y = np.meshgrid(x, y)
    Z, e = np.asarray(win.centre), np.asarray(win.half_extents)
    (g0x, gsx), (g0y, gsy) = em.grid
    out = np.zeros((em.amplitude.shape[1],) + win.shape, complex)
    for j, p in enumerate(em.position):
        s = (Z[2] - p[2]) / -p[2]  # the ray through x reaches the zone's plane at xi
        xi, eta = p[0] - Z[0] + s * (X - p[0]), p[1] - Z[1] + s * (Y - p[1])
        w = rim(xi, e[0] + e[2] * np.abs(X - p[0]) / -p[2], win.rim * e[0]) * \
            rim(eta, e[1] + e[2] * np.abs(Y - p[1]) / -p[2], win.rim * e[1])
        if em.visibility[j] >= 0:
            v = em.table[em.visibility[j]] / 255.0
            gy, gx = v.shape
            fx = np.clip((xi - g0x) / gsx, 0, gx - 1.0001)
            fy = np.clip((eta - g0y) / gsy, 0, gy - 1.0001)
            ix, iy = fx.astype(int), fy.astype(int)
            ax, ay = fx - ix, fy - iy
            top = v[iy, ix] * (1 - ax) + v[iy, ix + 1] * ax
            bottom = v[iy + 1, ix] * (1 - ax) + v[iy + 1, ix + 1] * ax
            w = w * (top * (1 - ay) + bottom * ay)
        r = np.sqrt((X - p[0]) ** 2 + (Y - p[1]) ** 2 + p[2] ** 2)
        out += em.amplitude[j][:, None, None] * (w * np.exp(1j * k * r) / r)[None]
    rz = np.sqrt((X - Z[0]) ** 2 + (Y - Z[1]) ** 2 + Z[2] ** 2)
    return out * np.exp(1j * k * rz)[None]


def emitters(rng, n, table):
    pos = np.stack([rng.uniform(-0.02, 0.02, n), rng.uniform(-0.02, 0.02, n),
                    rng.uniform(-0.35, -0.25, n)], 1)
    amp = rng.normal(size=(n, 3)) + 1j * rng.normal(size=(n, 3))
    rows = np.where(np.arange(n) % 2 == 0, np.arange(n) // 2, -1).astype(np.int32)
    return ZoneEmitters(position=pos, amplitude=amp, visibility=rows, table=table,
                        grid=((-0.035, 0.0175), (-0.024, 0.012)))


@pytest.mark.parametrize("rough", [False, True])
def test_zone_sum_equals_float64_numpy(rng, rough):
    """Three colour channels, 60 emitters 0.25-0.35 m behind, every other one seen from part
    of the zone: smooth visibility tables (an edge across the zone) within ZONE_SUM, random
    ones (a kink at every grid cell) within ZONE_SUM_ROUGH_VISIBILITY."""
    n = 60
    if rough:
        table = rng.integers(0, 256, (n // 2, 3, 5)).astype(np.uint8)
    else:
        table = np.full((n // 2, 3, 5), 255, np.uint8)
        table[:, :, :2] = 96
    em = emitters(rng, n, table)
    got, want = zone_sum(em, WINDOW, WAVELENGTH), reference(em, WINDOW, WAVELENGTH)
    err = rel_err(got, want)
    print(f"relative error {err:.2e}")
    assert err <= (ZONE_SUM_ROUGH_VISIBILITY if rough else ZONE_SUM), err


def test_regions_tile_the_whole_window(rng):
    """A window computed in blocks (a tiled recording's tasks) equals it computed whole, bit
    for bit: each sample's sum runs over the same emitters in the same order."""
    em = emitters(rng, 40, np.full((20, 3, 5), 200, np.uint8))
    whole = ZoneSum(em, WINDOW, WAVELENGTH)
    full = whole.region(0, 0, *WINDOW.shape)
    parts = np.concatenate([np.concatenate([whole.region(r, c, 256, 256)[:, :min(256, 448 - r),
                                                                         :min(256, 704 - c)]
                                            for c in range(0, 704, 256)], 2)
                            for r in range(0, 448, 256)], 1)
    assert np.array_equal(full, parts[:, :448, :704])


def test_footprint_is_the_cone_towards_the_zone():
    """An emitter straight behind the zone's centre at the zone's distance lights the zone's
    box (with its rim) scaled by one half on the plate halfway: its footprint's columns and
    rows span (1 + rim)·(half width + depth parallax) around its foot."""
    win = ZoneWindow(origin=(-0.05, -0.05), pitch=1e-4, row_pitch=2e-4, shape=(500, 1000),
                     centre=(0.0, 0.0, 0.3), half_extents=(0.02, 0.01, 0.0), rim=0.1)
    c0, c1, r0, r1 = footprints(np.array([[0.0, 0.0, -0.3]]), win)[0]
    assert (c1 - c0) * 1e-4 == pytest.approx(2 * 0.022 / 2, abs=3e-4)
    assert (r1 - r0) * 2e-4 == pytest.approx(2 * 0.011 / 2, abs=5e-4)
