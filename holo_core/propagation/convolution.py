"""Spectral convolution on a zero-padded grid: pad, FFT, multiply, inverse FFT, crop.

Every array stays on the device; only transfer functions are made on the host (in float64) and
uploaded once into the runtime's cache (``holo_core.opencl.arrays.cached``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .. import validate
from ..opencl import as_device, associated
from ..opencl.arrays import embed, read_first, window
from ..validate import InputError
from . import grid

PROGRAM = associated(__file__)


class Setup(NamedTuple):
    wavelength: float
    pitch: tuple[float, float]  # (x, y)
    z: float
    offset: tuple[float, float]
    padding: float
    rt: object
    dev: object
    from_host: bool
    shape: tuple[int, int]


def convolution_setup(field, wavelength, pitch, distance, offset, padding) -> Setup:
    """Checked settings (λ, pitch (x, y), distance, offset in metres), the field on the device
    and the padded grid: what every transfer-function propagation starts from."""
    wavelength, pitch = grid.wave_pair(wavelength, pitch)
    z = validate.within("distance", distance, validate.MAX_LENGTH)
    offset = validate.pair("offset", offset, "m", validate.MAX_LENGTH)
    padding = grid.padding_factor(padding)
    rt, dev, from_host = as_device(field, check=False)  # convolve checks the DC term
    return Setup(wavelength, pitch, z, offset, padding, rt, dev, from_host,
                 grid.padded_shape(dev.shape, padding))


def convolve(rt, field, transfer, chirp=None):
    """``field`` (h, w) convolved on the padded grid of ``transfer`` (H, W), cropped to (h, w).

    ``transfer`` is in FFT order and carries the 1/(H·W) of the inverse FFT. With ``chirp`` =
    (c [rad], d [m]) it holds (w, g) pairs instead, and the transfer function is w·exp(i(c-d·g)).
    Raises ``ValueError`` if the field holds NaN or Inf (seen in its DC term, the sum of all
    samples).
    """
    (h, w), (H, W) = field.shape, transfer.shape
    r0, c0 = (H - h) // 2, (W - w) // 2
    work = rt.scratch("convolve", (H, W))
    embed(rt, work, field, r0, c0)
    cols = (c0, c0 + w)
    rt.fft.forward(work, cols)
    if not np.isfinite(read_first(rt, work)).all():
        raise InputError("field must be finite; it holds NaN or infinite values")
    if chirp is None:
        multiply(rt, work, transfer)
    else:
        rt.kernel(PROGRAM, "multiply_chirp")(rt.queue, (H * W,), None, work.data,
                                             transfer.data, *map(np.float32, chirp))
    rt.fft.backward(work, cols)
    return window(rt, work, (h, w), r0, c0)


def multiply(rt, a, factor) -> None:
    """``a`` *= ``factor``, element-wise, on the device (both complex64, the same size)."""
    rt.kernel(PROGRAM, "multiply")(rt.queue, (a.size,), None, a.data, factor.data)
