"""Textured triangles recorded as primitives (holo_core.plate.triangles) against float64
Rayleigh-Sommerfeld sums (Sect. VI): a triangle equals the dense point sum of its surface,
triangles radiate the mean power of the points of the same surface, and report progress per
primitive."""

import numpy as np
import pytest
from accuracy import PRIMITIVE_VS_POINTS, rel_err
from point_sums import square

from holo_core.plate.record import record_hologram
from holo_core.plate.triangles import Primitive, primitive_wave, surface_field, surface_pitch
from holo_core.propagation import grid
from holo_core.scene.plate import Plate


def rs_point_sources(src, amp, normal, area, shape, pitch, lam):
    """First-kind Rayleigh-Sommerfeld (Eq. 7) of point sources ``src`` (N, 3) with field values
    ``amp`` on a surface of ``normal``, each standing for ``area`` [m²]: float64, on z = 0."""
    y, x = np.meshgrid(grid.coords(shape[0], pitch), grid.coords(shape[1], pitch), indexing="ij")
    x, y, k, out = x.ravel(), y.ravel(), 2 * np.pi / lam, np.zeros(x.size, complex)
    for s, a in zip(
        np.array_split(src, max(1, len(src) // 512)), np.array_split(amp, max(1, len(src) // 512))
    ):
        dx, dy, dz = x - s[:, :1], y - s[:, 1:2], -s[:, 2:]
        r = np.sqrt(dx * dx + dy * dy + dz * dz)
        cos = (dx * normal[0] + dy * normal[1] + dz * normal[2]) / r
        out += a @ (cos / r * (1 / r - 1j * k) * np.exp(1j * k * r))
    return (out * area / (2 * np.pi)).reshape(shape)


@pytest.mark.parametrize("tilt_deg, diffuse", [(0, False), (15, True)])
def test_triangle_equals_dense_point_sum(tilt_deg, diffuse):
    """A triangle 10 mm in front of the hologram: the primitive pipeline (spectrum rotation
    and resampling, then offset angular spectrum) against its surface samples summed as
    Rayleigh-Sommerfeld sources in float64. Tilted about x; diffuse = random phases."""
    lam, pitch, shape = 633e-9, 4e-6, (96, 96)
    t = np.radians(tilt_deg)
    flat = np.array([[-60e-6, -50e-6, 0], [60e-6, -50e-6, 0], [5e-6, 60e-6, 0]])
    tilt_x = np.array([[1, 0, 0], [0, np.cos(t), -np.sin(t)], [0, np.sin(t), np.cos(t)]])
    prim = Primitive(
        corners=flat @ tilt_x.T + [0, 0, -0.01],
        uvs=np.array([[0, 0], [1, 0], [0.5, 1]]),
        texture=np.ones((2, 2, 3)),
    )
    u = primitive_wave(prim, wavelength=lam, pitch=pitch, shape=shape, diffuse=diffuse)
    m, centre = prim.frame()
    q = surface_pitch(prim, wavelength=lam, pitch=pitch)
    f, mid = surface_field(prim, pitch=q, diffuse=diffuse)
    eta, xi = (grid.coords(n, q) + c for n, c in zip(f.shape, mid[::-1]))
    src = centre + eta[:, None, None] * m[:, 1] + xi[None, :, None] * m[:, 0]
    ref = rs_point_sources(src[f != 0], f[f != 0], m[:, 2], q * q, shape, pitch, lam)
    err = rel_err(u, ref)
    assert err < PRIMITIVE_VS_POINTS, f"triangle primitive vs dense point sum: {err:.2e}"


@pytest.mark.parametrize("tilt_deg", [0, 40])
def test_triangles_radiate_as_the_points_of_the_same_surface(tilt_deg):
    """A square recorded as two textured triangles and as points sampled on it: the same mean
    object-wave power, within the speckle's scatter (measured 0.98 and 1.12)."""
    plate = Plate(matrix_world=np.eye(4), width=0.1, height=0.1)
    mesh = square(0.04, -0.3, tilt_deg)
    points = record_hologram(mesh, plate=plate, resolution=256, depth=False, method="auto")
    triangles = record_hologram(
        (), triangles=[mesh], plate=plate, resolution=256, depth=False, method="auto"
    )
    ratio = np.mean(np.abs(triangles.object_wave[0]) ** 2) / np.mean(
        np.abs(points.object_wave[0]) ** 2
    )
    assert 0.8 <= ratio <= 1.25, f"triangles' mean power over the points': {ratio:.3f}"


def test_triangle_recording_reports_progress_per_primitive():
    """Textured triangles (a rotation and a propagation each) report progress as they go: a
    fraction per primitive and wavelength, rising, where they once reported none."""
    plate = Plate(matrix_world=np.eye(4), width=0.1, height=0.1)
    seen = []
    record_hologram(
        (),
        triangles=[square(0.04, -0.3)],
        plate=plate,
        resolution=128,
        depth=False,
        method="auto",
        progress=seen.append,
    )
    assert len(seen) >= 2 and seen == sorted(seen) and 0.1 <= seen[-1] <= 1.0, seen
    assert sum(0.1 <= f < 1.0 for f in seen) >= 2, "no report while the triangles ran"
