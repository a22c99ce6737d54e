"""Emitters: point sources and textured planar primitives, from meshes or directly (Sect. V-B).

Positions are metres in the hologram's frame (hologram plane z = 0, objects at z < 0). Colours
are linear intensities I per wavelength; a point's amplitude is A0 = √I (Sect. VII-B). Diffuse
surfaces get uniformly random phases from a seeded generator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import validate
from .propagation import propagate_to_plane

MAX_SLANT = 30.0  # visibility: a surface's depth slope (tan of its incidence) is capped here (88°)
MIN_SEEN = 0.3  # a primitive is recorded when the camera sees this share of its samples
                # (a cube: its hidden faces 0-0.15 through their rims, a grazing seen face 0.47)
SAMPLING_STREAM = 0x5A4D  # seeds mesh sampling apart from the phases (see _sample)


@dataclass(frozen=True, eq=False, kw_only=True)
class Mesh:
    """A triangle mesh: ``vertices`` (V, 3) [m], ``triangles`` (T, 3) int, optional
    ``colours`` (V, C) linear intensities, ``uvs`` (V, 2) and ``texture`` (h, w, C)."""

    vertices: np.ndarray
    triangles: np.ndarray
    colours: np.ndarray | None = None
    uvs: np.ndarray | None = None
    texture: np.ndarray | None = None

    def __post_init__(self):
        v, t = np.asarray(self.vertices), np.asarray(self.triangles)
        if v.ndim != 2 or v.shape[1] != 3 or not np.isfinite(v).all():
            raise ValueError(f"vertices must be a finite (V, 3) array [m]; got {v.shape}")
        if t.ndim != 2 or t.shape[1] != 3 or (t.size and (t.min() < 0 or t.max() >= len(v))):
            raise ValueError(f"triangles must be (T, 3) indices in [0, {len(v) - 1}]")

    def areas(self) -> np.ndarray:
        a, b, c = (self.vertices[self.triangles[:, i]] for i in range(3))
        return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)

    def normals(self) -> np.ndarray:
        """Unit face normals (T, 3) (zero for degenerate triangles)."""
        a, b, c = (self.vertices[self.triangles[:, i]] for i in range(3))
        n = np.cross(b - a, c - a)
        length = np.linalg.norm(n, axis=1, keepdims=True)
        return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def sample_points(mesh: Mesh, spacing: float, *, channels=3, seed=0, max_points=2_000_000,
                  normals=False):
    """Area-uniform random points on ``mesh``, one per ``spacing``² [m] of surface on average.

    Returns (positions (N, 3) [m], colours (N, C)) with colours interpolated from the vertex
    colours, looked up in the texture through the UVs, or white; with ``normals``, also each
    point's unit surface normal (N, 3).
    """
    tri, bary, pos = _sample(mesh, spacing, seed, max_points)
    colours = _colour(mesh, mesh.triangles[tri], bary, channels)
    return (pos, colours, mesh.normals()[tri]) if normals else (pos, colours)


def _sample(mesh: Mesh, spacing, seed, max_points):
    """(triangle index (N,), barycentric weights (N, 3), positions (N, 3) [m]) of area-uniform
    random points ``spacing`` [m] apart on average."""
    spacing = validate.positive("spacing", spacing, "m")
    areas = mesh.areas()
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
    cell = max(1.0, 2 * spacing / footprint)         # a few points per cell
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
            bound[1:-1, 1:-1] = np.minimum(bound[1:-1, 1:-1],
                                           reach[1 + dr:rows + 1 + dr, 1 + dc:cols + 1 + dc])
    keep[inside] = d <= bound[r, c] + 2 * spacing
    return keep


def facing(eye, positions, normals) -> np.ndarray:
    """|cos| of the angle between each surface normal (N, 3) and the line from its point
    (N, 3) [m] to ``eye`` [m]: the projected area per unit of surface seen from there."""
    ray = np.asarray(eye, np.float64) - positions
    return np.abs(np.einsum("nd,nd->n", normals, ray)) / np.linalg.norm(ray, axis=1)


def _colour(mesh: Mesh, corners, bary, channels):
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

@dataclass(frozen=True, eq=False, kw_only=True)
class Primitive:
    """A textured triangle or quad: ``corners`` (3|4, 3) [m] in order around the edge, ``uvs``
    (3|4, 2) and a ``texture`` (h, w, C) of linear intensities (row 0 at v = 1)."""

    corners: np.ndarray
    uvs: np.ndarray
    texture: np.ndarray

    def frame(self):
        """(rotation, centre): columns ξ, η, ζ with ζ the normal towards +z, and the centroid."""
        p = np.asarray(self.corners, np.float64)
        xi = p[1] - p[0]
        zeta = np.cross(p[1] - p[0], p[-1] - p[0])
        if np.linalg.norm(zeta) == 0 or np.linalg.norm(xi) == 0:
            raise ValueError("primitive corners are degenerate (zero area)")
        zeta = zeta / np.linalg.norm(zeta)
        if zeta[2] < 0:  # emit towards the hologram
            zeta = -zeta
        xi = xi / np.linalg.norm(xi)
        eta = np.cross(zeta, xi)
        return np.stack([xi, eta, zeta], axis=1), p.mean(axis=0)


def surface_field(prim: Primitive, *, pitch, channel=0, seed=0, diffuse=True):
    """The primitive's surface field on its own plane: (field (n, m) complex, the grid's centre
    in the local frame (ξ, η) [m]). √I from the texture, zero outside; a random phase per
    sample when ``diffuse`` (a rough surface), else phase 0 (a mirror-like emitter)."""
    m, centre = prim.frame()
    local = (np.asarray(prim.corners, np.float64) - centre) @ m  # (k, 3), third column ~0
    lo, hi = local[:, :2].min(0), local[:, :2].max(0)
    n = np.maximum(np.ceil((hi - lo) / pitch).astype(int) + 1, 1)
    mid = (lo + hi) / 2
    xi = (np.arange(n[0]) - (n[0] - 1) / 2) * pitch + mid[0]
    eta = (np.arange(n[1]) - (n[1] - 1) / 2) * pitch + mid[1]
    px, py = np.meshgrid(xi, eta)
    pts = np.stack([px.ravel(), py.ravel()], axis=1)
    inside = np.zeros(len(pts), bool)
    uv = np.zeros((len(pts), 2))
    tris = [(0, 1, 2)] if len(local) == 3 else [(0, 1, 2), (0, 2, 3)]
    for tri in tris:
        bary = _barycentric(pts, local[list(tri), :2])
        hit = (bary >= 0).all(axis=1)
        inside |= hit
        uv[hit] = bary[hit] @ np.asarray(prim.uvs, np.float64)[list(tri)]
    intensity = np.zeros(len(pts))
    intensity[inside] = texture_lookup(prim.texture, uv[inside])[:, channel]
    phase = np.random.default_rng(seed).uniform(0, 2 * np.pi, len(pts)) if diffuse else 0.0
    field = (np.sqrt(intensity) * np.exp(1j * phase)).reshape(n[1], n[0])
    return field, mid


def _barycentric(p, tri):
    a, b, c = tri
    v0, v1, v2 = b - a, c - a, p - a
    d = v0[0] * v1[1] - v1[0] * v0[1]
    l1 = (v2[:, 0] * v1[1] - v1[0] * v2[:, 1]) / d
    l2 = (v0[0] * v2[:, 1] - v2[:, 0] * v0[1]) / d
    return np.stack([1 - l1 - l2, l1, l2], axis=1)


def surface_pitch(prim: Primitive, *, wavelength, pitch) -> float:
    """The sample spacing [m] on the primitive's plane that holds every direction the hologram
    (``pitch`` [m] at ``wavelength`` [m]) records: its Nyquist cone, tilted with the plane."""
    m, _ = prim.frame()
    tilt = math.acos(min(1.0, abs(m[2, 2])))
    accept = math.asin(min(1.0, wavelength / (2 * pitch)))
    return min(pitch, wavelength / (2 * math.sin(min(math.pi / 2, tilt + accept))))


def primitive_wave(prim: Primitive, *, wavelength, pitch, shape, channel=0, seed=0, padding=2,
                   diffuse=True, sampled_for=None):
    """The primitive's wave on the hologram (z = 0, ``shape``, ``pitch`` [m]) at ``wavelength``
    [m]: its surface field, sampled at :func:`surface_pitch`, carried by spectrum rotation plus
    offset propagation (Sect. IV-D). ``sampled_for``: the shortest wavelength [m] of a set
    recorded together, so that all share one surface grid and so one diffuse phase pattern
    (the depth pair needs it)."""
    m, centre = prim.frame()
    q = surface_pitch(prim, wavelength=min(wavelength, sampled_for or wavelength), pitch=pitch)
    field, mid = surface_field(prim, pitch=q, channel=channel, seed=seed, diffuse=diffuse)
    grid_centre = centre + m[:, :2] @ mid  # the surface grid's centre in the hologram frame
    # the hologram plane seen from the primitive: axes = rows of m, centre at -grid_centre
    return propagate_to_plane(field.astype(np.complex64), wavelength=wavelength, pitch=q,
                              rotation=m.T, position=m.T @ (-grid_centre), padding=padding,
                              out_shape=shape, out_pitch=pitch)


def mesh_primitives(mesh: Mesh, *, visible_to=None, spacing=None) -> list[Primitive]:
    """The mesh's triangles as primitives, textured by the mesh's texture or, without one,
    by the mean of their corners' colours; with a camera ``visible_to``, only those it sees
    (tested on points ``spacing`` [m] apart, see :func:`visible_from`)."""
    keep = np.arange(len(mesh.triangles))
    if visible_to is not None:  # seen: most of its samples (a hidden face's rim passes)
        tri, _, pos = _sample(mesh, spacing, 0, 2_000_000)
        seen = visible_from(visible_to, pos, spacing, mesh.normals()[tri])
        share = np.bincount(tri[seen], minlength=len(keep)) / \
            np.maximum(np.bincount(tri, minlength=len(keep)), 1)
        keep = np.flatnonzero(share >= MIN_SEEN)
    prims = []
    for t in keep:
        idx = mesh.triangles[t]
        if mesh.texture is not None and mesh.uvs is not None:
            uvs, tex = mesh.uvs[idx], mesh.texture
        else:
            colour = (np.asarray(mesh.colours, np.float64)[idx].mean(0)
                      if mesh.colours is not None else np.ones(3))
            uvs, tex = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), colour[None, None, :]
        if np.linalg.norm(np.cross(*(mesh.vertices[idx[1:]] - mesh.vertices[idx[0]]))) > 0:
            prims.append(Primitive(corners=mesh.vertices[idx], uvs=uvs, texture=tex))
    return prims


def depth_texture(texture) -> np.ndarray:
    """The depth partner's texture: unit intensity, one channel (the recording scales it by
    the surface's cosine towards the camera). Its image is the surface's coverage of each
    pixel, whatever the colour, which gives the opacity mask; the depth pair's cross term
    u1·conj(u2) still weighs each emitter by its colour amplitude."""
    t = np.asarray(texture, np.float64)
    return np.ones(t.shape[:2] + (1,))


# --- mesh files ----------------------------------------------------------------------------------

def read_mesh(path) -> Mesh:
    """A triangle mesh from an OBJ (``v x y z [r g b]``, ``vt``, ``f``) or PLY (ASCII or binary
    little-endian; vertex x y z [red green blue], face vertex_indices) file, in the file's
    units taken as metres. Polygons are fanned into triangles."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such mesh file")
    kind = path.suffix.lower()
    if kind == ".obj":
        return _read_obj(path)
    if kind == ".ply":
        return _read_ply(path)
    raise ValueError(f"{path}: mesh files must be .obj or .ply")


