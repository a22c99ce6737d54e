"""The object wave of meshes with occlusion: emitters on depth slabs and silhouette masks.

Matsushima's silhouette method, per slab of depth. The field is carried from the farthest slab
to the nearest by the angular spectrum; at each slab the objects' silhouette there (the nodes
whose ray from the zone's centre passes through a closed mesh's interior, or an open mesh's
surface, within the slab) is cut out of the light arriving from behind, and the slab's own
emitters are added. Light is stopped by what lies in front of it along every direction the
plate carries, so each camera in the viewing zone sees the occlusion from its own viewpoint,
with parallax, from one recording: exactly from the zone's centre, and with an occluding edge
moved by at most half a slab times the zone's angular half width from anywhere else in it
(the plan keeps that within a resolved spot).

Emitters (:func:`lattice_emitters`): where the rays from the zone's centre through a lattice
of directions, one resolved spot apart, cross the surfaces (one per spot, as the camera
hologram has one per bin; the surfaces hidden from the centre too), on the faces turned
towards the zone (a point on a far face would shine past the silhouette, where a surface sends
no light). Each is moved along its ray onto its slab's plane, to the nearest node, with the
phase of the distance it moved (from the centre it is where it was, and in phase), and a random
phase (a diffuse surface; the depth partner shares it). A node of value v on a grid of pitch p
radiates v·p²/(iλ)·e^{ikr}/r (Eq. 7), so v = i·√I·λ/p² is the point source √I·e^{ikr}/r of
``point_sources.py``.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from .. import jobs, memory
from ..propagation import angular_spectrum
from ..scene.mesh import Mesh, surface_colour
from ..validate import InputError

log = logging.getLogger(__name__)
CHUNK = 4_000_000     # candidate nodes rasterised at once
NUDGE = 1.234567e-6   # node positions are nudged by this many pitches: none falls on an edge


class SlabGrid:
    """The lattice the slabs are sampled on: the plate's own nodes (column j at
    x = (j − (W−1)/2)·pitch), extended beyond the plate where the objects' light spreads:
    ``origin`` (row, col) of its node (0, 0) in the plate's indices, ``shape`` (rows, cols)."""

    def __init__(self, plate_shape, pitch, origin, shape):
        self.plate_shape, self.pitch = tuple(plate_shape), float(pitch)
        self.origin, self.shape = tuple(origin), tuple(shape)

    @classmethod
    def covering(cls, plate_shape, pitch, lo, hi):
        """The grid of the plate's lattice that covers [lo, hi] (x, y) [m]."""
        h, w = plate_shape
        c0 = math.floor(lo[0] / pitch + (w - 1) / 2)
        c1 = math.ceil(hi[0] / pitch + (w - 1) / 2)
        r0 = math.floor(lo[1] / pitch + (h - 1) / 2)
        r1 = math.ceil(hi[1] / pitch + (h - 1) / 2)
        return cls(plate_shape, pitch, (r0, c0), (r1 - r0 + 1, c1 - c0 + 1))

    def xy(self):
        """(x of each column, y of each row) [m] of the grid's nodes."""
        (h, w), (r0, c0), (n_r, n_c) = self.plate_shape, self.origin, self.shape
        x = (np.arange(n_c) + c0 - (w - 1) / 2) * self.pitch
        y = (np.arange(n_r) + r0 - (h - 1) / 2) * self.pitch
        return x, y

    def nearest(self, points) -> tuple[np.ndarray, np.ndarray]:
        """(flat node index, inside) of the nodes nearest to ``points`` (N, 2|3) [m]."""
        (h, w), (r0, c0), (n_r, n_c) = self.plate_shape, self.origin, self.shape
        c = np.rint(points[:, 0] / self.pitch + (w - 1) / 2).astype(np.int64) - c0
        r = np.rint(points[:, 1] / self.pitch + (h - 1) / 2).astype(np.int64) - r0
        inside = (c >= 0) & (c < n_c) & (r >= 0) & (r < n_r)
        return np.where(inside, r * n_c + c, 0), inside


