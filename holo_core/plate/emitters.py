"""A plate's emitters: the surfaces its viewing zone can see, one emitter per direction the
zone's reference pupil resolves, with the zone points each is seen from.

- Where (:func:`zone_emitters`). The rays of a pupil at the zone's centre, bins ``spacing``
  apart in direction cosine (one resolved spot of the views), cross the surfaces; every
  crossing up to ``layers`` deep is a candidate, so that what one zone point sees behind an
  edge that hides it from the centre is there (depth peeling). The emitters lie on a lattice
  of directions from the centre: their bins are the cells of the looks' phase codes.
- Seen from where (:func:`visibility`). Each point of a grid over the zone's centre plane
  rasters the nearest surfaces (a depth buffer, the same bins); an emitter is seen from it
  where it is no farther than that buffer (bilinear between the four bins around its
  direction, with a bias for its surface's slope). A ray from an emitter through the plate
  reaches the zone between grid points: the plate's sum interpolates there.
- Who (:func:`emitter_keys`, :func:`random_phases`). Each emitter is named by what it is, the
  crossing of one bin's ray with one triangle, hashed to a 64-bit key; its random phase is a
  hash of that key and the look's seed, so an emitter gained or lost elsewhere (an occluder's
  edge rastered differently) leaves every other emitter's phase as it was.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy import float32, int32

from ..opencl import get_runtime
from ..opencl.arrays import read
from ..opencl.kernel import BUFFER, kernel
from ..opencl.runtime import associated
from ..optics.raster import bin_rays, crossings
from ..scene.camera import look_at
from ..scene.mesh import outward, surface_colour
from ..scene.plate import ViewingZone
from ..validate import InputError

PROGRAM = associated(__file__)
# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
DEPTH_RASTER = kernel(PROGRAM, "depth_raster", zbuf=BUFFER, h=int32, w=int32, b=float32,
                      tx=BUFFER, ty=BUFFER, d=BUFFER, tri=BUFFER, triangles=int32)
SEEN_FROM = kernel(PROGRAM, "seen_from", seen=BUFFER, point=int32, zbuf=BUFFER, h=int32,
                   w=int32, b=float32, px=BUFFER, py=BUFFER, pz=BUFFER, nx=BUFFER, ny=BUFFER,
                   nz=BUFFER, ex=float32, ey=float32, axes=BUFFER, max_slope=float32,
                   bias_bins=float32, bias_depth=float32, closed=BUFFER, emitters=int32)
# fmt: on

EDGE_BINS = 4  # bins around the objects' directions
BIAS_BINS = 1.5  # the depth test's slack: the surface's depth change over this many bins
BIAS_DEPTH = 2e-3  # ... plus this fraction of the depth
MAX_SLOPE = 11.0  # tan 85°: a surface seen more edge-on gets no more slack
GRID_POINTS = (3, 17)  # the zone's visibility grid, points a side (at least, at most)


@dataclass(frozen=True, eq=False)
class Emitters:
    """Emitters in the plate's frame: ``position`` (n, 3) [m], linear ``colour`` (n, 3),
    ``cell`` (n, 2) their bin (kx, ky) from the zone's centre, ``visibility`` (n, G, G) in
    [0, 1] from the zone's grid points, ``grid`` the points' offsets from the zone's centre
    ((x0, step_x), (y0, step_y)) [m]; ``ids`` (n,) where they are drawn from a larger set
    shared by several plates (:mod:`.parts`), their indices in it, ``count`` its size: their
    random phases are the set's, so every plate of it sends one pupil the same wave;
    ``weight`` (n,), where given, scales their amplitudes (a set's lattice seen from this
    zone: :func:`holo_core.plate.parts.set_emitters`); ``key`` (n,) uint64 each one's
    identity (:func:`emitter_keys`), which its random phases are drawn from
    (:func:`random_phases`)."""

    position: np.ndarray
    colour: np.ndarray
    cell: np.ndarray
    visibility: np.ndarray
    grid: tuple
    ids: np.ndarray | None = None
    count: int = 0
    weight: np.ndarray | None = None
    key: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.position)


def zone_frame(zone: ViewingZone, bounds) -> np.ndarray:
    """The axes (columns) of a pupil at the zone's centre looking at the objects' box
    ``bounds`` (2, 3) [m] (the plate's frame), +y kept up."""
    target = np.asarray(bounds, np.float64).mean(0)
    return look_at(zone.centre, target, up=(0.0, 1.0, 0.0))[:3, :3]


def bins_covering(points, position, rotation, spacing) -> tuple[int, int]:
    """(h, w) of a bin grid ``spacing`` apart (FFT order) around the directions of ``points``
    (N, 3) [m] seen from ``position`` with axes ``rotation``."""
    v = (np.asarray(points, np.float64) - position) @ rotation
    r = np.linalg.norm(v, axis=1)
    half_x = np.abs(v[:, 0] / r).max() / spacing + EDGE_BINS
    half_y = np.abs(v[:, 1] / r).max() / spacing + EDGE_BINS
    return 2 * math.ceil(half_y) + 1, 2 * math.ceil(half_x) + 1


def grid_points(zone: ViewingZone) -> tuple[int, int]:
    """(rows, cols) of the zone's visibility grid: about one point per pupil across it, at
    least GRID_POINTS[0] a side."""
    hx, hy = zone.half_extents[:2]
    step = zone.pupil or max(hx, hy) / 4
    return tuple(int(np.clip(math.ceil(2 * half / step) + 1, *GRID_POINTS)) for half in (hy, hx))


def zone_emitters(
    meshes, zone: ViewingZone, spacing: float, *, layers=3, grid: tuple | None = None, sides=None
) -> Emitters:
    """The emitters of ``meshes`` (the plate's frame) that the zone sees (module docstring),
    ``spacing`` apart in direction cosine from the zone's centre; ``sides`` each mesh's
    :func:`~holo_core.scene.mesh.outward` where the caller found it."""
    if not meshes:
        raise InputError("a plate needs at least one mesh to record")
    every = np.concatenate([m.vertices for m in meshes])
    rotation = zone_frame(zone, np.array([every.min(0), every.max(0)]))
    position, colour, normal, cell, key, closed = surface_points(
        meshes,
        zone.centre,
        rotation,
        spacing,
        layers=layers,
        sides=[outward(m) for m in meshes] if sides is None else sides,
    )
    g = grid or grid_points(zone)
    offsets, seen = visibility(meshes, position, normal, zone, rotation, spacing, g, closed=closed)
    keep = seen.reshape(len(seen), -1).max(1) > 0
    return Emitters(
        position=position[keep],
        colour=colour[keep],
        cell=cell[keep],
        visibility=seen[keep],
        grid=offsets,
        key=key[keep],
    )


def surface_points(meshes, centre, rotation, spacing: float, *, layers=3, lattice=0, sides=None):
    """(position (n, 3) [m], linear colour (n, 3) >= 0, unit normal (n, 3), bin (kx, ky) (n, 2),
    key (n,) uint64, closed (n,) bool) of the crossings of the rays of a pupil at ``centre``
    (3,) [m] with axes ``rotation``, bins ``spacing`` apart in direction cosine, with
    ``meshes``, up to ``layers`` deep (all in one frame, the meshes'); ``key`` names each
    crossing (:func:`emitter_keys`, of the ``lattice``-th pupil where several find one set).
    ``sides``: each mesh's :func:`~holo_core.scene.mesh.outward` (None: none taken as
    closed); on a closed mesh (``closed``) the normal points out of it, elsewhere it follows
    the triangle's winding and either side may be the one a pupil sees."""
    every = np.concatenate([m.vertices for m in meshes])
    centre = np.asarray(centre, np.float64)
    shape = bins_covering(every, centre, rotation, spacing)
    hits = crossings(meshes, centre, rotation, spacing, shape, layers=layers)
    position = _points(hits, centre, rotation, spacing)
    colour = np.ones((len(hits), 3))
    normal = np.zeros((len(hits), 3))
    sides = np.zeros(len(meshes)) if sides is None else np.asarray(sides, np.float64)
    for m, mesh in enumerate(meshes):
        sel = hits.mesh == m
        if not sel.any():
            continue
        corners = np.asarray(mesh.triangles)[hits.triangle[sel]]
        c = surface_colour(mesh, corners, hits.bary[sel], 3)
        colour[sel] = c if c.shape[1] == 3 else np.repeat(c.mean(1, keepdims=True), 3, 1)
        v = np.asarray(mesh.vertices, np.float64)[corners]
        n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
        normal[sel] = (
            n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300) * (sides[m] or 1.0)
        )
    key = emitter_keys(hits.mesh, hits.triangle, hits.kx, hits.ky, lattice)
    return (
        position,
        np.clip(colour, 0, None),
        normal,
        np.stack([hits.kx, hits.ky], 1),
        key,
        sides[hits.mesh] != 0 if len(hits) else np.zeros(0, bool),
    )


