"""Speckle reduction (Sect. VII-E): temporal composition of renders with independent random
emitter phases (mean or maximum), and spatial low-pass plus downsampling."""

from __future__ import annotations

import numpy as np

from ..validate import InputError


def compose(intensities, how="mean") -> np.ndarray:
    """Combine N intensity images of the same view: 'mean' (speckle contrast falls as 1/√N
    for fully developed speckle) or 'max' (tends to (ΣA)² where few emitters interfere)."""
    stack = np.stack(intensities)
    if how == "mean":
        return stack.mean(0)
    if how == "max":
        return stack.max(0)
    raise InputError(f"composition must be 'mean' or 'max'; got {how!r}")


def downsample(image, factor: int) -> np.ndarray:
    """Average ``factor``×``factor`` blocks of (H·f, W·f[, C]): a box low-pass, then sampling."""
    if factor == 1:
        return image
    h, w = image.shape[0] // factor, image.shape[1] // factor
    blocks = image[:h * factor, :w * factor].reshape(h, factor, w, factor, *image.shape[2:])
    return blocks.mean((1, 3))


def box_mean(image, radius: int) -> np.ndarray:
    """The mean over (2r+1)² neighbourhoods, edges repeated: a symmetric low-pass, so a step
    edge keeps its half-way crossing where it was."""
    if radius == 0:
        return image
    image = np.asarray(image)  # float32 stays float32: a sum of nine carries 5e-7 at most
    a = np.pad(image if image.dtype.kind == "f" else image.astype(np.float64), radius,
               mode="edge")
    n = 2 * radius + 1
    h, w = a.shape[0] - 2 * radius, a.shape[1] - 2 * radius
    rows = a[:h].copy()  # the shifted copies summed in place: no running sum's rounding
    for i in range(1, n):  # to carry, and no temporary array for each shifted copy
        rows += a[i:i + h]
    out = rows[:, :w].copy()
    for j in range(1, n):
        out += rows[:, j:j + w]
    out *= out.dtype.type(1 / (n * n))
    return out


def pick_brightest(values, brightness, factor: int) -> np.ndarray:
    """Per ``factor``×``factor`` block, the value at its brightest sample (depth is not
    averaged across an edge)."""
    if factor == 1:
        return values
    h, w = values.shape[0] // factor, values.shape[1] // factor

    def blocks(a):
        return a[:h * factor, :w * factor].reshape(h, factor, w, factor).transpose(
            0, 2, 1, 3).reshape(h, w, factor * factor)

    best = np.argmax(blocks(brightness), -1)[..., None]
    return np.take_along_axis(blocks(values), best, -1)[..., 0]


def contrast(intensity, mask=None) -> float:
    """Speckle contrast σ/⟨I⟩ over ``mask`` (all pixels by default)."""
    i = np.asarray(intensity, np.float64)
    i = i[mask] if mask is not None else i.ravel()
    return float(i.std() / i.mean())
