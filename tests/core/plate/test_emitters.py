"""A plate's emitters (holo_core.plate.emitters) against the geometry they are defined by: they
lie on the surfaces, on a lattice of directions from the zone's centre ``spacing`` apart in
direction cosine, with their surface's colour."""

import numpy as np
import plate_scene as ps
import pytest

from holo_core.plate.emitters import surface_points, zone_emitters
from holo_core.scene.camera import look_at
from holo_core.scene.mesh import Mesh, outward
from holo_core.scene.plate import ViewingZone

ZONE = ViewingZone(centre=(0.0, 0.0, 0.3), half_extents=(0.03, 0.03, 0.0), pupil=0.01)
SPACING = 1e-3  # [1] direction cosine between neighbouring emitters


def square(side, z, colour):
    """A square of ``side`` [m] facing the plate at depth ``z`` [m], of one linear colour."""
    h = side / 2
    v = np.array([[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]])
    return Mesh(
        vertices=v, triangles=np.array([[0, 1, 2], [0, 2, 3]]), colours=np.tile(colour, (4, 1))
    )


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


@pytest.mark.parametrize("turn", [0.0, 30.0])
def test_no_emitter_shows_through_an_occluder(turn):
    """A 2 cm square at z = −0.25 m in front of an 8 cm square at −0.3 m, turned by ``turn``
    degrees about the axis (0° lays its diagonal, where its two triangles meet, along bins'
    rays). From each grid point of the zone, an emitter of the back square whose ray crosses
    the front square's plane inside it, farther from its edges than the diagonal of the bin
    cell around the emitter's direction there (the visibility mixes that cell's four bins), is
    not seen; one whose ray clears the square by as much is. Reference: the ray's crossing of
    the square in float64, in the square's own frame."""
    c, s = np.cos(np.radians(turn)), np.sin(np.radians(turn))
    spin = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # row vectors: v @ spin
    front = square(0.02, -0.25, (1.0, 0.0, 0.0))
    front = Mesh(vertices=front.vertices @ spin, triangles=front.triangles, colours=front.colours)
    e = zone_emitters([square(0.08, -0.3, (1.0, 1.0, 1.0)), front], ZONE, SPACING)
    assert not (np.linalg.norm(e.position - (0.0, 0.0, -0.3), axis=1) < 1e-9).any(), (
        "the back square's centre, hidden from the whole zone, is kept"
    )
    back = np.isclose(e.position[:, 2], -0.3, atol=1e-9)
    (x0, dx), (y0, dy) = e.grid
    gy, gx = e.visibility.shape[1:]
    eyes = np.stack(np.meshgrid(x0 + dx * np.arange(gx), y0 + dy * np.arange(gy)), -1)
    eyes = np.concatenate([eyes, np.zeros((gy, gx, 1))], -1) + ZONE.centre  # (gy, gx, 3)
    p = e.position[back][:, None, None]
    along = (-0.25 - eyes[..., 2]) / (p[..., 2] - eyes[..., 2])
    cross = eyes + along[..., None] * (p - eyes)  # in the front square's plane
    local = cross[..., :2] @ spin[:2, :2].T  # in the square's own axes
    inset = 0.01 - np.abs(local).max(-1)  # > 0 inside, the distance to the nearer edge
    # a bin cell's diagonal in that plane: √2 · the spacing in direction cosine · the distance
    margin = np.sqrt(2) * SPACING * np.linalg.norm(cross - eyes, axis=-1)
    seen = e.visibility[back]
    hidden, clear = inset > margin, -inset > margin
    assert hidden.sum() > 1000 and clear.sum() > 1000, (hidden.sum(), clear.sum())
    assert seen[hidden].max() == 0, (seen[hidden].max(), (seen[hidden] > 0).sum())
    assert seen[clear].min() > 1 - 1e-6, seen[clear].min()  # float32 weights' sum