def raster(triangles, u, v, cols, rows):
    """The integer nodes (col, row) in [0, cols) × [0, rows) inside each triangle of
    ``triangles`` (T, 3) whose corners lie at (``u``, ``v``) in node units (nodes exactly on an
    edge are avoided by the callers' nudge): (col, row, triangle, l1, l2), l1 and l2 the
    barycentric weights of the second and third corners."""
    tu, tv = u[triangles], v[triangles]
    c0 = np.clip(np.ceil(tu.min(1)), 0, cols).astype(np.int64)
    c1 = np.clip(np.floor(tu.max(1)), -1, cols - 1).astype(np.int64)
    r0 = np.clip(np.ceil(tv.min(1)), 0, rows).astype(np.int64)
    r1 = np.clip(np.floor(tv.max(1)), -1, rows - 1).astype(np.int64)
    ids = np.nonzero((c1 >= c0) & (r1 >= r0))[0]
    sizes = (c1 - c0 + 1)[ids] * (r1 - r0 + 1)[ids]
    ends = np.cumsum(sizes)
    out = []
    lo = 0
    while lo < len(ids):
        hi = max(lo + 1, int(np.searchsorted(ends, (ends[lo - 1] if lo else 0) + CHUNK)))
        sel, sz = ids[lo:hi], sizes[lo:hi]
        which = np.repeat(np.arange(len(sel)), sz)
        q = np.arange(int(sz.sum())) - np.repeat(np.cumsum(sz) - sz, sz)
        width = (c1 - c0 + 1)[sel][which]
        cc = c0[sel][which] + q % width
        rr = r0[sel][which] + q // width
        a, b, c = (np.stack([tu[sel, i], tv[sel, i]], -1)[which] for i in range(3))
        area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
        l1 = ((cc - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (rr - a[:, 1]))
        l2 = ((b[:, 0] - a[:, 0]) * (rr - a[:, 1]) - (cc - a[:, 0]) * (b[:, 1] - a[:, 1]))
        with np.errstate(divide="ignore", invalid="ignore"):
            l1, l2 = l1 / area, l2 / area
            inside = (area != 0) & (l1 >= 0) & (l2 >= 0) & (l1 + l2 <= 1)
        out.append((cc[inside], rr[inside], sel[which[inside]], l1[inside], l2[inside]))
        lo = hi
    if not out:
        return (np.zeros(0, np.int64),) * 3 + (np.zeros(0),) * 2
    return tuple(np.concatenate(parts) for parts in zip(*out))


def ray_crossings(mesh: Mesh, centre, step):
    """Where the rays from ``centre`` (3,) [m] through a lattice of view tangents ``step``
    apart cross ``mesh`` (plate frame): (cell (N, 2) int, depth z (N,) [m]) of each crossing
    (perspective-correct)."""
    d = centre[2] - mesh.vertices[:, 2]
    if (d <= 0).any():
        raise InputError("the objects must lie behind the viewing zone's centre")
    tu = (mesh.vertices[:, 0] - centre[0]) / d / step - NUDGE
    tv = (mesh.vertices[:, 1] - centre[1]) / d / step - NUDGE * math.pi
    i0, j0 = math.floor(tu.min()), math.floor(tv.min())
    cols, rows = math.ceil(tu.max()) - i0 + 1, math.ceil(tv.max()) - j0 + 1
    cc, rr, tri, l1, l2 = raster(mesh.triangles, tu - i0, tv - j0, cols, rows)
    corners = mesh.triangles[tri]
    inv = 1 / d[corners]
    w = np.stack([(1 - l1 - l2) * inv[:, 0], l1 * inv[:, 1], l2 * inv[:, 2]], -1)
    depth = 1 / w.sum(1)  # the distance along z from the centre's plane
    return np.stack([cc + i0, rr + j0], -1), centre[2] - depth, tri, w * depth[:, None]


def lattice_emitters(mesh: Mesh, centre, step):
    """Emitters where the rays from ``centre`` (3,) [m] through a lattice of directions,
    ``step`` [rad] apart in view tangent, cross ``mesh`` (every crossing, hidden ones too:
    the zone's other points see past what hides them from its centre). Returns (positions
    (N, 3) [m], colours (N, 3), lattice cells (N, 2) int, triangles (N,)): one emitter per
    direction of the zone's resolution on each surface, as the camera hologram has one per
    bin."""
    cells, _, tri, w = ray_crossings(mesh, centre, step)
    corners = mesh.triangles[tri]
    pos = np.einsum("nk,nkd->nd", w, mesh.vertices[corners])
    colour = surface_colour(mesh, corners, w, 3)
    if colour.shape[1] != 3:
        colour = np.repeat(colour.mean(1, keepdims=True), 3, 1)
    return pos, colour, cells, tri


def is_closed(mesh: Mesh) -> bool:
    """Whether every edge of ``mesh`` is shared by exactly two triangles (it bounds a solid),
    its corners welded by position (a texture's seams split vertices, not the surface);
    degenerate triangles (a UV sphere's poles) are left out."""
    scale = float(np.ptp(mesh.vertices, axis=0).max()) or 1.0
    _, weld = np.unique(np.round(mesh.vertices / (1e-9 * scale)).astype(np.int64), axis=0,
                        return_inverse=True)
    t = weld.reshape(-1)[mesh.triangles]
    t = t[(t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 2] != t[:, 0])]
    edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    if not len(edges):
        return False
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool((counts == 2).all())