_GOLDEN = np.uint64(0x9E3779B97F4A7C15)  # SplitMix64's increment (2⁶⁴/φ)


def _mix(x: np.ndarray) -> np.ndarray:
    """SplitMix64's finaliser (Steele, Lea and Flood 2014), uint64 → uint64: a bijection
    whose every output bit depends on every input bit. Held as an array (NumPy's uint64
    arrays wrap modulo 2⁶⁴ as it needs; its scalars warn that they overflow)."""
    x = np.array(x, np.uint64, ndmin=1)
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))


def emitter_keys(mesh, triangle, kx, ky, lattice: int = 0) -> np.ndarray:
    """(n,) uint64 keys naming emitters by what they are: the crossing of the bin (``kx``,
    ``ky``)'s ray (signed ints) with triangle ``triangle`` of mesh ``mesh`` (ints, each (n,)),
    found from pupil ``lattice`` (:mod:`.parts`: several pupils find one set). Each field is
    folded in through :func:`_mix`, so the keys of distinct crossings differ but by a 64-bit
    hash collision (about n²/2⁶⁵: 3e-8 for a million emitters)."""
    key = np.full(np.shape(kx), _mix(np.uint64(lattice))[0], np.uint64)
    for field in (mesh, triangle, kx, ky):
        key = _mix(key ^ (np.asarray(field, np.int64).view(np.uint64) + _GOLDEN))
    return key


