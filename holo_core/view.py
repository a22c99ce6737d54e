"""The result both renderers return: a view's radiance, opacity and planar depth."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import preview

BACKGROUND_DEPTH = 1e10  # depth of empty pixels [m], as Blender's Cycles and Workbench


def channel_colours(count: int) -> np.ndarray:
    """How ``count`` colour channels of a hologram (in the order recorded) show in a view's
    R, G, B: a (count, 3) matrix. One channel is grey (R = G = B). Otherwise channel k gets
    the fully saturated hue 360°·k/count (0° red, 120° green, 240° blue: three channels are
    R, G, B as recorded, two are red and cyan, four red, chartreuse, cyan and violet), and
    each of R, G, B is the weighted mean of the channels that feed it, so that equal radiance
    in every channel shows white of that radiance."""
    if count == 1:
        return np.ones((1, 3))
    hue = 6.0 * np.arange(count)[:, None] / count  # in sextants
    k = (np.array([5.0, 3.0, 1.0])[None, :] + hue) % 6  # HSV at S = V = 1
    weights = 1 - np.clip(np.minimum(k, 4 - k), 0, 1)
    return weights / weights.sum(0)


def as_rgb(radiance: np.ndarray) -> np.ndarray:
    """``radiance`` (..., C) of C colour channels as (..., 3) R, G, B
    (:func:`channel_colours`)."""
    count = radiance.shape[-1]
    if count == 3:  # the identity, exactly
        return radiance
    return radiance @ channel_colours(count).astype(radiance.dtype)


@dataclass(frozen=True, eq=False)
class RenderResult:
    """A rendered view: radiance, opacity and depth, with the optics used.

    Parameters
    ----------
    rgb : (H, W, 3) float array
        Radiance; row 0 at the top.
    alpha : (H, W) float array
        Opacity.
    depth : (H, W) float array
        Planar camera-space depth [m] (BACKGROUND_DEPTH where empty).
    info : dict
        The optics used (aperture, resolution limit, wavelengths).
    coverage : (H, W) float array, optional
        The surfaces' share of each pixel (camera holograms).
    radiance : (H, W, 3) float array, optional
        The radiance before the division by ``coverage`` (camera holograms).

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import RenderResult
    >>> r = RenderResult(rgb=np.zeros((4, 6, 3)), alpha=np.ones((4, 6)), depth=np.ones((4, 6)))
    >>> r.rgb.shape, r.info
    ((4, 6, 3), {})
    """

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
        depth = (
            f"depth {preview.length(float(np.min(self.depth[seen])))} to "
            f"{preview.length(float(np.max(self.depth[seen])))}"
            if seen.any()
            else "no depth"
        )
        return (
            f"RenderResult({w}x{h}, rgb max {float(np.max(self.rgb)):.3g}, "
            f"{100 * float(np.mean(self.alpha)):.3g} % opaque, {depth}, info: "
            f"{', '.join(sorted(self.info)) or 'none'})"
        )

    def _repr_png_(self) -> bytes:
        """A notebook's picture: the rgb radiance in sRGB, at most 512 pixels a side."""
        return preview.png(preview.srgb(preview.thumbnail(self.rgb)))
