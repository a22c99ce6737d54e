"""Point sums on an 8 µm plate at 633 nm: a jittered lattice of points and a white square
mesh, the scenes the point-sum recorder's tests record."""

import numpy as np

from holo_core.scene.mesh import Mesh

LAM, PITCH = 633e-9, 8e-6


def cloud(rng, z):
    """Six points on a 3x2 lattice 20 pixels apart, jittered by up to a pixel."""
    lattice = np.array([(i, j) for i in (-1, 0, 1) for j in (-0.5, 0.5)]) * 20 * PITCH
    return np.c_[lattice + rng.uniform(-PITCH, PITCH, (6, 2)), np.full(6, z)]


def square(size, z, tilt_deg=0.0):
    """A white square mesh (two triangles) of side ``size`` [m] at depth ``z`` [m], tilted
    about x."""
    t = np.radians(tilt_deg)
    corners = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float) * size / 2
    rot = np.array([[1, 0, 0], [0, np.cos(t), -np.sin(t)], [0, np.sin(t), np.cos(t)]])
    return Mesh(
        vertices=corners @ rot.T + [0, 0, z],
        triangles=np.array([[0, 1, 2], [0, 2, 3]]),
        colours=np.ones((4, 3)),
    )