def occupied_intervals(mesh: Mesh, centre, step):
    """(cell (N, 2), z_from, z_to) [m] of the depth intervals ``mesh`` occupies along the rays
    from ``centre`` through the tangent lattice ``step`` apart (:func:`ray_crossings`): its
    interior between pairs of crossings for a closed mesh, each crossing (a surface of no
    thickness) for an open one."""
    cells, z, _, _ = ray_crossings(mesh, centre, step)
    if not is_closed(mesh) or not len(z):
        return cells, z, z
    key = (cells[:, 1] - cells[:, 1].min()) * (np.ptp(cells[:, 0]) + 1) \
        + cells[:, 0] - cells[:, 0].min()
    order = np.lexsort((z, key))
    key, z, cells = key[order], z[order], cells[order]
    first = np.ones(len(key), bool)
    first[1:] = key[1:] != key[:-1]
    rank = np.arange(len(key)) - np.maximum.accumulate(np.where(first, np.arange(len(key)), 0))
    starts = rank % 2 == 0
    pair = np.nonzero(starts[:-1] & (key[1:] == key[:-1]))[0]  # an odd last crossing: alone
    lone = np.nonzero(starts & ~np.isin(np.arange(len(key)), pair))[0]
    return (np.concatenate([cells[pair], cells[lone]]), np.concatenate([z[pair], z[lone]]),
            np.concatenate([z[pair + 1], z[lone]]))


class SlabMasks:
    """The objects' silhouettes on each slab's plane as seen from the zone's centre: the nodes
    whose ray from the centre passes through an object within the slab's depth. Exact for a
    camera at the centre; one elsewhere in the zone sees an occluding edge move by at most
    half a slab times the zone's angular half-width (the plan keeps that within a spot)."""

    def __init__(self, meshes, centre, grid: SlabGrid, plane_z):
        self.centre, self.grid = np.asarray(centre, np.float64), grid
        self.step = grid.pitch / (self.centre[2] - float(np.mean(plane_z)))
        parts = [occupied_intervals(m, self.centre, self.step) for m in meshes]
        self.cells = np.concatenate([c for c, _, _ in parts]) if parts else np.zeros((0, 2))
        self.z_from = np.concatenate([a for _, a, _ in parts])
        self.z_to = np.concatenate([b for _, _, b in parts])
        self.lo = self.cells.min(0) if len(self.cells) else np.zeros(2, np.int64)
        self.size = (np.ptp(self.cells, axis=0) + 1) if len(self.cells) else np.ones(2, int)

    def nodes(self, bottom, top, plane) -> np.ndarray | None:
        """Flat indices of the slab grid's nodes masked on the plane at z = ``plane`` [m] for
        the slab [``bottom``, ``top``] [m], or None."""
        sel = (self.z_from <= top) & (self.z_to >= bottom)
        if not sel.any():
            return None
        image = np.zeros(self.size[::-1], bool)
        c = self.cells[sel] - self.lo
        image[c[:, 1], c[:, 0]] = True
        x, y = self.grid.xy()
        scale = 1 / ((self.centre[2] - plane) * self.step)
        u = np.rint((x - self.centre[0]) * scale).astype(np.int64) - self.lo[0]
        v = np.rint((y - self.centre[1]) * scale).astype(np.int64) - self.lo[1]
        cols = np.nonzero((u >= 0) & (u < self.size[0]))[0]
        rows = np.nonzero((v >= 0) & (v < self.size[1]))[0]
        if not len(cols) or not len(rows):
            return None
        hit = image[v[rows][:, None], u[cols][None, :]]
        r, q = np.nonzero(hit)
        return rows[r] * self.grid.shape[1] + cols[q]


