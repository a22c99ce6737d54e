"""Inputs too large to hold: a mesh of broadcast views that owns no memory, and a stand-in for
the work that fails if it starts before its memory was counted."""

import numpy as np


def huge_mesh(vertices):
    """A mesh of ``vertices`` vertices and twice as many triangles that holds no memory of its
    own (broadcast views): what a refusal must see before any array of that size is made."""
    from holo_core.scene.mesh import Mesh

    return Mesh(
        vertices=np.broadcast_to(np.array([0.0, 0.0, -1.0]), (vertices, 3)),
        triangles=np.broadcast_to(np.array([0, 1, 2]), (2 * vertices, 3)),
    )


def never(*_, **__):
    raise AssertionError("the work started before its memory was counted")
