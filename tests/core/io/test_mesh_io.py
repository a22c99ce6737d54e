"""The mesh files (PLY ASCII and binary, OBJ): the same geometry whatever the encoding, and a
damaged file named with its problem."""

import struct

import numpy as np
import pytest
from cli import CUBE_OBJ

from holo_core.io.mesh import MeshFileError, read_mesh

# an ASCII PLY of three vertices, its faces declared by FACES and listed in BODY
PLY = (
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    "property float z\n{faces}end_header\n0 0 0\n1 0 0\n0 1 0\n{body}"
)


def test_ply_with_an_empty_face_skips_it_with_a_warning(tmp_path):
    ply = PLY.format(
        faces="element face 2\nproperty list uchar int vertex_indices\n", body="0\n3 0 1 2\n"
    )
    (tmp_path / "m.ply").write_text(ply)
    with pytest.warns(UserWarning, match="1 face"):
        assert read_mesh(tmp_path / "m.ply").triangles.tolist() == [[0, 1, 2]]


@pytest.mark.parametrize(
    "body, problem",
    [
        ("element vertex 3\nproperty float x\nend_header\n0    1\n", "truncated"),
        ("element vertex 1\nproperty float y\nend_header\n0\n", "x, y, z"),
        ("element vertex 1\nproperty int64 x\nend_header\n0\n", "cannot read"),
        ("element junk 1000000000000\nend_header\n", "no properties"),
        ("element vertex 1000000000000\nproperty float x\nend_header\n0\n", "more than the file"),
        ("element vertex 1\nproperty float x\nproperty float x\nend_header\n0 0\n", "twice"),
    ],
)
def test_damaged_ply_names_the_file_and_the_problem(tmp_path, body, problem):
    path = tmp_path / "m.ply"
    path.write_bytes(b"ply\nformat ascii 1.0\n" + body.encode())
    with pytest.raises(MeshFileError, match=f"{path}.*{problem}"):
        read_mesh(path)
    path.write_bytes(b"ply\nformat ascii 1.0\n\xff\xfe" + body.encode())
    with pytest.raises(MeshFileError, match="ASCII"):
        read_mesh(path)


def test_binary_big_endian_ply_reads_as_little_endian(tmp_path):
    verts = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)]
    meshes = []
    for fmt, e in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
        head = (
            f"ply\nformat {fmt} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            f"property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
            f"end_header\n"
        ).encode()
        body = b"".join(struct.pack(e + "fff", *v) for v in verts)
        (tmp_path / f"{fmt}.ply").write_bytes(head + body + struct.pack(e + "B4i", 4, 0, 1, 3, 2))
        meshes.append(read_mesh(tmp_path / f"{fmt}.ply"))
    assert np.array_equal(meshes[0].vertices, meshes[1].vertices)
    assert meshes[0].triangles.tolist() == meshes[1].triangles.tolist() == [[0, 1, 3], [0, 3, 2]]


def test_obj_with_a_byte_order_mark_reads_the_same_geometry(tmp_path):
    (tmp_path / "a.obj").write_text(CUBE_OBJ)
    (tmp_path / "b.obj").write_bytes(b"\xef\xbb\xbf" + CUBE_OBJ.encode())
    a, b = read_mesh(tmp_path / "a.obj"), read_mesh(tmp_path / "b.obj")
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.triangles, b.triangles)


@pytest.mark.parametrize(
    "text, problem",
    [
        ("", "no vertices"),
        ("hello world\n", "no vertices"),
        ("v 0 0 0\n", "no faces"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "out of range"),
        ("v 0 0 x\n", "line 1"),
        ("v 0 0 0\nf 0 1 2\n", "line 2: OBJ indices start at 1"),
        ("v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "finite"),
    ],
)
def test_bad_obj_names_the_file_and_the_problem(tmp_path, text, problem):
    (tmp_path / "m.obj").write_text(text)
    with pytest.raises(MeshFileError, match=problem):
        read_mesh(tmp_path / "m.obj")


def test_a_ply_with_a_scalar_face_property_names_it(tmp_path):
    """A PLY whose face property vertex_indices is a scalar, not a list, is refused naming
    the property (not a TypeError)."""
    ply = PLY.format(faces="element face 1\nproperty int vertex_indices\n", body="0\n")
    (tmp_path / "m.ply").write_text(ply)
    with pytest.raises(MeshFileError, match="face property vertex_indices must be a list"):
        read_mesh(tmp_path / "m.ply")


@pytest.mark.parametrize(
    "text, index",
    [
        ("f 1 2 99999999999999999999999\n", "99999999999999999999999"),  # beyond int64: was -1
        ("f 1 2 9\n", "9"),  # OBJ's own numbering
    ],
)
def test_an_obj_index_out_of_range_is_reported_as_the_file_has_it(tmp_path, text, index):
    """An OBJ index out of range is reported as the file writes it, numbered from 1, also one
    beyond int64."""
    (tmp_path / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n" + text)
    with pytest.raises(
        MeshFileError, match=f"index {index} is out of range .*3 vertices, numbered from 1"
    ):
        read_mesh(tmp_path / "m.obj")
