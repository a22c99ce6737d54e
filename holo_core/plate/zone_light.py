"""The light from the objects to the viewing zone as it crosses the plate, in the plate's frame
[m]: the zone with its soft rim, the window of the plate the light crosses, the band of
directions it carries there, and the surfaces the zone sees (their emitters and footprints).
Pure arithmetic, as the plan (:mod:`.plan`) that reads it.
"""

from __future__ import annotations

import numpy as np

from ..scene.mesh import outward
from ..scene.plate import ViewingZone, box_corners
from ..validate import InputError

RIM = 0.15  # the zone's soft rim, a fraction of its half widths


def rim_corners(zone: ViewingZone) -> np.ndarray:
    """The zone box's corners (8, 3) [m] with its soft rim (x and y widened by RIM)."""
    c, e = np.asarray(zone.centre), np.asarray(zone.half_extents)
    e = e * np.array([1 + RIM, 1 + RIM, 1.0])
    return box_corners((c - e, c + e))


def window_on_plate(box, zone: ViewingZone, width, height) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) (x, y) [m] of the plate's part that light from the objects' box to the zone
    (with its rim) crosses, cut to the plate's size."""
    objects, eyes = box_corners(box), rim_corners(zone)
    t = -objects[:, None, 2] / (eyes[None, :, 2] - objects[:, None, 2])
    xy = objects[:, None, :2] + t[..., None] * (eyes[None, :, :2] - objects[:, None, :2])
    lo, hi = xy.reshape(-1, 2).min(0), xy.reshape(-1, 2).max(0)
    edge = np.array([width / 2, height / 2])
    lo, hi = np.maximum(lo, -edge), np.minimum(hi, edge)
    if (hi <= lo).any():
        raise InputError(
            f"no light from the objects reaches the viewing zone through the "
            f"{width:g} x {height:g} m plate: the zone ({zone.describe()}) sees "
            f"the objects beside it"
        )
    return lo, hi


def zone_band(lo, hi, zone: ViewingZone) -> tuple[float, float]:
    """The largest differences of direction cosines (x, y) between the line from a point of
    the window [lo, hi] (x, y) [m] to the zone's centre and one to a point of the zone with
    its rim: the carrier-free samples' band along each axis."""
    corners = np.array([[x, y, 0.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])])
    to_eyes = rim_corners(zone)[None] - corners[:, None]
    to_centre = np.asarray(zone.centre)[None] - corners
    d = (
        to_eyes / np.linalg.norm(to_eyes, axis=-1, keepdims=True)
        - (to_centre / np.linalg.norm(to_centre, axis=-1, keepdims=True))[:, None]
    )
    return float(np.abs(d[..., 0]).max()), float(np.abs(d[..., 1]).max())


def seen_area(meshes, centre, sides=None) -> float:
    """The area (dimensionless: squared direction tangents x/−z, y/−z about ``centre``, the
    measure the emitters' lattice spaces them in) of the surfaces of ``meshes`` (the plate's
    frame [m], z below ``centre``'s) seen from ``centre`` (3,) [m]: each closed mesh's faces
    turned towards it, every face of an open one (a card is seen from either side); ``sides``
    each mesh's :func:`holo_core.scene.mesh.outward` where the caller found it (it holds in any
    frame), else found here. Surfaces behind others are counted too: an upper bound where
    objects hide each other."""
    c = np.asarray(centre, np.float64)
    total = 0.0
    sides = [outward(m) for m in meshes] if sides is None else sides
    for mesh, side in zip(meshes, sides, strict=True):
        v = np.asarray(mesh.vertices, np.float64)[np.asarray(mesh.triangles, np.int64)] - c
        t = v[..., :2] / -v[..., 2:3]
        a, b = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
        area = (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]) / 2
        if side:  # a face turned towards the centre: its outward normal against the ray
            normal = side * np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
            area = area[np.einsum("ij,ij->i", normal, v.mean(1)) < 0]
        total += float(np.abs(area).sum())
    return total


def emitters_seen(box, zone: ViewingZone, spacing, area, seen=None) -> tuple[int, float]:
    """(the emitters' count, the samples an emitter's footprint holds), estimated: the
    surfaces' area ``seen`` from the zone's centre (:func:`seen_area`) over a spot's, or
    where the surfaces are not known the box's (its solid angle, times the two surfaces a ray
    may meet, the front one and what the zone sees behind an edge: the shot's objects have a
    third of that, a sphere half); the footprint is the zone's box with its rim, scaled from
    the zone's plane onto the plate at the objects' middle depth."""
    centre = np.asarray(zone.centre)
    v = box_corners(box) - centre
    t = v[:, :2] / -v[:, 2:3]
    solid = 1.5 * float(np.prod(t.max(0) - t.min(0))) if seen is None else seen
    emitters = int(solid / spacing**2) + 1
    depth = -float(box.mean(0)[2])
    scale = depth / (depth + centre[2])
    e = np.asarray(zone.half_extents) * (1 + RIM)
    return emitters, float(4 * e[0] * e[1] * scale**2 / area)
