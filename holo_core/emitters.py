"""Emitters: point sources and textured planar primitives, from meshes or directly (Sect. V-B).

Positions are metres in the hologram's frame (hologram plane z = 0, objects at z < 0). Colours
are linear intensities I per wavelength; a point's amplitude is A0 = √I (Sect. VII-B). Diffuse
surfaces get uniformly random phases from a seeded generator.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import validate
from .propagation import propagate_to_plane
from .validate import InputError

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
            raise InputError(f"vertices must be a finite (V, 3) array [m]; got {v.shape}")
        if t.ndim != 2 or t.shape[1] != 3 or (t.size and (t.min() < 0 or t.max() >= len(v))):
            raise InputError(f"triangles must be (T, 3) indices in [0, {len(v) - 1}]")

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
    max_points = int(validate.at_least("max_points", max_points, 1))
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
            raise InputError("primitive corners are degenerate (zero area)")
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

class MeshFileError(InputError):
    """A mesh file that cannot be read; the message names the file, the place and the problem."""


TEXT_BYTES = 40  # host bytes a text mesh's parse takes per byte of file (Python floats, lists)


def read_mesh(path) -> Mesh:
    """A triangle mesh from an OBJ (``v x y z [r g b]``, ``f``; UTF-8 with or without a
    byte-order mark, or Latin-1) or PLY (ASCII, binary little- or big-endian; vertex x y z
    [red green blue], face vertex_indices) file, in the file's units taken as metres. Polygons
    are fanned into triangles; faces of fewer than three vertices are skipped with a warning.
    :class:`MeshFileError` names the file and the problem: damaged or truncated data, counts
    the file cannot hold, indices out of range, non-finite coordinates, no faces."""
    path = Path(path)
    if not path.is_file():
        raise MeshFileError(f"{path}: no such mesh file")
    kind = path.suffix.lower()
    if kind not in (".obj", ".ply"):
        raise MeshFileError(f"{path}: mesh files must be .obj or .ply")
    data = path.read_bytes()
    verts, faces, colours = (_read_obj if kind == ".obj" else _read_ply)(path, data)
    return _mesh(path, verts, faces, colours)


def _mesh(path, verts, faces, colours) -> Mesh:
    """The mesh of ``faces`` (lists of vertex indices, 0-based) fanned into triangles."""
    verts = np.asarray(verts, np.float64).reshape(-1, 3)
    if not len(verts):
        raise MeshFileError(f"{path}: no vertices")
    if not np.isfinite(verts).all():
        raise MeshFileError(f"{path}: vertex coordinates must be finite (NaN or infinity "
                            f"found)")
    tris, skipped = _triangles(faces)
    if skipped:
        warnings.warn(f"{path}: {skipped} face(s) of fewer than 3 vertices skipped",
                      UserWarning, stacklevel=3)
    if not len(tris):
        raise MeshFileError(f"{path}: no faces of 3 or more vertices (read_mesh needs a "
                            f"surface, not a point cloud)")
    bad = (tris < 0) | (tris >= len(verts))
    if bad.any():
        raise MeshFileError(f"{path}: face vertex index {int(tris[bad][0])} is out of range "
                            f"(the file has {len(verts)} vertices)")
    if colours is not None:
        colours = np.asarray(colours, np.float64).reshape(len(verts), -1)
        if not np.isfinite(colours).all() or (colours < 0).any():
            raise MeshFileError(f"{path}: vertex colours must be finite and >= 0")
    return Mesh(vertices=verts, triangles=tris, colours=colours)


def _triangles(faces) -> tuple[np.ndarray, int]:
    """(the polygons ``faces`` fanned into triangles (T, 3), how many had < 3 vertices);
    ``faces`` is a list of index lists, or a (F, k) array when all have k vertices."""
    if isinstance(faces, np.ndarray) and faces.ndim == 2:
        f = faces.astype(np.int64)
        if f.shape[1] < 3:
            return np.zeros((0, 3), np.int64), len(f)
        return np.concatenate([f[:, [0, i, i + 1]] for i in range(1, f.shape[1] - 1)]), 0
    kept = [list(map(int, f)) for f in faces if len(f) >= 3]
    fans = [(f[0], f[i], f[i + 1]) for f in kept for i in range(1, len(f) - 1)]
    try:
        tris = np.array(fans, np.int64).reshape(-1, 3)
    except OverflowError:  # an index beyond int64 is out of range whatever the mesh
        tris = np.full((1, 3), -1, np.int64)
    return tris, len(faces) - len(kept)


def _read_obj(path: Path, data: bytes):
    from .memory import check_host
    check_host(f"{path} (OBJ text)", TEXT_BYTES * len(data))
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = data.decode("latin-1")  # numbers are ASCII; names and comments may not be
    verts, cols, faces = [], [], []
    for number, line in enumerate(text.splitlines(), 1):
        parts = line.split("#", 1)[0].split()
        if not parts or parts[0] not in ("v", "f"):
            continue
        try:
            if parts[0] == "v":
                values = [float(x) for x in parts[1:]]
                if len(values) < 3:
                    raise ValueError("a vertex needs x y z")
                verts.append(values[:3])
                cols.append(values[3:6] if len(values) >= 6 else None)
            else:
                idx = [int(p.split("/")[0]) for p in parts[1:]]
                if 0 in idx:
                    raise ValueError("OBJ indices start at 1 (0 is not an index)")
                faces.append([i - 1 if i > 0 else len(verts) + i for i in idx])
        except ValueError as e:
            raise MeshFileError(f"{path}, line {number}: {e}") from None
    colours = cols if cols and all(c is not None for c in cols) else None
    return verts, faces, colours


_PLY_TYPES = {"char": "i1", "uchar": "u1", "short": "i2", "ushort": "u2", "int": "i4",
              "uint": "u4", "float": "f4", "double": "f8", "int8": "i1", "uint8": "u1",
              "int16": "i2", "uint16": "u2", "int32": "i4", "uint32": "u4", "float32": "f4",
              "float64": "f8"}
_PLY_FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}


def _read_ply(path: Path, data: bytes):
    fmt, elements, body = _ply_header(path, data)
    if fmt is None:
        from .memory import check_host
        check_host(f"{path} (PLY text)", TEXT_BYTES * len(body))
    reader = _PlyText(path, body) if fmt is None else _PlyBinary(path, body, fmt)
    values = {name: reader.element(name, count, props) for name, count, props in elements}
    vertex = values.get("vertex")
    if vertex is None or not all(k in vertex for k in "xyz"):
        raise MeshFileError(f"{path}: PLY needs a vertex element with x, y, z properties")
    verts = np.stack([np.asarray(vertex[k], np.float64) for k in "xyz"], 1)
    face = values.get("face", {})
    faces = face.get("vertex_indices", face.get("vertex_index", []))
    colours = None
    rgb = ("red", "green", "blue")
    if all(k in vertex for k in rgb):  # integers scale by their type's full range
        kinds = {p[-1]: np.dtype(_PLY_TYPES[p[0]]) for name, _, props in elements
                 if name == "vertex" for p in props if p[0] != "list"}
        colours = np.stack([np.asarray(vertex[k], np.float64) /
                            (np.iinfo(kinds[k]).max if kinds[k].kind in "iu" else 1.0)
                            for k in rgb], 1)
    return verts, faces, colours


def _ply_header(path: Path, data: bytes):
    """(byte order or None for ASCII, [(element, count, [property...])], body bytes), every
    count checked against what the body can hold."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise MeshFileError(f"{path}: not a PLY file (no 'ply' ... 'end_header' header)")
    newline = data.find(b"\n", end)
    body = data[newline + 1:] if newline >= 0 else b""
    try:
        lines = data[:end].decode("ascii").splitlines()[1:]
    except UnicodeDecodeError:
        raise MeshFileError(f"{path}: the PLY header must be ASCII text") from None
    fmt, elements = "missing", []
    for number, line in enumerate(lines, 2):
        p = line.split()
        if not p or p[0] in ("comment", "obj_info"):
            continue
        where = f"{path}, header line {number}"
        if p[0] == "format" and len(p) == 3 and p[1] in _PLY_FORMATS:
            fmt = _PLY_FORMATS[p[1]]
        elif p[0] == "element" and len(p) == 3 and p[2].isdigit():
            elements.append((p[1], int(p[2]), []))
        elif p[0] == "property" and elements and (
                (len(p) == 3 and p[1] in _PLY_TYPES) or
                (len(p) == 5 and p[1] == "list" and p[2] in _PLY_TYPES and p[3] in _PLY_TYPES
                 and np.dtype(_PLY_TYPES[p[2]]).kind in "iu"
                 and np.dtype(_PLY_TYPES[p[3]]).kind in "iu")):
            elements[-1][2].append(p[1:])
        else:
            raise MeshFileError(f"{where}: cannot read {line.strip()[:80]!r} (expected format "
                                f"ascii|binary_little_endian|binary_big_endian 1.0, element "
                                f"<name> <count>, property <type> <name>, or property list "
                                f"<int type> <int type> <name>)")
    if fmt == "missing":
        raise MeshFileError(f"{path}: the PLY header has no valid format line")
    for name, _, props in elements:
        names = [q[-1] for q in props]
        if len(set(names)) < len(names) or any(n.endswith("#n") for n in names):
            raise MeshFileError(f"{path}: element {name} names a property twice")
    room = len(body)
    for name, count, props in elements:
        if count and not props:
            raise MeshFileError(f"{path}: element {name} has {count} entries but no properties")
        least = sum(2 if fmt is None else np.dtype(_PLY_TYPES[q[1] if q[0] == "list" else q[0]])
                    .itemsize for q in props)  # per entry: '0 ' per value, or the fixed bytes
        if count * least > room:
            raise MeshFileError(f"{path}: element {name} declares {count} entries, more than "
                                f"the file's {len(body)} bytes of data can hold")
        room -= count * least if fmt is not None else 0
    return fmt, elements, body


