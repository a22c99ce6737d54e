"""The rays of a pupil's bins and the surfaces they cross (holo_core/optics/raster)."""

import numpy as np

from holo_core.optics.raster import crossing_chunks, crossing_count
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
    found = sum(len(part[0]) for part in crossing_chunks([mesh], eye, rotation, b, shape,
                                                        2_000_000))
    counted = crossing_count([mesh], eye, rotation, b)
    assert found > 100 * len(mesh.triangles)
    assert abs(counted / found - 1) < 0.01, (counted, found)