def _facing_zone(mesh: Mesh, pos, colour, cells, tri, zone):
    """The emitters of a closed mesh whose face is turned towards some point of ``zone``: the
    others lie on its far side, where no camera of the zone sees them, and a point emitter
    there would shine past the silhouette where a surface sends no light (behind its own
    plane). Outwards is where the mesh's volume is positive (a consistent winding, either
    way round); an open mesh is a two-sided surface: all of it stays."""
    if not is_closed(mesh):
        return pos, colour, cells
    v = mesh.vertices[mesh.triangles] - mesh.vertices.mean(0)
    volume = np.einsum("nd,nd->", v[:, 0], np.cross(v[:, 1], v[:, 2]))
    normals = mesh.normals()[tri] * (1.0 if volume >= 0 else -1.0)  # outwards
    towards = np.einsum("nd,knd->kn", normals, zone.corners()[:, None, :] - pos[None])
    keep = (towards > 0).any(0)
    return pos[keep], colour[keep], cells[keep]


TRIANGLE_BYTES = 320  # host bytes per triangle of the meshes while recording in slabs
                      # (rasters along the zone's rays, the closed-surface test's edges,
                      # normals: measured 300-360)
VERTEX_BYTES = 96     # per vertex: the plate-frame copy, the welded positions


def mesh_bytes(meshes) -> float:
    """Host bytes a slab recording of ``meshes`` takes for their triangles and vertices
    (the plate's own fields are :meth:`~.sampling.PlatePlan.memory_bytes`)."""
    return sum(TRIANGLE_BYTES * len(m.triangles) + VERTEX_BYTES * len(m.vertices)
               for m in meshes)


