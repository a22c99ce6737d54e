"""The holographic plate: its pose and size in the world. The hologram is its z = 0 plane,
viewers at z > 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import validate


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class Plate:
    """The holographic plate in the world: ``matrix_world`` (4, 4) plate-to-world pose [m]
    (rotation and translation; the hologram is its z = 0 plane, viewers at z > 0) and its
    physical ``width``, ``height`` [m]."""

    matrix_world: np.ndarray
    width: float
    height: float

    def __post_init__(self):
        m = validate.rigid_pose("plate matrix_world", self.matrix_world)
        object.__setattr__(self, "matrix_world", m)
        validate.positive("plate width", self.width, "m")
        validate.positive("plate height", self.height, "m")

    def to_plate(self, points) -> np.ndarray:
        """World points (N, 3) [m] in the plate's frame."""
        m = self.matrix_world
        return (np.asarray(points, np.float64) - m[:3, 3]) @ m[:3, :3]
