"""The tutorials' small scene: a warm cube partly hiding a blue ball, about 0.3 m behind a
6 cm plate at z = 0, seen by 50 mm f/2.8 cameras 0.3 m in front of it (metres throughout)."""

import numpy as np

import holo_core as hc

TARGET = (0.0, 0.0, -0.32)


def box(centre, size, colour):
    """A cube of edge ``size`` [m] at ``centre`` [m], one linear-RGB ``colour``."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    triangles = [t for a, b, c, d in faces for t in ((a, b, c), (a, c, d))]
    return hc.Mesh(
        vertices=corners * size / 2 + np.asarray(centre),
        triangles=np.array(triangles),
        colours=np.tile(colour, (8, 1)),
    )


def ball(centre, radius, colour, n=24):
    """A UV sphere of ``radius`` [m] at ``centre`` [m]."""
    th, ph = np.meshgrid(
        np.linspace(0, np.pi, n + 1), np.linspace(0, 2 * np.pi, 2 * n + 1), indexing="ij"
    )
    v = np.stack([np.sin(th) * np.cos(ph), np.cos(th), np.sin(th) * np.sin(ph)], -1)
    idx = np.arange(v.shape[0] * v.shape[1]).reshape(v.shape[:2])
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, :-1], idx[1:, 1:]
    triangles = np.concatenate(
        [np.stack([a, c, d], -1).reshape(-1, 3), np.stack([a, d, b], -1).reshape(-1, 3)]
    )
    vertices = v.reshape(-1, 3) * radius + np.asarray(centre)
    return hc.Mesh(
        vertices=vertices, triangles=triangles, colours=np.tile(colour, (len(vertices), 1))
    )


def meshes():
    return [
        box((-0.008, -0.003, -0.30), 0.036, (0.9, 0.3, 0.1)),
        ball((0.016, 0.008, -0.355), 0.024, (0.2, 0.5, 0.9)),
    ]


def camera(x=0.0, resolution=(160, 90)):
    """A 50 mm f/2.8 camera at (x, 0, 0.3) m looking at the objects, focused at 0.6 m."""
    return hc.Camera(
        matrix_world=hc.look_at((x, 0.0, 0.3), TARGET, up=(0, 1, 0)),
        lens=50,
        resolution=resolution,
        fstop=2.8,
        focus_distance=0.6,
    )
