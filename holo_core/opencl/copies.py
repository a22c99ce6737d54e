"""Whole device arrays copied to and from the host, keeping no event on the device array
(pyopencl's ``get`` and ``set`` keep the host array alive with it). The floor under the FFT
backends (fft.py) and the array helpers (arrays.py): it imports neither, nor the runtime."""

from __future__ import annotations

import numpy as np
import pyopencl as cl
import pyopencl.array as cla

from ..validate import InputError


def read(a: cla.Array, out: np.ndarray | None = None) -> np.ndarray:
    """A new host array of the device array ``a``'s samples (C-contiguous ``a``), or ``out``
    (C-contiguous, ``a``'s shape and type) filled with them, waited for.
    pyopencl's ``get`` keeps each read's event on ``a``, and with it the host array it filled
    (up to 12 of them), so reading a reused array (a scratch buffer, an imager's pixels) that
    way keeps a dozen copies alive (gigabytes a worker for the tiles of a plate)."""
    if out is None:
        out = np.empty(a.shape, a.dtype)
    elif out.shape != a.shape or out.dtype != a.dtype or not out.flags.c_contiguous:
        raise InputError(
            f"a {out.shape} {out.dtype} array cannot take a device array of {a.shape} {a.dtype}"
        )
    cl.enqueue_copy(
        a.queue, out, a.base_data, src_offset=a.offset, wait_for=a.events, is_blocking=True
    )
    return out


def write(a: cla.Array, host) -> None:
    """Copy the host array ``host`` (``a``'s shape) into the device array ``a``, waited for,
    no event kept on ``a`` (:func:`read`: pyopencl's ``set`` keeps the host array alive)."""
    host = np.ascontiguousarray(host, a.dtype)
    if host.shape != a.shape:
        raise InputError(f"a {host.shape} array cannot fill a device array of {a.shape}")
    cl.enqueue_copy(
        a.queue, a.base_data, host, dst_offset=a.offset, wait_for=a.events, is_blocking=True
    )