def test_random_phases_follow_the_emitters_not_their_count():
    """A plate's random phases are drawn per emitter from its key (holo_core.plate.emitters.
    emitter_keys: its mesh, triangle and bin), not by its place in the list: with one triangle
    of a 2 cm square before an 8 cm one removed (its last: the others keep their indices),
    the emitters it hid appear and its own go, yet every emitter found both times (the same point, to 1e-12 m) keeps its phase exactly,
    for plain and coded looks. Drawn in list order instead (the earlier rule, here as the
    reference that the case moves emitters), most of them would change. The keys are
    distinct, and the phases uniform on [0, 2π): their mean phasor is within 4/√n of 0."""
    from holo_core.plate.look_codes import emitter_phases, look_code

    back, front = square(0.08, -0.3, (1.0, 1.0, 1.0)), square(0.02, -0.25, (1.0, 0.0, 0.0))
    half = Mesh(vertices=front.vertices, triangles=front.triangles[:1], colours=front.colours)
    whole, cut = (zone_emitters([front_, back], ZONE, SPACING) for front_ in (front, half))
    where = {tuple(np.round(p, 12)): n for n, p in enumerate(cut.position)}
    i, j = np.array(
        [
            (n, where[tuple(np.round(p, 12))])
            for n, p in enumerate(whole.position)
            if tuple(np.round(p, 12)) in where
        ]
    ).T
    assert len(whole) != len(cut) and len(i) > 0.5 * len(whole), (len(whole), len(cut), len(i))
    for code in (None, look_code(1, 2)):
        a, b = emitter_phases(whole, 7, code), emitter_phases(cut, 7, code)
        assert np.array_equal(a[i], b[j]), np.abs(a[i] - b[j]).max()
    by_order = [np.random.default_rng(7).uniform(0, 2 * np.pi, len(e)) for e in (whole, cut)]
    moved = np.mean(by_order[0][i] != by_order[1][j])
    assert moved > 0.5, moved
    assert len(np.unique(whole.key)) == len(whole)
    p = emitter_phases(whole, 7, None)
    assert p.min() >= 0 and p.max() < 2 * np.pi
    assert abs(np.exp(1j * p).mean()) < 4 / np.sqrt(len(p)), abs(np.exp(1j * p).mean())
    assert not np.array_equal(p, emitter_phases(whole, 8, None))  # another seed, other phases


def test_a_closed_meshs_outside_is_found_from_its_winding_and_a_card_has_none():
    """The cube and the UV sphere (split seams, a pole's slivers) are closed: +1 wound
    outward, -1 with every triangle's winding reversed; a square card and the cube less one
    face are not closed (0)."""
    cube, sphere = ps.cube(), ps.sphere()
    flipped = lambda m: Mesh(
        vertices=m.vertices,
        triangles=m.triangles[:, ::-1],  # noqa: E731
        colours=m.colours,
    )
    assert outward(cube) == -outward(flipped(cube)) != 0
    assert outward(sphere) == -outward(flipped(sphere)) != 0
    assert outward(square(0.04, -0.3, (1, 1, 1))) == 0
    open_box = Mesh(vertices=cube.vertices, triangles=cube.triangles[2:], colours=cube.colours)
    assert outward(open_box) == 0


def test_no_zone_point_sees_a_closed_meshs_far_side():
    """The plate scene's cube (closed), three layers deep: the zone's rays cross its far side
    (the second layer), but no emitter the zone keeps is seen from a grid point its face is
    turned away from. Near the silhouettes the far side's crossings lie within the depth
    test's slack for a surface seen edge-on; passed, their light swelled a view's silhouettes
    by half a pixel (IoU 0.976 against the camera hologram's 0.994 on the close-up)."""
    cube = ps.cube()
    rotation = look_at(ZONE.centre, ps.CUBE_CENTRE, up=(0.0, 1.0, 0.0))[:3, :3]
    crossed = surface_points([cube], ZONE.centre, rotation, SPACING, sides=[outward(cube)])
    position, normal = crossed[0], crossed[2]
    assert (np.einsum("nj,nj->n", normal, np.asarray(ZONE.centre) - position) < 0).sum() > 100
    e = zone_emitters([cube], ZONE, SPACING)
    r = ps.rotation(0.35, 0.6)
    local = (e.position - ps.CUBE_CENTRE) @ r  # the cube's own axes
    axis = np.abs(local).argmax(1)
    normal = np.zeros_like(local)
    normal[np.arange(len(local)), axis] = np.sign(local[np.arange(len(local)), axis])
    normal = normal @ r.T
    (x0, sx), (y0, sy) = e.grid
    gy, gx = e.visibility.shape[1:]
    points = np.array(
        [
            [ZONE.centre[0] + x0 + i * sx, ZONE.centre[1] + y0 + j * sy, ZONE.centre[2]]
            for j in range(gy)
            for i in range(gx)
        ]
    )
    towards = points[None, :, :] - e.position[:, None, :]
    away = np.einsum("nj,npj->np", normal, towards) < 0  # (n, grid points)
    seen = e.visibility.reshape(len(e), -1)
    assert (seen[away] == 0).all(), f"{int((seen[away] > 0).sum())} seen from behind"
