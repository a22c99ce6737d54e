"""Mesh files: OBJ and PLY (ASCII and binary) read into a :class:`~holo_core.scene.Mesh`."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ..memory import check_host
from ..scene.mesh import Mesh
from ..validate import InputError


class MeshFileError(InputError):
    """A mesh file that cannot be read; the message names the file, the place and the problem."""


TEXT_BYTES = 40  # host bytes a text mesh's parse takes per byte of file (Python floats, lists)


def read_mesh(path) -> Mesh:
    """Read a triangle mesh from an OBJ or PLY file, in the file's units taken as metres.

    Parameters
    ----------
    path : str or Path
        An OBJ (``v x y z [r g b]``, ``f``; UTF-8 with or without a byte-order mark, or
        Latin-1) or PLY (ASCII, binary little- or big-endian; vertex x y z [red green blue],
        face vertex_indices) file.

    Returns
    -------
    Mesh
        Vertices [m] and triangles: polygons are fanned into triangles; faces of fewer than
        three vertices are skipped with a warning.

    Raises
    ------
    MeshFileError
        (an :class:`InputError`) Naming the file and the problem: damaged or truncated data,
        counts the file cannot hold, indices out of range, non-finite coordinates, no faces.

    Examples
    --------
    >>> import os, tempfile
    >>> from holo_core import read_mesh
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = os.path.join(folder, "quad.obj")
    ...     with open(path, "w") as f:
    ...         _ = f.write("v 0 0 0\\nv 1 0 0\\nv 1 1 0\\nv 0 1 0\\nf 1 2 3 4\\n")
    ...     mesh = read_mesh(path)
    >>> mesh.triangles.shape
    (2, 3)
    """
    path = Path(path)
    if not path.is_file():
        raise MeshFileError(f"{path}: no such mesh file")
    kind = path.suffix.lower()
    if kind not in (".obj", ".ply"):
        raise MeshFileError(f"{path}: mesh files must be .obj or .ply")
    data = path.read_bytes()
    verts, faces, colours = (_read_obj if kind == ".obj" else _read_ply)(path, data)
    return _mesh(path, verts, faces, colours, first=1 if kind == ".obj" else 0)


def _mesh(path, verts, faces, colours, first=0) -> Mesh:
    """The mesh of ``faces`` (lists of vertex indices, 0-based) fanned into triangles;
    ``first``: the file's number of the first vertex, for messages."""
    verts = np.asarray(verts, np.float64).reshape(-1, 3)
    if not len(verts):
        raise MeshFileError(f"{path}: no vertices")
    if not np.isfinite(verts).all():
        raise MeshFileError(f"{path}: vertex coordinates must be finite (NaN or infinity found)")
    _check_indices(path, faces, len(verts), first)
    tris, skipped = _triangles(faces)
    if skipped:
        warnings.warn(
            f"{path}: {skipped} face(s) of fewer than 3 vertices skipped", UserWarning, stacklevel=3
        )
    if not len(tris):
        raise MeshFileError(
            f"{path}: no faces of 3 or more vertices (read_mesh needs a surface, not a point cloud)"
        )
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
    return np.array(fans, np.int64).reshape(-1, 3), len(faces) - len(kept)


def _check_indices(path, faces, count, first) -> None:
    """:class:`MeshFileError` naming the first face vertex index outside the ``count``
    vertices, as the file numbers it (from ``first``), however large (before any cast)."""
    if isinstance(faces, np.ndarray):
        bad = faces[(faces < 0) | (faces >= count)] if faces.size else faces
        offender = int(bad.flat[0]) if bad.size else None
    else:
        offender = next(
            (
                int(i)
                for f in faces
                if len(f) and not (min(f) >= 0 and max(f) < count)
                for i in f
                if not 0 <= i < count
            ),
            None,
        )
    if offender is not None:
        raise MeshFileError(
            f"{path}: face vertex index {offender + first} is out of range "
            f"(the file has {count} vertices, numbered from {first})"
        )


def _read_obj(path: Path, data: bytes):
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
                if idx and min(idx) < -len(verts):
                    raise ValueError(
                        f"relative index {min(idx)} reaches before the first "
                        f"vertex ({len(verts)} so far)"
                    )
                faces.append([i - 1 if i > 0 else len(verts) + i for i in idx])
        except ValueError as e:
            raise MeshFileError(f"{path}, line {number}: {e}") from None
    colours = cols if cols and all(c is not None for c in cols) else None
    return verts, faces, colours


