"""Spectral convolution on a zero-padded grid: pad, FFT, multiply, inverse FFT, crop.

Every array stays on the device; only transfer functions are made on the host (in float64) and
uploaded once into a per-runtime cache. Padding and cropping are native fill and rectangle
copies (PoCL compiles them to memset/memcpy; a kernel was 6x slower).
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np
import pyopencl as cl
import pyopencl.array as cla

CACHE_BYTES = 512 * 2**20  # device memory kept for transfer functions, least recently used out
_ZERO = np.zeros(1, np.complex64)


def convolve(rt, field: cla.Array, transfer: cla.Array) -> cla.Array:
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
    dc = np.empty(1, np.complex64)
    cl.enqueue_copy(rt.queue, dc, work.data)
    if not np.isfinite(dc).all():
        raise ValueError("field must be finite; it holds NaN or infinite values")
    rt.kernel("spectral", "multiply")(rt.queue, (H * W,), None, work.data, transfer.data)
    rt.fft.backward(work, cols)
    return window(rt, work, (h, w), r0, c0)


def embed(rt, dst: cla.Array, src: cla.Array, r0: int, c0: int) -> None:
    """dst = zeros with ``src`` placed at row ``r0``, column ``c0``."""
    cl.enqueue_fill_buffer(rt.queue, dst.data, _ZERO, 0, dst.nbytes)
    _rect(rt, dst, src, (0, 0), (r0, c0), src.shape)


def window(rt, src: cla.Array, shape, r0: int, c0: int) -> cla.Array:
    """A new array of ``shape`` cut from ``src`` at row ``r0``, column ``c0``."""
    out = cla.empty(rt.queue, tuple(shape), np.complex64)
    _rect(rt, out, src, (r0, c0), (0, 0), shape)
    return out


def _rect(rt, dst, src, src_rc, dst_rc, shape):
    item = src.dtype.itemsize
    cl.enqueue_copy(rt.queue, dst.data, src.data,
                    src_origin=(src_rc[1] * item, src_rc[0]), dst_origin=(dst_rc[1] * item, dst_rc[0]),
                    region=(shape[1] * item, shape[0]),
                    src_pitches=(src.shape[1] * item,), dst_pitches=(dst.shape[1] * item,))


def cached(rt, key, make):
    """``(device array, notes)`` for ``make() -> (host array, notes)``, made once per runtime."""
    lru = rt.cache.setdefault("spectral-lru", OrderedDict())
    if key in lru:
        lru.move_to_end(key)
        return lru[key]
    host, notes = make()
    lru[key] = rt.to_device(host, np.complex64), notes
    while sum(v[0].nbytes for v in lru.values()) > CACHE_BYTES and len(lru) > 1:
        lru.popitem(last=False)
    return lru[key]
