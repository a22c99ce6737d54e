"""Spectral convolution on a zero-padded grid: pad, FFT, multiply, inverse FFT, crop.

Transfer functions are made on the device and kept in the runtime's cache
(``holo_core.opencl.arrays.cached``). On a CPU device with FFTW the convolution runs on the
host, on the mapped buffers (``rt.fft.convolve``: the padding, the multiply and the crop inside
the FFT's passes), and a NumPy field never goes to the device; elsewhere every stage is a
device stage.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy import float32

from .. import validate
from ..opencl import as_device, associated, get_runtime, is_device_array
from ..opencl.arrays import embed, empty, read_first, window
from ..opencl.kernel import BUFFER, kernel
from ..validate import InputError, host_field
from . import grid

PROGRAM = associated(__file__)
MULTIPLY = kernel(PROGRAM, "multiply", a=BUFFER, t=BUFFER)
CHIRP_TRANSFER = kernel(PROGRAM, "chirp_transfer", t=BUFFER, wg=BUFFER, c=float32, d=float32)


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
    """Checked settings (λ, pitch (x, y), distance, offset in metres), the field where
    :func:`convolve` takes it (on the device, or a complex64 NumPy array where the runtime
    convolves on the host) and the padded grid: what every transfer-function propagation
    starts from."""
    wavelength, pitch = grid.wave_pair(wavelength, pitch)
    z = validate.within("distance", distance, validate.MAX_LENGTH)
    offset = validate.pair("offset", offset, "m", validate.MAX_LENGTH)
    padding = grid.padding_factor(padding)
    rt = get_runtime()
    if not is_device_array(field) and rt.fft.convolves:
        dev, from_host = np.ascontiguousarray(host_field("field", field), np.complex64), True
    else:
        rt, dev, from_host = as_device(field, check=False)  # convolve checks the DC term
    return Setup(
        wavelength,
        pitch,
        z,
        offset,
        padding,
        rt,
        dev,
        from_host,
        grid.padded_shape(dev.shape, padding),
    )


def convolve(rt, field, transfer, padded=None):
    """``field`` (h, w) convolved on the padded grid of ``transfer`` (H, W), cropped to (h, w).

    ``transfer`` (device) is in FFT order and carries the 1/(H·W) of the inverse FFT; where the
    runtime convolves on the host it may hold only the first quadrant of a transfer function
    even in both frequencies, with the grid's shape ``padded`` (:func:`symmetric`). ``field``
    is a device array, or a NumPy array (a NumPy result where the runtime convolves on the
    host). Raises ``InputError`` if the field holds NaN or Inf (seen in its DC term, the sum
    of all samples).
    """
    if rt.fft.convolves:
        return rt.fft.convolve(field, transfer, padded)
    if not is_device_array(field):
        field = rt.to_device(field, np.complex64)
    (h, w), (H, W) = field.shape, transfer.shape
    r0, c0 = (H - h) // 2, (W - w) // 2
    work = rt.scratch("convolve", (H, W))
    embed(rt, work, field, r0, c0)
    rt.fft.forward(work)
    if not np.isfinite(read_first(rt, work)).all():
        raise InputError("field must be finite; it holds NaN or infinite values")
    multiply(rt, work, transfer)
    rt.fft.backward(work)
    return window(rt, work, (h, w), r0, c0)


def symmetric(rt, offset) -> bool:
    """Whether a transfer function of no lateral ``offset`` (even in both frequencies) is made
    as its first quadrant only: where the runtime convolves on the host, which reads it
    mirrored (a quarter of the samples to make, keep and read)."""
    return rt.fft.convolves and tuple(offset) == (0.0, 0.0)


def chirp_transfer(rt, wg, carrier: float, distance: float):
    """The transfer function w·exp(i(c − d·g)) (FFT order, a new device array) from ``wg``,
    the (w, g) pairs of a chirp shared by every distance (w the weight with the inverse FFT's
    1/N, g = 2πf²/(1/λ + fz) [rad/m]): ``carrier`` c [rad], ``distance`` d [m]."""
    out = empty(rt, wg.shape)
    CHIRP_TRANSFER.launch(rt, (wg.size,), t=out, wg=wg, c=carrier, d=distance)
    return out


def multiply(rt, a, factor) -> None:
    """``a`` *= ``factor``, element-wise, on the device (both complex64, the same size)."""
    MULTIPLY.launch(rt, (a.size,), a=a, t=factor)