def random_phases(key, seed: int) -> np.ndarray:
    """Random phases [rad] in [0, 2π) (n,) float64 of the emitters ``key`` (n,) uint64
    (:func:`emitter_keys`) for ``seed``: a counter-based draw, each a hash of its own key and
    the seed alone (SplitMix64), uniform to 2⁻⁵³, so an emitter's phase does not depend on
    which other emitters there are or in what order they come."""
    mixed = _mix(np.asarray(key, np.uint64) ^ _mix(_mix(np.uint64(seed % 2**64)) + _GOLDEN)[0])
    return (mixed >> np.uint64(11)).astype(np.float64) * (2 * math.pi / 2.0**53)


def _points(hits, centre, rotation, spacing) -> np.ndarray:
    """The crossings' points [m] in the plate's frame."""
    tx, ty = bin_rays(hits.kx, hits.ky, spacing)
    local = np.stack([tx, ty, -np.ones_like(tx)], -1) * hits.depth[:, None]
    return local @ rotation.T + centre


def visibility(
    meshes, position, normal, zone: ViewingZone, rotation, spacing, g, *, closed=None, rt=None
):
    """(grid offsets ((x0, step_x), (y0, step_y)) [m], (n, gy, gx) visibility in [0, 1]) of
    the points ``position`` (n, 3) on surfaces of ``normal`` from the g = (gy, gx) points of
    the zone's centre plane (module docstring; ``emitters.cl``). ``closed`` (n,) bool: the
    points on a closed mesh, their normals outward (:func:`surface_points`), unseen from a
    grid point they face away from (None: none)."""
    rt = rt or get_runtime()
    centre = np.asarray(zone.centre, np.float64)
    hx, hy = zone.half_extents[:2]
    xs, ys = np.linspace(-hx, hx, g[1]), np.linspace(-hy, hy, g[0])
    vertices = np.concatenate([np.asarray(m.vertices, np.float64) for m in meshes])
    starts = np.cumsum([0] + [len(m.vertices) for m in meshes])
    triangles = np.concatenate([np.asarray(m.triangles) + s for m, s in zip(meshes, starts)])
    tri = rt.to_device(triangles.astype(np.int32))
    n = len(position)
    seen = rt.to_device(np.zeros(g[0] * g[1] * max(n, 1), np.float32))
    # the emitters from the zone's centre, and their normals, handed over once for all pupils
    offsets = dict(
        zip(
            ("px", "py", "pz"),
            (rt.to_device(a, np.float32) for a in (np.asarray(position, np.float64) - centre).T),
        )
    )
    normals = dict(
        zip(
            ("nx", "ny", "nz"),
            (rt.to_device(a, np.float32) for a in np.asarray(normal, np.float64).T),
        )
    )
    axes = rt.to_device(np.asarray(rotation, np.float64).ravel(), np.float32)  # its rows
    flags = np.zeros(max(n, 1), np.uint8)
    if closed is not None and n:
        flags[:n] = np.asarray(closed, bool)
    closed = rt.to_device(flags)
    for iy, y in enumerate(ys):
        for ix, x in enumerate(xs):
            eye = centre + (x, y, 0.0)
            h, w = bins_covering(vertices, eye, rotation, spacing)
            zbuf = rt.to_device(np.full(h * w, np.inf, np.float32))
            v = (vertices - eye) @ rotation
            d = -v[:, 2]
            t = v[:, :2] / np.where(d > 1e-9, d, 1)[:, None]
            DEPTH_RASTER.launch(
                rt,
                (len(triangles),),
                zbuf=zbuf,
                h=h,
                w=w,
                b=spacing,
                tx=rt.to_device(t[:, 0], np.float32),
                ty=rt.to_device(t[:, 1], np.float32),
                d=rt.to_device(d, np.float32),
                tri=tri,
                triangles=len(triangles),
            )
            SEEN_FROM.launch(
                rt,
                (max(n, 1),),
                seen=seen,
                point=iy * g[1] + ix,
                zbuf=zbuf,
                h=h,
                w=w,
                b=spacing,
                **offsets,
                **normals,
                ex=x,
                ey=y,
                axes=axes,
                max_slope=MAX_SLOPE,
                bias_bins=BIAS_BINS,
                bias_depth=BIAS_DEPTH,
                closed=closed,
                emitters=n,
            )
    step = lambda a: float(a[1] - a[0]) if len(a) > 1 else 1.0  # noqa: E731
    table = read(seen)[: g[0] * g[1] * n].reshape(g[0], g[1], n).transpose(2, 0, 1)
    return ((float(xs[0]), step(xs)), (float(ys[0]), step(ys))), np.ascontiguousarray(table)
