"""The light from the objects to the zone as it crosses the plate (holo_core.plate.zone_light):
the band of directions against random pairs of window and zone points, the surfaces a zone
sees against a sphere's silhouette and a card."""

import numpy as np
import plate_scene as ps
import pytest

from holo_core.plate.zone_light import RIM, rim_corners, seen_area, zone_band
from holo_core.scene.mesh import Mesh
from holo_core.scene.plate import ViewingZone

ZONE = ViewingZone(centre=(0.01, -0.005, 0.3), half_extents=(0.04, 0.03, 0.02), pupil=0.05 / 2.8)


def test_band_is_the_widest_turn_from_the_carrier_towards_the_zone(rng):
    """The samples' band along each axis: the largest difference of direction cosines between
    the line from a window point to the zone's centre and one to a point of the zone (with its
    rim). The window's and the zone's corners reach it; 100,000 random pairs inside stay
    below it."""
    lo, hi = np.array([-0.03, -0.02]), np.array([0.04, 0.03])
    band = zone_band(lo, hi, ZONE)
    c, e = np.asarray(ZONE.centre), np.asarray(ZONE.half_extents) * [1 + RIM, 1 + RIM, 1]
    x = np.stack(
        [rng.uniform(lo[0], hi[0], 100_000), rng.uniform(lo[1], hi[1], 100_000), np.zeros(100_000)],
        1,
    )
    z = c + rng.uniform(-1, 1, (100_000, 3)) * e
    unit = lambda v: v / np.linalg.norm(v, axis=1, keepdims=True)  # noqa: E731
    d = np.abs(unit(z - x) - unit(c - x))
    assert d[:, 0].max() <= band[0] + 1e-12 and d[:, 1].max() <= band[1] + 1e-12
    assert d[:, 0].max() >= 0.9 * band[0] and d[:, 1].max() >= 0.9 * band[1]
    assert len(rim_corners(ZONE)) == 8


def test_the_surfaces_a_zone_sees_are_a_spheres_silhouette_and_a_cards_one_face():
    """seen_area: a sphere of radius r at distance d from the centre covers the silhouette's
    tangent area π r²/(d² − r²), whichever way its triangles wind (its front faces only);
    a card counts its one face from either side."""
    ball = ps.sphere(centre=np.array([0.0, 0.0, -0.3]), radius=0.02, n=128)
    exact = np.pi * 0.02**2 / (0.3**2 - 0.02**2)
    assert seen_area([ball], (0.0, 0.0, 0.0)) == pytest.approx(exact, rel=0.01)
    flipped = Mesh(vertices=ball.vertices, triangles=ball.triangles[:, ::-1])
    assert seen_area([flipped], (0.0, 0.0, 0.0)) == pytest.approx(exact, rel=0.01)
    corners = [[-0.01, -0.01, -0.2], [0.01, -0.01, -0.2], [0.01, 0.01, -0.2], [-0.01, 0.01, -0.2]]
    card = Mesh(vertices=np.array(corners), triangles=np.array([[0, 1, 2], [0, 2, 3]]))
    for tri in (card.triangles, card.triangles[:, ::-1]):
        assert seen_area(
            [Mesh(vertices=card.vertices, triangles=tri)], (0.0, 0.0, 0.0)
        ) == pytest.approx(0.02**2 / 0.2**2)