_PLY_TYPES = {
    "char": "i1",
    "uchar": "u1",
    "short": "i2",
    "ushort": "u2",
    "int": "i4",
    "uint": "u4",
    "float": "f4",
    "double": "f8",
    "int8": "i1",
    "uint8": "u1",
    "int16": "i2",
    "uint16": "u2",
    "int32": "i4",
    "uint32": "u4",
    "float32": "f4",
    "float64": "f8",
}


_PLY_FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}


def _read_ply(path: Path, data: bytes):
    fmt, elements, body = _ply_header(path, data)
    if fmt is None:
        check_host(f"{path} (PLY text)", TEXT_BYTES * len(body))
    reader = _PlyText(path, body) if fmt is None else _PlyBinary(path, body, fmt)
    values = {name: reader.element(name, count, props) for name, count, props in elements}
    vertex = values.get("vertex")
    if vertex is None or not all(k in vertex for k in "xyz"):
        raise MeshFileError(f"{path}: PLY needs a vertex element with x, y, z properties")
    verts = np.stack([np.asarray(vertex[k], np.float64) for k in "xyz"], 1)
    face = values.get("face", {})
    name = "vertex_indices" if "vertex_indices" in face else "vertex_index"
    faces = face.get(name, [])
    if any(
        p[-1] == name and p[0] != "list" for e, _, props in elements if e == "face" for p in props
    ):
        raise MeshFileError(
            f"{path}: face property {name} must be a list (property list "
            f"<count type> <index type> {name}); it is a single number"
        )
    colours = None
    rgb = ("red", "green", "blue")
    if all(k in vertex for k in rgb):  # integers scale by their type's full range
        kinds = {
            p[-1]: np.dtype(_PLY_TYPES[p[0]])
            for name, _, props in elements
            if name == "vertex"
            for p in props
            if p[0] != "list"
        }
        colours = np.stack(
            [
                np.asarray(vertex[k], np.float64)
                / (np.iinfo(kinds[k]).max if kinds[k].kind in "iu" else 1.0)
                for k in rgb
            ],
            1,
        )
    return verts, faces, colours


def _ply_header(path: Path, data: bytes):
    """(byte order or None for ASCII, [(element, count, [property...])], body bytes), every
    count checked against what the body can hold."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise MeshFileError(f"{path}: not a PLY file (no 'ply' ... 'end_header' header)")
    newline = data.find(b"\n", end)
    body = data[newline + 1 :] if newline >= 0 else b""
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
        elif (
            p[0] == "property"
            and elements
            and (
                (len(p) == 3 and p[1] in _PLY_TYPES)
                or (
                    len(p) == 5
                    and p[1] == "list"
                    and p[2] in _PLY_TYPES
                    and p[3] in _PLY_TYPES
                    and np.dtype(_PLY_TYPES[p[2]]).kind in "iu"
                    and np.dtype(_PLY_TYPES[p[3]]).kind in "iu"
                )
            )
        ):
            elements[-1][2].append(p[1:])
        else:
            raise MeshFileError(
                f"{where}: cannot read {line.strip()[:80]!r} (expected format "
                f"ascii|binary_little_endian|binary_big_endian 1.0, element "
                f"<name> <count>, property <type> <name>, or property list "
                f"<int type> <int type> <name>)"
            )
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
        least = sum(
            2 if fmt is None else np.dtype(_PLY_TYPES[q[1] if q[0] == "list" else q[0]]).itemsize
            for q in props
        )  # per entry: '0 ' per value, or the fixed bytes
        if count * least > room:
            raise MeshFileError(
                f"{path}: element {name} declares {count} entries, more than "
                f"the file's {len(body)} bytes of data can hold"
            )
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
                    fields += [
                        (p[-1] + "#n", self.dtype(p[1])),
                        (p[-1], self.dtype(p[2]), (first[p[-1]],)),
                    ]
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
                    out[p[-1]].append(self._take(name, self.dtype(p[2]), self._length(name, p[1])))
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
            raise MeshFileError(
                f"{self.path}: truncated in element {name} (the data ends "
                f"after {len(self.body)} bytes)"
            )
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
                        raise MeshFileError(
                            f"{self.path}: element {name}: a list of length "
                            f"{n} the file cannot hold"
                        )
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
            raise MeshFileError(
                f"{self.path}: element {name}: {token[:20]!r} is not {kind}"
            ) from None
