"""Meshes and their point emitters (Sect. V-B).

Positions are metres; colours are linear intensities I per wavelength, and a point's amplitude
is A0 = √I (Sect. VII-B). Surfaces are sampled area-uniformly by a seeded generator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import preview, validate
from ..validate import InputError

MAX_SLANT = 30.0  # visibility: a surface's depth slope (tan of its incidence) is capped here (88°)
SAMPLING_STREAM = 0x5A4D  # seeds mesh sampling apart from the phases (see surface_samples)


@dataclass(frozen=True, eq=False, kw_only=True)
class Mesh:
    """A triangle mesh, optionally coloured, textured and moving over the shutter.

    Parameters
    ----------
    vertices : (V, 3) float array
        Vertex positions [m]; the frame's own time, where colours and textures are found.
    triangles : (T, 3) int array
        Vertex indices of each triangle.
    colours : (V, C) float array, optional
        Linear intensities per vertex and colour.
    uvs : (V, 2) float array, optional
        Texture coordinates.
    texture : (h, w, C) float array, optional
        The texture the ``uvs`` index.
    motion : (K, V, 3) float array, optional
        The vertices [m] at K >= 2 equally spaced times from the shutter's opening to its
        closing, between which the mesh moves linearly (as Cycles interpolates its motion
        steps); a render averages the image over the shutter (motion blur).

    Raises
    ------
    InputError
        Where an array has the wrong shape, is not finite, or an index is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import Mesh
    >>> Mesh(vertices=np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]),
    ...      triangles=np.array([[0, 1, 2]]))
    Mesh(1 triangle, 3 vertices, extent 1 m x 1 m x 0 m, no colours)
    """

    vertices: np.ndarray
    triangles: np.ndarray
    colours: np.ndarray | None = None
    uvs: np.ndarray | None = None
    texture: np.ndarray | None = None
    motion: np.ndarray | None = None

    def __post_init__(self):
        v = _numbers("vertices", self.vertices, "a finite (V, 3) array [m]")
        if v.ndim != 2 or v.shape[1] != 3 or not np.isfinite(v).all():
            raise InputError(f"vertices must be a finite (V, 3) array [m]; got shape {v.shape}")
        t = np.asarray(self.triangles)
        if t.ndim != 2 or t.shape[1] != 3 or (t.size and t.dtype.kind not in "iu"):
            raise InputError(
                f"triangles must be a (T, 3) array of integer vertex indices; got "
                f"shape {t.shape}, dtype {t.dtype}"
            )
        if not len(t):  # a stage would end in NumPy's reduction of an empty array
            raise InputError(
                f"triangles must hold at least one triangle (a Mesh is a "
                f"surface); got none, with {len(v)} vertices"
            )
        if t.min() < 0 or t.max() >= len(v):
            bad = t[(t < 0) | (t >= len(v))][0]
            raise InputError(f"triangles must index vertices in [0, {len(v) - 1}]; got {bad}")
        object.__setattr__(self, "vertices", v.astype(np.float64, copy=False))
        object.__setattr__(self, "triangles", t.astype(np.int64, copy=False))
        self._check_appearance(len(v))
        if self.motion is not None:
            m = _numbers("motion", self.motion, "a finite (K, V, 3) array [m], K >= 2")
            if m.ndim != 3 or m.shape[0] < 2 or m.shape[1:] != v.shape or not np.isfinite(m).all():
                raise InputError(
                    f"motion must be a finite (K, V, 3) array [m] with K >= 2 "
                    f"and V = {len(v)} vertices; got shape {m.shape}"
                )
            object.__setattr__(self, "motion", m.astype(np.float64, copy=False))

    def at_shutter(self, t: float) -> Mesh:
        """The mesh at ``t`` in [0, 1] of its shutter (0 opens, 1 closes), interpolated
        linearly between its motion steps; itself when it does not move."""
        if self.motion is None:
            return self
        k = len(self.motion) - 1
        i = min(int(t * k), k - 1)
        f = t * k - i
        moved = (1 - f) * self.motion[i] + f * self.motion[i + 1]
        return Mesh(
            vertices=moved,
            triangles=self.triangles,
            colours=self.colours,
            uvs=self.uvs,
            texture=self.texture,
        )

    def _check_appearance(self, count):
        """Colours (V, C) and a texture (h, w[, C]) of finite intensities >= 0; UVs (V, 2)."""
        for name, shape in (("colours", "(V, C)"), ("uvs", "(V, 2)"), ("texture", "(h, w, C)")):
            value = getattr(self, name)
            if value is None:
                continue
            a = _numbers(name, value, f"a finite {shape} array")
            ok = (
                a.ndim == 2 and len(a) == count and a.shape[1] >= 1
                if name != "texture"
                else a.ndim in (2, 3) and min(a.shape) >= 1
            )
            if name == "uvs":
                ok = ok and a.shape[1] == 2
            if not ok:
                raise InputError(
                    f"{name} must be a {shape} array (V = {count} vertices); got shape {a.shape}"
                )
            if not np.isfinite(a).all() or (name != "uvs" and (a < 0).any()):
                kind = "finite" if name == "uvs" else "finite intensities >= 0"
                raise InputError(
                    f"{name} must be {kind}; they hold NaN, infinite or negative values"
                )
            object.__setattr__(self, name, a)

    def __repr__(self) -> str:
        """One line: counts, extent and appearance; no arrays."""
        lo, hi = (
            (self.vertices.min(0), self.vertices.max(0))
            if len(self.vertices)
            else (np.zeros(3), np.zeros(3))
        )
        look = (
            "texture {}x{}".format(*self.texture.shape[:2])
            if self.texture is not None
            else f"{self.colours.shape[1]} colour channels"
            if self.colours is not None
            else "no colours"
        )
        t, v = len(self.triangles), len(self.vertices)
        moving = "" if self.motion is None else f", moving ({len(self.motion)} steps)"
        return (
            f"Mesh({t} triangle{'s' * (t != 1)}, {v} vert{'ices' if v != 1 else 'ex'}, extent "
            f"{' x '.join(preview.length(e) for e in hi - lo)}, {look}{moving})"
        )

    def areas(self) -> np.ndarray:
        a, b, c = (self.vertices[self.triangles[:, i]] for i in range(3))
        return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)

    def normals(self) -> np.ndarray:
        """Unit face normals (T, 3) (zero for degenerate triangles)."""
        a, b, c = (self.vertices[self.triangles[:, i]] for i in range(3))
        n = np.cross(b - a, c - a)
        length = np.linalg.norm(n, axis=1, keepdims=True)
        return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def _numbers(name, value, allowed) -> np.ndarray:
    """``value`` as an array of numbers (its own dtype: a large texture is not copied)."""
    try:
        a = np.asarray(value)
    except (TypeError, ValueError):
        a = None
    if a is None or a.dtype.kind not in "iuf":
        raise InputError(
            f"{name} must be {allowed}; got {type(value).__name__}"
            f"{'' if a is None else f' of dtype {a.dtype}'}"
        )
    return a


def sample_points(
    mesh: Mesh, spacing: float, *, channels=3, seed=0, max_points=2_000_000, normals=False
):
    """Area-uniform random points on a mesh, one per ``spacing``² of surface on average.

    Parameters
    ----------
    mesh : Mesh
        The surface [m].
    spacing : float
        The points' mean spacing [m]: N = area / spacing², at least 1.
    channels : int
        Colour channels C of the result.
    seed : int
        Seeds the sampling (a random stream of its own, apart from the emitters' phases).
    max_points : int
        At most this many points, >= 1.
    normals : bool
        Also return each point's unit surface normal.

    Returns
    -------
    positions : (N, 3) float64 ndarray
        The points [m].
    colours : (N, C) ndarray
        Interpolated from the vertex colours, looked up in the texture through the UVs, or
        white.
    normals : (N, 3) ndarray
        Only with ``normals``: each point's triangle's unit normal.

    Raises
    ------
    InputError
        Where ``mesh`` is not a Mesh or has no surface area, ``spacing`` is not a length
        > 0 or ``max_points`` < 1.

    Examples
    --------
    A triangle of 0.5 mm² at 10 µm spacing:

    >>> import numpy as np
    >>> from holo_core import Mesh
    >>> from holo_core.scene import sample_points
    >>> tri = Mesh(vertices=np.array([[0, 0, 0], [1e-3, 0, 0], [0, 1e-3, 0.0]]),
    ...            triangles=np.array([[0, 1, 2]]))
    >>> positions, colours = sample_points(tri, 1e-5)
    >>> positions.shape, colours[0]
    ((5000, 3), array([1., 1., 1.]))
    """
    tri, bary, pos = surface_samples(mesh, spacing, seed, max_points)
    colours = surface_colour(mesh, mesh.triangles[tri], bary, channels)
    return (pos, colours, mesh.normals()[tri]) if normals else (pos, colours)


def surface_samples(mesh: Mesh, spacing, seed, max_points):
    """(triangle index (N,), barycentric weights (N, 3), positions (N, 3) [m]) of area-uniform
    random points ``spacing`` [m] apart on average."""
    if not isinstance(mesh, Mesh):
        raise InputError(f"mesh must be a Mesh; got {type(mesh).__name__}")
    spacing = validate.length("spacing", spacing)
    max_points = validate.integer("max_points", max_points, 1)
    seed = validate.seed(seed)
    areas = mesh.areas()
    if not areas.sum() > 0:
        raise InputError("the mesh has no surface area (every triangle is degenerate)")
    n = int(min(max_points, max(1, round(areas.sum() / spacing**2))))
    # a stream of its own: record_points draws the phases from default_rng(seed), and phases
    # that follow the sampling's numbers would make each triangle's points coherent
    rng = np.random.default_rng([SAMPLING_STREAM, seed])
    tri = rng.choice(len(areas), size=n, p=areas / areas.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    bary = np.stack([1 - s, s * (1 - r2), s * r2], axis=1)  # uniform in each triangle
    return tri, bary, np.einsum("nk,nkd->nd", bary, mesh.vertices[mesh.triangles[tri]])


def visible_from(camera, positions, spacing: float, normals=None) -> np.ndarray:
    """Mask of the points (N, 3) [m] that ``camera`` sees: its own surface is the nearest within
    a few samples (``spacing`` [m] apart) along the pixel's line of sight.

    A hologram recorded for one viewpoint holds only the surfaces seen from there, as a raster
    renderer would draw them (surfaces are two-sided). The points themselves form the depth
    buffer: each cell of the camera's grid holds its nearest point, and a point is seen when it
    lies no deeper than what the nearest surface in its 3×3 neighbourhood can reach there, so a
    cell the random sampling left empty does not let a hidden surface through. That reach is
    the depth the nearest surface spans across three cells: one cell per cell (45°) without
    ``normals``; with the points' unit normals (N, 3), tan(incidence) cells, so the rim of a
    sphere, seen at a grazing angle, stays. Points outside the frame are kept.
    """
    xy, depth = camera.project(positions)
    w, h = camera.resolution
    footprint = camera.pixel_angle() * np.nanmin(np.where(depth > 0, depth, np.nan))
    cell = max(1.0, 2 * spacing / footprint)  # a few points per cell
    cols, rows = math.ceil(w / cell), math.ceil(h / cell)
    inside = (depth > 0) & (xy[:, 0] >= 0) & (xy[:, 0] < w) & (xy[:, 1] >= 0) & (xy[:, 1] < h)
    keep = np.ones(len(depth), bool)
    if not inside.any():
        return keep
    c = (xy[inside, 0] / cell).astype(int) + 1
    r = (xy[inside, 1] / cell).astype(int) + 1
    d = depth[inside]
    slope = np.ones(len(d))
    if normals is not None:
        cos = facing(camera.position, positions[inside], normals[inside])
        tan = np.sqrt(1 - np.minimum(cos, 1) ** 2) / np.maximum(cos, 1 / MAX_SLANT)
        slope = np.maximum(1.0, tan)
    # per cell, the nearest point and the deepest its surface reaches three cells away
    cell_id = r * (cols + 2) + c
    order = np.lexsort((d, cell_id))
    first = order[np.unique(cell_id[order], return_index=True)[1]]
    reach = np.full((rows + 2, cols + 2), np.inf)
    reach[r[first], c[first]] = d[first] * (1 + 3 * cell * camera.pixel_angle() * slope[first])
    bound = reach.copy()
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            bound[1:-1, 1:-1] = np.minimum(
                bound[1:-1, 1:-1], reach[1 + dr : rows + 1 + dr, 1 + dc : cols + 1 + dc]
            )
    keep[inside] = d <= bound[r, c] + 2 * spacing
    return keep


def facing(eye, positions, normals) -> np.ndarray:
    """|cos| of the angle between each surface normal (N, 3) and the line from its point
    (N, 3) [m] to ``eye`` [m]: the projected area per unit of surface seen from there."""
    ray = np.asarray(eye, np.float64) - positions
    return np.abs(np.einsum("nd,nd->n", normals, ray)) / np.linalg.norm(ray, axis=1)


def outward(mesh) -> float:
    """+1 where a closed ``mesh``'s triangles wind (counter-clockwise) with their normals out of
    it, -1 where into it (the sign of its signed volume), 0 where it is not closed: an edge
    not shared by exactly two triangles (vertices within 1e-9 of its size taken as one, the
    triangles that leaves edgeless dropped), a card or an open shell, with no outside."""
    v = np.asarray(mesh.vertices, np.float64)
    tri = np.asarray(mesh.triangles, np.int64)
    if len(tri) == 0:
        return 0.0
    # a seam's split vertices made one, and a pole's (within a billionth of the mesh's size)
    tol = 1e-9 * max(float(np.ptp(v, axis=0).max()), 1e-300)
    _, same = np.unique(np.round(v / tol), axis=0, return_inverse=True)
    t = same.reshape(-1)[tri]
    t = t[(t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 2] != t[:, 0])]  # a pole's slivers
    edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    _, shared = np.unique(edges, axis=0, return_counts=True)
    if (shared != 2).any():
        return 0.0
    a, b, c = (v[tri[:, i]] for i in range(3))
    volume = np.einsum("ij,ij->", a, np.cross(b, c)) / 6
    return float(np.sign(volume))


def surface_colour(mesh: Mesh, corners, bary, channels):
    if mesh.texture is not None and mesh.uvs is not None:
        uv = np.einsum("nk,nkd->nd", bary, mesh.uvs[corners])
        return texture_lookup(mesh.texture, uv)
    if mesh.colours is not None:
        return np.einsum("nk,nkc->nc", bary, np.asarray(mesh.colours, np.float64)[corners])
    return np.ones((len(bary), channels))


def texture_lookup(texture, uv) -> np.ndarray:
    """Nearest texel of ``texture`` (h, w, C), row 0 at the top (v = 1), at ``uv`` (N, 2)."""
    tex = np.asarray(texture, np.float64)
    tex = tex[..., None] if tex.ndim == 2 else tex
    h, w = tex.shape[:2]
    col = np.clip((np.mod(uv[:, 0], 1) * w).astype(int), 0, w - 1)
    row = np.clip(((1 - np.mod(uv[:, 1], 1)) * h).astype(int), 0, h - 1)
    return tex[row, col]


def point_spacing(wavelength, pitch, shape, distance) -> float:
    """The hologram's resolution at ``distance`` [m]: λ|z| / (aperture) [m], the spacing below
    which further points are not resolved (Sect. VI-A), for ``wavelength``, ``pitch`` [m]."""
    aperture = min(shape) * pitch
    return wavelength * abs(distance) / aperture


# --- textured planar primitives ----------------------------------------------------------------


# --- mesh files ----------------------------------------------------------------------------------


def default_spacing(wavelength, pitch, shape, positions) -> float:
    """:func:`point_spacing` at the nearest depth of ``positions`` [m], at least one ``pitch``
    [m], over √2: two samples per resolved spot along the diagonal (``wavelength`` [m])."""
    z = np.abs(np.asarray(positions)[:, 2]).min()
    return max(point_spacing(wavelength, pitch, shape, z), pitch) / math.sqrt(2)
