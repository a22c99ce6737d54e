"""Emitters from meshes and files."""

import numpy as np

from holo_core.io.mesh import read_mesh
from holo_core.scene.mesh import Mesh, sample_points


def test_area_uniform_sampling_with_vertex_colours(rng):
    # two triangles of areas 1 and 3 (cm²), red and blue
    v = np.array([[0, 0, -1], [1, 0, -1], [0, 2, -1], [10, 0, -1], [13, 0, -1], [10, 2, -1]]) * 1e-2
    cols = np.array([[1, 0, 0]] * 3 + [[0, 0, 1]] * 3, float)
    mesh = Mesh(vertices=v, triangles=np.array([[0, 1, 2], [3, 4, 5]]), colours=cols)
    pos, col = sample_points(mesh, 1e-3, seed=1)
    assert abs(len(pos) - 400) <= 1  # 4 cm² at one point per mm²
    share = (pos[:, 0] > 0.05).mean()
    assert abs(share - 0.75) < 0.05, f"area share of the big triangle: {share:.3f}"
    assert np.allclose(col[pos[:, 0] > 0.05], [0, 0, 1]) and np.allclose(pos[:, 2], -0.01)


def test_obj_and_ply_read_the_same_mesh(tmp_path):
    (tmp_path / "q.obj").write_text(
        "v 0 0 -1 1 0 0\nv 1 0 -1 0 1 0\nv 1 1 -1 0 0 1\nv 0 1 -1 1 1 1\nf 1 2 3 4\n"
    )
    (tmp_path / "q.ply").write_text(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 -1 255 0 0\n1 0 -1 0 255 0\n1 1 -1 0 0 255\n0 1 -1 255 255 255\n4 0 1 2 3\n"
    )
    a, b = read_mesh(tmp_path / "q.obj"), read_mesh(tmp_path / "q.ply")
    assert np.array_equal(a.triangles, [[0, 1, 2], [0, 2, 3]])
    assert np.array_equal(a.triangles, b.triangles) and np.allclose(a.vertices, b.vertices)
    assert np.allclose(a.colours, b.colours) and np.isclose(a.areas().sum(), 1.0)