class _PlyBinary:
    """Elements of a binary PLY body, read with NumPy: fixed-size rows at once, list rows at
    once when every list has the first row's length, else row by row."""

    def __init__(self, path, body, order):
        self.path, self.body, self.order, self.at = path, body, order, 0

    def dtype(self, kind):
        return np.dtype(self.order + _PLY_TYPES[kind])

    def element(self, name, count, props):
        fields = []
        if count and any(p[0] == "list" for p in props):
            first = self._first_lengths(name, props)
            for p in props:
                if p[0] == "list":
                    fields += [(p[-1] + "#n", self.dtype(p[1])), (p[-1], self.dtype(p[2]),
                                                                   (first[p[-1]],))]
                else:
                    fields.append((p[-1], self.dtype(p[0])))
            rows = self._take(name, np.dtype(fields), count)
            if all((rows[p[-1] + "#n"] == first[p[-1]]).all() for p in props if p[0] == "list"):
                return {p[-1]: rows[p[-1]] for p in props}
            self.at -= rows.nbytes
            return self._row_by_row(name, count, props)
        if any(p[0] == "list" for p in props):
            return {p[-1]: [] for p in props}
        rows = self._take(name, np.dtype([(p[-1], self.dtype(p[0])) for p in props]), count)
        return {p[-1]: rows[p[-1]] for p in props}

    def _first_lengths(self, name, props):
        at, lengths = self.at, {}
        for p in props:
            if p[0] == "list":
                lengths[p[-1]] = n = self._length(name, p[1])
                self.at += n * self.dtype(p[2]).itemsize
            else:
                self.at += self.dtype(p[0]).itemsize
        self.at = at
        return lengths

    def _row_by_row(self, name, count, props):
        out = {p[-1]: [] for p in props}
        for _ in range(count):
            for p in props:
                if p[0] == "list":
                    out[p[-1]].append(self._take(name, self.dtype(p[2]),
                                                 self._length(name, p[1])))
                else:
                    out[p[-1]].append(self._take(name, self.dtype(p[0]), 1)[0])
        return out

    def _length(self, name, kind) -> int:
        """A list's length, read at the cursor."""
        (n,) = self._take(name, self.dtype(kind), 1)
        if n < 0:
            raise MeshFileError(f"{self.path}: element {name}: a list of length {n}")
        return int(n)

    def _take(self, name, dtype, count):
        if self.at + dtype.itemsize * count > len(self.body):
            raise MeshFileError(f"{self.path}: truncated in element {name} (the data ends "
                                f"after {len(self.body)} bytes)")
        rows = np.frombuffer(self.body, dtype, count, self.at)
        self.at += rows.nbytes
        return rows


