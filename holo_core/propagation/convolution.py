"""Spectral convolution on a zero-padded grid: pad, FFT, multiply, inverse FFT, crop.

Every array stays on the device; only transfer functions are made on the host (in float64) and
uploaded once into the runtime's cache (``holo_core.opencl.arrays.cached``).
"""

from __future__ import annotations

import numpy as np

from ..opencl.arrays import embed, read_first, window


def convolve(rt, field, transfer):
    """``field`` (h, w) convolved on the padded grid of ``transfer`` (H, W), cropped to (h, w).

    ``transfer`` is in FFT order and carries the 1/(H·W) of the inverse FFT. Raises
    ``ValueError`` if the field holds NaN or Inf (seen in its DC term, the sum of all samples).
    """
    (h, w), (H, W) = field.shape, transfer.shape
    r0, c0 = (H - h) // 2, (W - w) // 2
    work = rt.scratch("convolve", (H, W))
    embed(rt, work, field, r0, c0)
    cols = (c0, c0 + w)
    rt.fft.forward(work, cols)
    if not np.isfinite(read_first(rt, work)).all():
        raise ValueError("field must be finite; it holds NaN or infinite values")
    rt.kernel("spectral", "multiply")(rt.queue, (H * W,), None, work.data, transfer.data)
    rt.fft.backward(work, cols)
    return window(rt, work, (h, w), r0, c0)
