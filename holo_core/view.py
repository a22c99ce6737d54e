"""The result both renderers return: a view's radiance, opacity and planar depth."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

BACKGROUND_DEPTH = 1e10     # depth of empty pixels [m], as Blender's Cycles and Workbench


@dataclass(frozen=True, eq=False)
class RenderResult:
    """A rendered view: ``rgb`` (H, W, 3) radiance, ``alpha`` (H, W) opacity, ``depth``
    (H, W) planar camera-space depth [m] (BACKGROUND_DEPTH where empty); row 0 at the top.
    ``info`` holds the optics used (aperture, resolution limit, wavelengths)."""

    rgb: np.ndarray
    alpha: np.ndarray
    depth: np.ndarray
    info: dict = field(default_factory=dict)
    coverage: np.ndarray | None = None  # the surfaces' share of each pixel (camera holograms)
    radiance: np.ndarray | None = None  # (H, W, 3) before the division by coverage (idem)
