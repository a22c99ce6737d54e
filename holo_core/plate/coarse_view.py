"""A coarse view, the preview while a camera moves: the camera with pixels a whole factor
larger each way (the same rays through the same pupil), and its picture upsampled back to the
camera's pixels.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..scene.camera import Camera


def coarser(camera: Camera, factor: int) -> Camera:
    """``camera`` with pixels ``factor`` times larger each way: ⌈W/factor⌉ × ⌈H/factor⌉ of
    them, pixel (i, j) spanning the camera's pixels factor·i … factor·(i + 1) − 1 (the same
    rays; the last row and column may reach beyond the image)."""
    if factor == 1:
        return camera
    w, h = camera.resolution
    s, dx, dy, ycor = camera._plane()
    ws, hs = -(-w // factor), -(-h // factor)
    # the same pixel centres' tangents at factor times the pixel: sensor, then shifts, fitted
    # horizontally (tangent = (col − W/2 + dx)/s; Camera._plane)
    sx = ws / 2 + (dx - w / 2) / factor
    sy = (0.5 * ycor * h + dy) / factor - 0.5 * ycor * hs
    return replace(
        camera,
        resolution=(ws, hs),
        sensor_fit="HORIZONTAL",
        sensor_width=camera.lens * ws * factor / s,
        shift_x=sx / ws,
        shift_y=sy / ws,
    )


def upsampled(a: np.ndarray, factor: int, shape) -> np.ndarray:
    """``a`` (h, w, ...) of pixels ``factor`` times larger (:func:`coarser`) resampled
    bilinearly at the (H, W) = ``shape`` pixels' centres, the edges held."""
    if factor == 1:
        return a
    out = a
    for axis, n in enumerate(shape):
        at = (np.arange(n) + 0.5) / factor - 0.5
        at = np.clip(at, 0, a.shape[axis] - 1)
        i0 = np.floor(at).astype(int)
        i1 = np.minimum(i0 + 1, a.shape[axis] - 1)
        t = (at - i0).astype(a.dtype)
        t = t.reshape((-1,) + (1,) * (out.ndim - axis - 1))
        lo, hi = np.take(out, i0, axis=axis), np.take(out, i1, axis=axis)
        out = lo + (hi - lo) * t
    return out
