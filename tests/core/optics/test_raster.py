"""The rays of a pupil's bins and the surfaces they cross (holo_core/optics/raster)."""

import numpy as np
import pytest

from holo_core.optics.raster import bin_rays, crossing_chunks, crossing_count
from holo_core.scene.camera import look_at
from holo_core.scene.mesh import Mesh


def test_the_crossings_counted_before_the_work_are_those_found(rng):
    """A mesh of large random triangles through each other (a scan's noise, a damaged file):
    the count from the triangles' areas in direction cosine is the crossings the raster then
    enumerates, within 1 %."""
    v = rng.uniform([-0.03, -0.03, -0.36], [0.03, 0.03, -0.3], (3000, 3))
    mesh = Mesh(vertices=v, triangles=rng.integers(0, len(v), (1000, 3)))
    eye, b = np.array([0.0, 0.0, 0.3]), 2e-3
    rotation = look_at(eye, (0, 0, -0.33), up=(0, 1, 0))[:3, :3]
    shape = (81, 81)  # every direction of the objects from the pupil, with a rim
    found = sum(
        len(part[0]) for part in crossing_chunks([mesh], eye, rotation, b, shape, 2_000_000)
    )
    counted = crossing_count([mesh], eye, rotation, b)
    assert found > 100 * len(mesh.triangles)
    assert abs(counted / found - 1) < 0.01, (counted, found)


@pytest.mark.parametrize("turn", [0.0, 30.0])
def test_a_ray_through_a_shared_edge_crosses_the_surface_once(rng, turn):
    """A flat sheet of 128 triangles (a grid of 2.5 mm cells, each cut along one diagonal,
    corners listed in a random order), turned by ``turn`` degrees about the pupil's axis:
    every bin's ray that crosses the sheet away from its rim crosses exactly one triangle.
    At 0° the grid lines and diagonals through the pupil's axis hold whole rows, columns and
    diagonals of bins' rays exactly on shared edges; turned, rays pass within rounding of
    them. Reference: the crossing of the ray with the sheet's plane, in float64."""
    c, s = np.cos(np.radians(turn)), np.sin(np.radians(turn))
    spin = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # row vectors: v @ spin
    n, cell, z = 9, 2.5e-3, -0.25
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    vertices = (
        np.stack([(j - n // 2) * cell, (i - n // 2) * cell, np.full(i.shape, z)], -1).reshape(-1, 3)
        @ spin
    )
    triangles = []
    for r in range(n - 1):
        for q in range(n - 1):
            a, b, d, e = r * n + q, r * n + q + 1, (r + 1) * n + q, (r + 1) * n + q + 1
            triangles += [[a, b, e], [a, e, d]] if (r + q) % 2 else [[a, b, d], [b, e, d]]
    triangles = np.array(triangles)
    # each triangle's corners from a random one of its six orders: either winding, any start
    orders = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]])
    triangles = np.take_along_axis(triangles, orders[rng.integers(0, 6, len(triangles))], 1)
    sheet = Mesh(vertices=vertices, triangles=triangles)
    b, shape, rotation = 5e-4, (81, 81), np.eye(3)
    ky, kx = np.meshgrid(
        np.arange(shape[0]) - shape[0] // 2, np.arange(shape[1]) - shape[1] // 2, indexing="ij"
    )
    tx, ty = bin_rays(kx, ky, b)
    for t in np.linspace(-0.01, 0.01, 9):  # pupils along a diagonal of the grid
        eye = np.array([t, t, 0.0]) @ spin + (0.0, 0.0, 0.3)
        parts = list(crossing_chunks([sheet], eye, rotation, b, shape, 2_000_000))
        hit_x, hit_y = (np.concatenate([p[i] for p in parts]) for i in (0, 1))
        count = np.zeros(shape, int)
        np.add.at(count, (hit_y % shape[0], hit_x % shape[1]), 1)
        # the rays' crossings of the sheet's plane, in its own axes
        cross = eye[:2] + (z - eye[2]) * np.stack([-tx, -ty], -1)
        inner = np.abs(cross @ spin[:2, :2].T).max(-1) < (n // 2) * cell - 1e-6
        found = count[ky % shape[0], kx % shape[1]]
        assert inner.sum() > 1000, inner.sum()
        assert np.all(found[inner] == 1), (
            t,
            (found[inner] == 0).sum(),
            np.unique(found[inner], return_counts=True),
        )
