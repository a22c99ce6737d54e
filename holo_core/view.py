"""The result both renderers return: a view's radiance, opacity and planar depth."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import preview

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

    def __repr__(self) -> str:
        """One line: resolution, brightness, coverage and depth range; no pixels."""
        h, w = np.shape(self.alpha)[:2]
        seen = np.asarray(self.depth) < BACKGROUND_DEPTH
        depth = (f"depth {preview.length(float(np.min(self.depth[seen])))} to "
                 f"{preview.length(float(np.max(self.depth[seen])))}" if seen.any()
                 else "no depth")
        return (f"RenderResult({w}x{h}, rgb max {float(np.max(self.rgb)):.3g}, "
                f"{100 * float(np.mean(self.alpha)):.3g} % opaque, {depth}, info: "
                f"{', '.join(sorted(self.info)) or 'none'})")

    def _repr_png_(self) -> bytes:
        """A notebook's picture: the rgb radiance in sRGB, at most 512 pixels a side."""
        return preview.png(preview.srgb(preview.thumbnail(self.rgb)))