def _fan(poly):
    return [(poly[0], poly[i], poly[i + 1]) for i in range(1, len(poly) - 1)]


def _read_obj(path: Path) -> Mesh:
    verts, cols, tris = [], [], []
    for line in path.read_text().splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            verts.append([float(x) for x in parts[1:4]])
            cols.append([float(x) for x in parts[4:7]] if len(parts) >= 7 else None)
        elif parts[0] == "f":
            idx = [int(p.split("/")[0]) for p in parts[1:]]
            tris += _fan([i - 1 if i > 0 else len(verts) + i for i in idx])
    colours = np.array(cols, np.float64) if cols and all(c is not None for c in cols) else None
    return Mesh(vertices=np.array(verts, np.float64).reshape(-1, 3),
                triangles=np.array(tris, np.int64).reshape(-1, 3), colours=colours)


_PLY_TYPES = {"char": "i1", "uchar": "u1", "short": "i2", "ushort": "u2", "int": "i4",
              "uint": "u4", "float": "f4", "double": "f8", "int8": "i1", "uint8": "u1",
              "int16": "i2", "uint16": "u2", "int32": "i4", "uint32": "u4", "float32": "f4",
              "float64": "f8"}


def _read_ply(path: Path) -> Mesh:
    data = path.read_bytes()
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise ValueError(f"{path}: not a PLY file")
    header = data[:end].decode("ascii", "replace").splitlines()
    body = data[data.index(b"\n", end) + 1:]
    fmt = next(l.split()[1] for l in header if l.startswith("format"))
    elements = []
    for line in header:
        p = line.split()
        if p[:1] == ["element"]:
            elements.append((p[1], int(p[2]), []))
        elif p[:1] == ["property"]:
            elements[-1][2].append(p[1:])
    if fmt == "ascii":
        tokens = iter(body.decode("ascii").split())
        read = lambda t: float(next(tokens))  # noqa: E731
    elif fmt == "binary_little_endian":
        offset = [0]

        def read(t):
            dt = np.dtype("<" + _PLY_TYPES[t])
            v = np.frombuffer(body, dt, 1, offset[0])[0]
            offset[0] += dt.itemsize
            return v
    else:
        raise ValueError(f"{path}: PLY format {fmt!r} is not supported (ascii, "
                         f"binary_little_endian)")
    verts, cols, tris = [], [], []
    for name, count, props in elements:
        for _ in range(count):
            row = {}
            for prop in props:
                if prop[0] == "list":
                    row[prop[-1]] = [int(read(prop[2])) for _ in range(int(read(prop[1])))]
                else:
                    row[prop[-1]] = float(read(prop[0]))
            if name == "vertex":
                verts.append([row["x"], row["y"], row["z"]])
                if "red" in row:
                    cols.append([row["red"], row["green"], row["blue"]])
            elif name == "face":
                tris += _fan(row.get("vertex_indices") or row.get("vertex_index"))
    colours = np.array(cols) / 255.0 if len(cols) == len(verts) and cols else None
    return Mesh(vertices=np.array(verts, np.float64).reshape(-1, 3),
                triangles=np.array(tris, np.int64).reshape(-1, 3), colours=colours)


def default_spacing(wavelength, pitch, shape, positions) -> float:
    """:func:`point_spacing` at the nearest depth of ``positions`` [m], at least one ``pitch``
    [m], over √2: two samples per resolved spot along the diagonal (``wavelength`` [m])."""
    z = np.abs(np.asarray(positions)[:, 2]).min()
    return max(point_spacing(wavelength, pitch, shape, z), pitch) / math.sqrt(2)
