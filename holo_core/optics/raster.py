"""Rays through a pupil's bins and the surfaces they cross (a depth-buffered raster).

A pupil's spectrum bin (kx, ky) at spacing b in direction cosine is one direction of arrival,
α = kx·b, β = ky·b (Eq. 22); its ray leaves the pupil's centre along −(α, β, γ). Both the
camera hologram (one emitter where each bin's ray meets the nearest surface) and the plate
(emitters on every surface a bin's ray crosses, seen from the zone's centre) raster meshes
onto these rays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def bin_rays(kx, ky, b):
    """View tangents (t_x, t_y) of the rays of bins (kx, ky) (signed indices)."""
    alpha, beta = kx * b, ky * b
    gamma = np.sqrt(np.clip(1 - alpha * alpha - beta * beta, 1e-12, None))
    return -alpha / gamma, -beta / gamma


def bin_boxes(tris, b, h, w):
    """Bin ranges (kx0, kx1, ky0, ky1) that may hold each projected triangle (T, 3, 2) of view
    tangents: its edges sampled, as direction cosines bend them, plus one bin."""
    s = np.linspace(0, 1, 9)[:, None]
    pts = np.concatenate(
        [
            tris[:, i : i + 1] * (1 - s) + tris[:, (i + 1) % 3 : (i + 1) % 3 + 1] * s
            for i in range(3)
        ],
        1,
    )
    n = np.sqrt(1 + (pts**2).sum(-1))
    kx, ky = -pts[..., 0] / n / b, -pts[..., 1] / n / b
    box = np.stack(
        [
            np.floor(kx.min(1)) - 1,
            np.ceil(kx.max(1)) + 1,
            np.floor(ky.min(1)) - 1,
            np.ceil(ky.max(1)) + 1,
        ],
        1,
    )
    lim = np.array([-(w // 2), (w - 1) // 2, -(h // 2), (h - 1) // 2])
    box[:, 0::2] = np.maximum(box[:, 0::2], lim[0::2])
    box[:, 1::2] = np.minimum(box[:, 1::2], lim[1::2])
    return box.astype(np.int64)


@dataclass(frozen=True, eq=False)
class Crossings:
    """Where bins' rays cross triangles: signed bins ``kx``, ``ky``, planar ``depth`` [m],
    ``mesh`` and ``triangle`` indices, perspective-correct barycentric ``bary`` (n, 3), and
    ``layer``: 0 for the nearest crossing of its bin, 1 for the next, …"""

    kx: np.ndarray
    ky: np.ndarray
    depth: np.ndarray
    mesh: np.ndarray
    triangle: np.ndarray
    bary: np.ndarray
    layer: np.ndarray

    def __len__(self) -> int:
        return len(self.depth)


def crossings(
    meshes, position, rotation, b, shape, *, layers=1, chunk=2_000_000, coincident=1e-6
) -> Crossings:
    """The first ``layers`` surfaces each bin's ray crosses (nearest first) for a pupil at
    ``position`` [m] with axes ``rotation`` (columns X right, Y up, Z back, world frame) and
    bins ``b`` apart on a grid of ``shape`` (h, w); crossings within ``coincident``·depth of
    the previous one (two surfaces that meet, a face listed twice; a ray through an edge two
    triangles share already crosses one of them, :func:`_inside`) count once."""
    h, w = shape
    parts = list(crossing_chunks(meshes, position, rotation, b, shape, chunk))
    if not parts:
        empty = np.zeros(0)
        return Crossings(
            empty.astype(np.int64),
            empty.astype(np.int64),
            empty,
            empty.astype(np.int64),
            empty.astype(np.int64),
            np.zeros((0, 3)),
            empty.astype(np.int64),
        )
    kx, ky, depth, mesh, tri_id, bary = (np.concatenate([p[i] for p in parts]) for i in range(6))
    flat = (ky % h) * w + kx % w
    order = np.lexsort((depth, flat))
    flat, depth = flat[order], depth[order]
    same_bin = np.r_[False, flat[1:] == flat[:-1]]
    repeat = same_bin & (np.r_[np.inf, np.diff(depth)] <= coincident * depth)
    kept = order[~repeat]
    flat, depth, same_bin = flat[~repeat], depth[~repeat], same_bin[~repeat]
    start = np.maximum.accumulate(np.where(same_bin, 0, np.arange(len(flat))))
    layer = np.arange(len(flat)) - start
    inside = layer < layers
    kept = kept[inside]
    return Crossings(
        kx[kept], ky[kept], depth[inside], mesh[kept], tri_id[kept], bary[kept], layer[inside]
    )


CROSSING_BYTES = (
    176  # host bytes a crossing holds in crossings(): its chunk's fields, joined, sorted
)


def crossing_count(meshes, position, rotation, b) -> float:
    """How many crossings :func:`crossings` finds before it keeps its layers (every
    triangle's, hidden or not), for a pupil at ``position`` [m] with axes ``rotation`` and
    bins ``b`` apart: the triangles' areas in direction cosine over b², counted before the
    work (a mesh of many large triangles crossing each other holds far more than its
    surface seen once)."""
    total = 0.0
    for mesh in meshes:
        v = (np.asarray(mesh.vertices, np.float64) - position) @ rotation
        r = np.linalg.norm(v, axis=1)
        u = v[:, :2] / np.where(r > 0, r, 1)[:, None]
        tri = np.asarray(mesh.triangles)
        front = (v[:, 2][tri] < -1e-9).all(1)
        p0, p1, p2 = (u[tri[front, i]] for i in range(3))
        total += 0.5 * float(
            np.abs(
                (p1[:, 0] - p0[:, 0]) * (p2[:, 1] - p0[:, 1])
                - (p2[:, 0] - p0[:, 0]) * (p1[:, 1] - p0[:, 1])
            ).sum()
        )
    return total / b**2


def crossing_chunks(meshes, position, rotation, b, shape, chunk):
    """Every crossing of the bins' rays with the meshes' triangles, a chunk of at most
    ``chunk`` bin-triangle pairs at a time: tuples (kx, ky, planar depth [m], mesh index,
    triangle index, perspective-correct barycentrics (n, 3)) (:func:`_chunk`)."""
    h, w = shape
    for m, mesh in enumerate(meshes):
        v = (np.asarray(mesh.vertices, np.float64) - position) @ rotation
        tri = np.asarray(mesh.triangles)
        d = -v[:, 2]
        t = v[:, :2] / np.where(d > 1e-9, d, 1)[:, None]
        p0, p1, p2 = (t[tri[:, i]] for i in range(3))
        area = (p1[:, 0] - p0[:, 0]) * (p2[:, 1] - p0[:, 1]) - (p2[:, 0] - p0[:, 0]) * (
            p1[:, 1] - p0[:, 1]
        )
        ids = np.nonzero((d[tri] > 1e-9).all(1) & (area != 0))[0]
        if not len(ids):
            continue
        box = bin_boxes(t[tri[ids]], b, h, w)
        keep = (box[:, 1] >= box[:, 0]) & (box[:, 3] >= box[:, 2])
        ids, box = ids[keep], box[keep]
        sizes = (box[:, 1] - box[:, 0] + 1) * (box[:, 3] - box[:, 2] + 1)
        ends = np.cumsum(sizes)
        lo = 0
        while lo < len(ids):
            hi = max(lo + 1, int(np.searchsorted(ends, (ends[lo - 1] if lo else 0) + chunk)))
            part = _chunk(ids[lo:hi], box[lo:hi], sizes[lo:hi], tri, t, d, b, m)
            if part is not None:
                yield part
            lo = hi


def _chunk(ids, box, sizes, tri, t, d, b, m):
    """Every crossing of the bins in ``box`` with the triangles ``ids`` (mesh ``m``)."""
    total = int(sizes.sum())
    which = np.repeat(np.arange(len(ids)), sizes)
    q = np.arange(total) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    width = (box[:, 1] - box[:, 0] + 1)[which]
    kx = box[which, 0] + q % width
    ky = box[which, 2] + q // width
    tx, ty = bin_rays(kx, ky, b)
    corners = tri[ids][which]
    p0, p1, p2 = (t[corners[:, i]] for i in range(3))
    l1, l2, inside = _inside(p0, p1, p2, tx, ty)
    if not inside.any():
        return None
    l1, l2, corners, which = l1[inside], l2[inside], corners[inside], which[inside]
    inv = (1 - l1 - l2) / d[corners[:, 0]] + l1 / d[corners[:, 1]] + l2 / d[corners[:, 2]]
    w1 = l1 / d[corners[:, 1]] / inv
    w2 = l2 / d[corners[:, 2]] / inv
    bary = np.stack([1 - w1 - w2, w1, w2], -1)
    return (kx[inside], ky[inside], 1 / inv, np.full(len(inv), m), ids[which], bary)


def _edge(p, q, tx, ty):
    """The edge function of the edge p–q (n, 2) at the rays (tx, ty): twice the signed area of
    (p, q, ray), evaluated from the endpoint that comes first in (x, y) order, so that the
    two triangles sharing the edge get the same number, one with each sign."""
    swap = (p[:, 0] > q[:, 0]) | ((p[:, 0] == q[:, 0]) & (p[:, 1] > q[:, 1]))
    u = np.where(swap[:, None], q, p)
    v = np.where(swap[:, None], p, q)
    e = (v[:, 0] - u[:, 0]) * (ty - u[:, 1]) - (v[:, 1] - u[:, 1]) * (tx - u[:, 0])
    return np.where(swap, -e, e)


def _inside(p0, p1, p2, tx, ty):
    """(barycentrics l1, l2 (n,) in view tangents, inside (n,) bool) of the rays (tx, ty) in
    the projected triangles (p0, p1, p2) (n, 2) each. Watertight: a ray through an edge two
    triangles share is inside exactly one of them. Each edge's function is evaluated the
    same way by both triangles (:func:`_edge`), and a ray exactly on an edge belongs to the
    triangle on whose top or left side it lies (counter-clockwise: the edge runs down, or
    runs left level); ``emitters.cl``'s depth raster keeps the same rule. Testing
    barycentrics divided by each triangle's own area instead lets rounding put a ray on a
    shared edge outside both: a crack that light leaks through."""
    area = (p1[:, 0] - p0[:, 0]) * (p2[:, 1] - p0[:, 1]) - (p2[:, 0] - p0[:, 0]) * (
        p1[:, 1] - p0[:, 1]
    )
    s = np.sign(area)
    inside = area != 0
    weights = []
    for a, b in ((p1, p2), (p2, p0), (p0, p1)):  # the edges facing p0, p1, p2
        w = s * _edge(a, b, tx, ty)
        dx, dy = s * (b[:, 0] - a[:, 0]), s * (b[:, 1] - a[:, 1])
        top_left = (dy < 0) | ((dy == 0) & (dx < 0))
        inside &= (w > 0) | ((w == 0) & top_left)
        weights.append(w)
    total = np.where(inside, weights[0] + weights[1] + weights[2], 1)
    return weights[1] / total, weights[2] / total, inside
