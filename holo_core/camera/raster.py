"""The camera hologram's emitters: one per direction the pupil resolves.

- Emitters (:func:`rasterize`). The surfaces the camera sees, one emitter per bin: each bin's
  ray meets the nearest triangle (a depth buffer, perspective-correct attributes), which
  emits its colour from the hit point, at distance R, with a random phase per look (speckle
  is averaged over looks, Sect. VII-E). Bare points go to their nearest bin.
- The stage's entry (:func:`camera_emitters`): the optics chosen for the emitters' depths,
  then the emitters of the meshes and of bare points.
- Motion blur (:func:`across_shutter`). Meshes that move (``Mesh.motion``) are rasterized at
  times spread over the shutter, close enough that no vertex moves more than a bin (a fine
  pixel) from one to the next, and each time's emitters weigh 1/N: the image, its coverage
  and its depth pair are then the shutter's time average (the emitters are mutually
  incoherent), as a camera's exposure is. Each time costs a rasterization.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import validate
from ..optics.raster import bin_rays, crossing_chunks
from ..scene.camera import Camera
from ..scene.mesh import surface_colour
from ..validate import InputError
from .optics import PupilOptics, choose_optics


@dataclass(frozen=True, eq=False)
class Emitters:
    """One emitter per covered bin: ``index`` into the (h, w) spectrum in FFT order, planar
    ``depth`` and ray ``distance`` R [m], ``colour`` (n, 3) linear, ``coverage`` (n,) in [0, 1]
    (the partner's amplitude²), sorted by ``layer``; ``starts`` the first emitter of each."""

    index: np.ndarray
    depth: np.ndarray
    distance: np.ndarray
    colour: np.ndarray
    coverage: np.ndarray
    layer: np.ndarray
    starts: np.ndarray


def camera_space(camera: Camera, points) -> np.ndarray:
    """World points (N, 3) [m] in the camera's axes, relative to its pupil."""
    return (np.asarray(points, np.float64) - camera.position) @ camera.rotation


RASTER_CHUNK = 4_000_000  # bin-triangle pairs tested at once
# host bytes per triangle of the largest mesh while rasterizing (its projected corners and bin
# boxes), above the peak (docs, Performance)
TRIANGLE_BYTES = 1000
VERTEX_BYTES = 64  # per vertex: camera-space positions, depths, tangents
PAIR_BYTES = 100  # per bin-triangle pair of a chunk, above the peak (docs, Performance)


def raster_bytes(meshes, chunk=RASTER_CHUNK) -> float:
    """Host bytes :func:`rasterize` takes for ``meshes`` beyond the pupil's grid (one mesh is
    projected at a time, so the largest counts)."""
    largest = max(
        (TRIANGLE_BYTES * len(m.triangles) + VERTEX_BYTES * len(m.vertices) for m in meshes),
        default=0,
    )
    return largest + PAIR_BYTES * chunk


def rasterize(meshes, camera: Camera, optics: PupilOptics, *, chunk=RASTER_CHUNK) -> Emitters:
    """The surfaces of ``meshes`` (world metres) the camera sees, one emitter per bin."""
    h, w = optics.shape
    zbuf = np.full(h * w, np.inf)
    owner = np.full(h * w, -1, np.int64)  # (mesh, triangle) packed
    bary = np.zeros((h * w, 2), np.float32)
    meshes = list(meshes)
    for kx, ky, depth, mesh, triangle, weights in crossing_chunks(
        meshes, camera.position, camera.rotation, optics.bin, (h, w), chunk
    ):
        flat = (ky % h) * w + kx % w
        order = np.lexsort((depth, flat))  # nearest first within each bin
        flat, depth = flat[order], depth[order]
        first = np.ones(len(flat), bool)
        first[1:] = flat[1:] != flat[:-1]
        sel = order[first]
        flat, depth = flat[first], depth[first]
        nearer = depth < zbuf[flat]
        flat, sel = flat[nearer], sel[nearer]
        zbuf[flat] = depth[nearer]
        owner[flat] = (mesh[sel] << 40) | triangle[sel]
        bary[flat] = weights[sel, 1:]  # perspective-correct: λ_i/d_i over Σ λ_j/d_j
    covered = np.nonzero(owner >= 0)[0]
    return _emitters(meshes, covered, owner[covered], bary[covered], zbuf[covered], optics)


def _emitters(meshes, covered, owner, bary, depth, optics: PupilOptics) -> Emitters:
    h, w = optics.shape
    colour = np.ones((len(covered), 3))
    mesh_of, tri_of = owner >> 40, owner & ((1 << 40) - 1)
    for m, mesh in enumerate(meshes):
        sel = mesh_of == m
        if not sel.any():
            continue
        corners = np.asarray(mesh.triangles)[tri_of[sel]]
        lam = bary[sel].astype(np.float64)
        weights = np.stack([1 - lam.sum(1), lam[:, 0], lam[:, 1]], -1)
        c = surface_colour(mesh, corners, weights, 3)
        colour[sel] = c if c.shape[1] == 3 else np.repeat(c.mean(1, keepdims=True), 3, 1)
    ky, kx = grid_indices(covered, optics.shape)
    return _sorted_emitters(
        covered, depth, _ray_distance(kx, ky, depth, optics), colour, np.ones(len(covered)), optics
    )


def _ray_distance(kx, ky, depth, optics: PupilOptics) -> np.ndarray:
    """The distance R [m] along the ray of bin (kx, ky) to its planar ``depth`` [m]."""
    tx, ty = bin_rays(kx, ky, optics.bin)
    return depth * np.sqrt(1 + tx * tx + ty * ty)


def grid_indices(flat, shape):
    """Signed (row, col) bin indices of flat FFT-order indices."""
    h, w = shape
    r, c = np.divmod(np.asarray(flat), w)
    return np.where(r > (h - 1) // 2, r - h, r), np.where(c > (w - 1) // 2, c - w, c)


def layer_of(optics: PupilOptics, depth) -> np.ndarray:
    """Index of the depth layer of ``optics`` each planar ``depth`` [m] belongs to (nearest
    in 1/z)."""
    if not len(depth):
        return np.zeros(0, np.int64)
    inv = 1 / np.asarray(optics.layers)
    return np.argmin(np.abs(1 / np.asarray(depth)[:, None] - inv[None, :]), axis=1)


def _sorted_emitters(index, depth, distance, colour, coverage, optics, layer=None):
    if layer is None:
        layer = layer_of(optics, depth)
    order = np.argsort(layer, kind="stable")
    starts = np.searchsorted(layer[order], np.arange(len(optics.layers) + 1))
    return Emitters(
        index=index[order],
        depth=depth[order],
        distance=distance[order],
        colour=np.clip(colour[order], 0, None),
        coverage=coverage[order],
        layer=layer[order],
        starts=starts,
    )


def point_emitters(positions, colours, camera: Camera, optics: PupilOptics) -> Emitters:
    """Bare points (N, 3) [m] with linear colours (N, 3), each at its nearest bin: within half
    a bin b/2 = Δ/(2s) of its direction (points that share a bin add their intensities; its
    depth is their intensity-weighted mean)."""
    local = camera_space(camera, positions)
    front = local[:, 2] < 0
    local, col = local[front], np.asarray(colours, np.float64).reshape(-1, 3)[front]
    r = np.linalg.norm(local, axis=1)
    kx = np.rint(-local[:, 0] / r / optics.bin).astype(np.int64)
    ky = np.rint(-local[:, 1] / r / optics.bin).astype(np.int64)
    h, w = optics.shape
    inside = (np.abs(kx) <= (w - 1) // 2) & (np.abs(ky) <= (h - 1) // 2)
    kx, ky, col, depth = kx[inside], ky[inside], col[inside], -local[inside, 2]
    dist = _ray_distance(kx, ky, depth, optics)
    index, inverse = np.unique((ky % h) * w + kx % w, return_inverse=True)
    weight = col.sum(1) + 1e-30
    summed = np.stack([np.bincount(inverse, col[:, c]) for c in range(3)], -1)
    mean = lambda a: np.bincount(inverse, a * weight) / np.bincount(inverse, weight)  # noqa: E731
    return _sorted_emitters(index, mean(depth), mean(dist), summed, np.ones(len(index)), optics)


MOTION_STEP = 1.0  # bins a vertex may move between two of the shutter's times
MAX_TIMES = 256  # times across the shutter, at most
DENSE_CELLS = 1 << 23  # (layer, bin) cells summed in dense grids, at most (six of 64 MiB)


def shutter_times(meshes, camera: Camera, optics: PupilOptics) -> np.ndarray:
    """Times in (0, 1) across the shutter at which moving ``meshes`` are rasterized: the
    midpoints of N equal intervals, N a multiple of the motion steps' intervals such that no
    vertex moves more than :data:`MOTION_STEP` bins between two times (one time, 0.5, when
    nothing moves)."""
    moving = [m.motion for m in meshes if m.motion is not None]
    if not moving:
        return np.array([0.5])
    per = 1
    for motion in moving:
        k = len(motion) - 1
        local = camera_space(camera, motion.reshape(-1, 3)).reshape(motion.shape)
        d = np.maximum(-local[..., 2], 1e-9)
        t = local[..., :2] / d[..., None]
        n = np.sqrt(1 + (t**2).sum(-1))[..., None]
        bins = -t / n / optics.bin
        jump = float(np.abs(np.diff(bins, axis=0)).max(initial=0))
        per = max(per, k * math.ceil(jump / MOTION_STEP))
    count = per
    if count > MAX_TIMES:
        validate.warn_sampling(
            f"the motion across the shutter needs {count} times to stay "
            f"within {MOTION_STEP} fine pixel a step; using {MAX_TIMES} "
            f"(the blur may show steps)"
        )
        count = MAX_TIMES
    return (np.arange(count) + 0.5) / count


def across_shutter(meshes, camera: Camera, optics: PupilOptics) -> Emitters | None:
    """The emitters of ``meshes`` averaged over the shutter (module docstring): each bin's
    emitters of all times summed with weight 1/N in colour and coverage, their depth and
    distance the coverage-weighted mean, per depth layer. Without motion, :func:`rasterize`."""
    times = shutter_times(meshes, camera, optics)
    if len(times) == 1:
        return rasterize(meshes, camera, optics)
    size = math.prod(optics.shape)
    cells = len(optics.layers) * size
    w = 1 / len(times)
    # each time's emitters hold one (layer, bin) each: summed where they land, into dense
    # grids where those fit (a layer of a 720p frame's pupil: 1.1e6 cells), else by key
    sums = np.zeros((6, cells)) if cells <= DENSE_CELLS else None
    parts = []
    for t in times:
        p = rasterize([m.at_shutter(t) for m in meshes], camera, optics)
        if not len(p.index):
            continue
        key, c = p.layer * size + p.index, p.coverage * w
        rows = (c, p.depth * c, p.distance * c, *(p.colour.T * w))
        if sums is None:
            parts.append((key, np.stack(rows)))
        else:
            sums[:, key] += rows
    if sums is not None:
        keys = np.nonzero(sums[0])[0]
        sums = sums[:, keys]
    elif parts:
        keys, inverse = np.unique(np.concatenate([k for k, _ in parts]), return_inverse=True)
        rows = np.concatenate([r for _, r in parts], axis=1)
        sums = np.stack([np.bincount(inverse, row) for row in rows])
    else:
        return None
    if not len(keys):
        return None
    cover = sums[0]
    weight = np.maximum(cover, 1e-300)
    return _sorted_emitters(
        keys % size,
        sums[1] / weight,
        sums[2] / weight,
        sums[3:].T,
        cover,
        optics,
        layer=keys // size,
    )


def camera_emitters(
    meshes, points, camera: Camera, *, supersample, pupil_diameter=None
) -> tuple[PupilOptics, Emitters]:
    """(the optics, the emitters) of ``meshes`` (a list of Mesh, across the shutter where they
    move) and bare ``points`` ((positions (N, 3) [m], colours (N, 3)) or None) seen by
    ``camera``: the optics chosen for their depths (:func:`.optics.choose_optics`, at
    ``supersample`` fine pixels per pixel, ``pupil_diameter`` [m] or the camera's), then one
    emitter per bin. The host's memory for the meshes' rasterization (:func:`raster_bytes`)
    is the caller's to check first (:func:`holo_core.camera.render.render_camera` does)."""
    pos, colours = (None, None) if points is None else points
    near_far = depth_range(meshes, camera, pos)
    optics = choose_optics(camera, near_far, supersample=supersample, pupil_diameter=pupil_diameter)
    em = across_shutter(meshes, camera, optics) if meshes else None
    if pos is not None:
        em = merged(em, point_emitters(pos, colours, camera, optics), optics)
    if em is None or not len(em.index):
        raise InputError("no emitter is visible to the camera")
    return optics, em


def depth_range(meshes, camera: Camera, points=None) -> tuple[float, float]:
    """(near, far) planar depths [m] of the emitters in front of ``camera`` (across the
    shutter, for meshes that move)."""
    zs = [
        -camera_space(camera, m.vertices if m.motion is None else m.motion.reshape(-1, 3))[:, 2]
        for m in meshes
    ]
    if points is not None and len(points):
        zs.append(-camera_space(camera, points)[:, 2])
    z = np.concatenate(zs) if zs else np.zeros(0)
    z = z[z > 0]
    if not len(z):
        raise InputError("no emitter lies in front of the camera")
    return float(z.min()), float(z.max())


def merged(a: Emitters | None, b: Emitters, optics) -> Emitters:
    if a is None:
        return b
    cat = [
        np.concatenate([getattr(a, k), getattr(b, k)])
        for k in ("index", "depth", "distance", "colour", "coverage")
    ]
    return _sorted_emitters(*cat, optics)