def record_slabs(meshes, *, plan, wavelengths, seed=0, code=None,
                 progress: jobs.Progress = None):
    """The object waves (C, H, W) complex64 on the plate of ``meshes`` (each in the plate's
    frame, colours linear RGB) sampled as ``plan`` (:class:`~.sampling.PlatePlan`) says, one
    per wavelength of ``wavelengths`` (λ [m], channel role): the colour channels 'R', 'G',
    'B' at one wavelength and the depth partner 'Z' (unit intensity). The emitters are
    :func:`lattice_emitters` of the zone's centre. Returns (waves, emitters per m² of a
    surface facing the zone at ``plan.distance``)."""
    meshes = list(meshes)
    if not meshes:
        raise InputError("record_slabs needs at least one mesh")
    p = plan.pitch
    centre = np.asarray(plan.zone.centre, np.float64)
    parts = [_facing_zone(m, *lattice_emitters(m, centre, plan.step), plan.zone)
             for m in meshes]
    pos = np.concatenate([a for a, _, _ in parts])
    rgb = np.concatenate([c for _, c, _ in parts])
    cells = np.concatenate([c for _, _, c in parts])
    if not len(pos):
        raise InputError("no surface of the meshes faces the viewing zone")
    # one emitter per direction seen from the zone's centre: a surface at distance R holds
    # 1/(step·R)² per m² facing it; the intensities (R/R0)² make each direction's radiance
    # the surface's own, R0 = plan.distance, where the density is 1/(step·R0)²
    weight = (np.linalg.norm(pos - centre, axis=1) / plan.distance) ** 2
    phases = np.random.default_rng(seed).uniform(0, 2 * np.pi, len(pos))
    if code is not None:  # look k of m² whose cross terms cancel between neighbouring cells
        (k, m) = code
        phases = phases + 2 * np.pi * ((k // m) * cells[:, 0] + (k % m) * cells[:, 1]) / m
    density = 1 / (plan.step * plan.distance) ** 2
    lo, hi = np.asarray(plan.bounds)
    spread = (hi[2] - lo[2]) * plan.band / math.sqrt(1 - plan.band**2) + 8 * p
    grid = SlabGrid.covering(plan.shape, p, lo[:2] - spread, hi[:2] + spread)
    memory.check_host(f"the {grid.shape[1]}x{grid.shape[0]} slab grid's fields",
                      8.0 * (3 + 2 * 4) * math.prod(grid.shape))
    n_slabs = max(1, math.ceil((hi[2] - lo[2]) / plan.slab))
    thickness = max(hi[2] - lo[2], p) / n_slabs
    planes = lo[2] + (np.arange(n_slabs) + 0.5) * thickness
    slab_of = np.clip(((pos[:, 2] - lo[2]) / thickness).astype(np.int64), 0, n_slabs - 1)
    # each emitter moves along its ray from the zone's centre onto its slab's plane, with the
    # phase of the distance it moved: from the centre it is where it was, in phase
    ratio = (centre[2] - planes[slab_of]) / (centre[2] - pos[:, 2])
    moved = centre + (pos - centre) * ratio[:, None]
    shift = np.linalg.norm(pos - moved, axis=1) * np.sign(planes[slab_of] - pos[:, 2])
    node, keep = grid.nearest(moved)
    silhouettes = SlabMasks(meshes, centre, grid, planes)
    masks = [silhouettes.nodes(lo[2] + s * thickness, lo[2] + (s + 1) * thickness, planes[s])
             for s in range(n_slabs)]
    log.info("slabs: %d emitters %.3g rad apart seen from the zone, %d slabs %.3g m deep on a "
             "%dx%d grid", len(pos), plan.step, n_slabs, thickness, grid.shape[1], grid.shape[0])
    groups = {}
    for c, (lam, role) in enumerate(wavelengths):
        groups.setdefault(lam, []).append((c, role))
    waves = [None] * len(wavelengths)
    total = len(groups) * (n_slabs + 1)
    step = 0
    for lam, chans in groups.items():
        k = 2 * np.pi / lam
        # the emitters' values on their nodes: i·√I·λ/p²·e^{i(φ + k·moved)}
        base = 1j * lam / p**2 * np.exp(1j * (phases + np.remainder(k * shift, 2 * np.pi)))
        amps = [base * np.sqrt(weight * (1.0 if role == "Z" else rgb[:, "RGB".index(role)]))
                for _, role in chans]
        fields = np.zeros((len(chans),) + grid.shape, np.complex64)
        started, z_at = False, planes[0]
        for s in range(n_slabs):
            here = keep & (slab_of == s)
            if not here.any() and masks[s] is None:
                jobs.report(progress, step := step + 1, total)
                continue
            if started and planes[s] != z_at:
                step_padding = _padding(grid.shape, planes[s] - z_at, lam, p)
                for f in range(len(chans)):
                    fields[f] = angular_spectrum(fields[f], wavelength=lam, pitch=p,
                                                 distance=planes[s] - z_at,
                                                 padding=step_padding)
            z_at = planes[s]
            if masks[s] is not None and started:
                for f in range(len(chans)):
                    fields[f].ravel()[masks[s]] = 0
            if here.any():  # summed per node over the slab's emitters only, not the grid
                nodes, at = np.unique(node[here], return_inverse=True)
                for f, a in enumerate(amps):
                    v = a[here]
                    fields[f].ravel()[nodes] += (np.bincount(at, v.real, len(nodes))
                                                 + 1j * np.bincount(at, v.imag, len(nodes)))
                started = True
            jobs.report(progress, step := step + 1, total)
        for f, (c, _) in enumerate(chans):
            waves[c] = _to_plate(fields[f], grid, lam, -z_at)
        jobs.report(progress, step := step + 1, total)
    return np.stack(waves), density


def _padding(shape, distance, wavelength, pitch) -> float:
    """The zero-padding of a step of ``distance`` [m] between slabs: the light of the grid's
    edge spreads by at most distance·tan θ (θ the grid's widest direction), beyond which the
    field is empty (the grid's margin holds the spread of the objects' light), so a few
    samples more than that spread keep the convolution from wrapping around, where 2x would
    cost four times the FFTs."""
    s = min(0.99, math.sqrt(2) * wavelength / (2 * pitch))
    spread = abs(distance) * s / math.sqrt(1 - s * s) / pitch
    return min(2.0, 1 + (2 * spread + 16) / min(shape))


def _to_plate(field, grid: SlabGrid, wavelength, distance) -> np.ndarray:
    """The field on the slab grid carried ``distance`` [m] to the plate (complex64 (H, W)):
    both embedded in one window of the plate's lattice."""
    (h, w), (r0, c0), (n_r, n_c) = grid.plate_shape, grid.origin, grid.shape
    top, left = min(0, r0), min(0, c0)
    bottom, right = max(h, r0 + n_r), max(w, c0 + n_c)
    big = np.zeros((bottom - top, right - left), np.complex64)
    big[r0 - top:r0 - top + n_r, c0 - left:c0 - left + n_c] = field
    out = angular_spectrum(big, wavelength=wavelength, pitch=grid.pitch, distance=distance)
    return np.ascontiguousarray(out[-top:-top + h, -left:-left + w])
