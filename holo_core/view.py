"""Image generation: a camera anywhere in front of the hologram (Sect. VII).

Per wavelength: the reconstructed wave (Sect. VI) is carried to the camera's aperture plane by
tilt plus offset propagation (Sect. IV-D); the aperture is cut out as a disc, apodized by the
cosine window of Fig. 9 and, for a thin lens, multiplied by Eq. 24's phase; its angular
spectrum is then read at each pixel's direction cosines (Eq. 22) by bilinear weighting. The
image holds the complex amplitude A(α/λ, β/λ) [field·m²] of the plane wave from each pixel's
direction; the radiance is |A|² / (λ²·∫w²) (power per aperture area and projected solid
angle), so a surface of point emitters of intensity I and density σ shows radiance σ·I.
"""

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
