"""A plate's emitters (holo_core.plate.emitters) against the geometry they are defined by: they
lie on the surfaces, on a lattice of directions from the zone's centre ``spacing`` apart in
direction cosine, with their surface's colour."""

import numpy as np

from holo_core.plate.emitters import zone_emitters
from holo_core.scene.mesh import Mesh
from holo_core.scene.plate import ViewingZone

ZONE = ViewingZone(centre=(0.0, 0.0, 0.3), half_extents=(0.03, 0.03, 0.0), pupil=0.01)
SPACING = 1e-3  # [1] direction cosine between neighbouring emitters


def square(side, z, colour):
    """A square of ``side`` [m] facing the plate at depth ``z`` [m], of one linear colour."""
    h = side / 2
    v = np.array([[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]])
    return Mesh(vertices=v, triangles=np.array([[0, 1, 2], [0, 2, 3]]),
                colours=np.tile(colour, (4, 1)))


def test_emitters_lie_on_the_surface_on_a_lattice_of_directions():
    """One square 0.6 m from the zone's centre: every emitter lies on it, its bin (kx, ky) is
    its direction from the centre (the pupil's axes, looking at the square) over the spacing,
    and the bins cover the square's directions (a side of 2·0.02/0.6/1e-3 ≈ 33 bins)."""
    e = zone_emitters([square(0.04, -0.3, (0.2, 0.5, 0.8))], ZONE, SPACING, layers=1)
    assert np.allclose(e.position[:, 2], -0.3, atol=1e-9), np.ptp(e.position[:, 2])
    assert np.abs(e.position[:, :2]).max() <= 0.02 + 1e-9
    u = e.position - ZONE.centre
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    # the square's centre lies straight ahead, so the pupil's axes are the plate's; a bin's
    # ray runs along −(α, β) of its direction cosines (α, β) = (kx, ky)·spacing
    assert np.allclose(-u[:, :2] / SPACING, e.cell, atol=1e-6)
    side = np.ptp(e.cell, axis=0) + 1
    assert np.all(np.abs(side - 0.04 / 0.6 / SPACING) <= 2), side
    assert np.allclose(e.colour, (0.2, 0.5, 0.8))