class _PlyText:
    """Elements of an ASCII PLY body, token by token."""

    def __init__(self, path, body):
        self.path, self.tokens, self.at = path, body.split(), 0

    def element(self, name, count, props):
        out = {p[-1]: [] for p in props}
        for _ in range(count):
            for p in props:
                if p[0] == "list":
                    n = int(self._next(name, True))
                    if n < 0 or self.at + n > len(self.tokens):
                        raise MeshFileError(f"{self.path}: element {name}: a list of length "
                                            f"{n} the file cannot hold")
                    out[p[-1]].append([int(self._next(name, True)) for _ in range(n)])
                else:
                    out[p[-1]].append(self._next(name, np.dtype(_PLY_TYPES[p[0]]).kind in "iu"))
        return out

    def _next(self, name, integer):
        if self.at >= len(self.tokens):
            raise MeshFileError(f"{self.path}: truncated in element {name}")
        token = self.tokens[self.at]
        self.at += 1
        try:
            return int(token) if integer else float(token)
        except ValueError:
            kind = "an integer" if integer else "a number"
            raise MeshFileError(f"{self.path}: element {name}: {token[:20]!r} is not "
                                f"{kind}") from None


def default_spacing(wavelength, pitch, shape, positions) -> float:
    """:func:`point_spacing` at the nearest depth of ``positions`` [m], at least one ``pitch``
    [m], over √2: two samples per resolved spot along the diagonal (``wavelength`` [m])."""
    z = np.abs(np.asarray(positions)[:, 2]).min()
    return max(point_spacing(wavelength, pitch, shape, z), pitch) / math.sqrt(2)
