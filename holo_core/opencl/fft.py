"""2-D FFTs of complex64 device arrays, in place and unnormalised in both directions: of an
(H, W) array, or of each plane of a (P, H, W) stack.

Callers fold the 1/N of the inverse into something they multiply anyway (a transfer function).
The backend depends on the device (``HOLO_FFT`` overrides: ``fftw``, ``vkfft``, ``numpy``):

* CPU devices keep buffers in host memory: FFTW (pyfftw) transforms the mapped buffer in place,
  with no copy, in fixed blocks of columns and rows over threads, its plans measured once per
  machine and kept as wisdom (:mod:`.host_fft`: bit-identical across processes and thread
  counts). It also does the padded convolution on the host (:meth:`FFTW.convolve`), with the
  padding, the multiply and the crop inside its passes.
* GPU devices: pyvkfft when it is importable; otherwise a host FFT through copies (logged).

``nonzero=(row ranges, column ranges)`` tells a transform where its input is non-zero: the
caller calls :meth:`clear` with the same ranges before it writes there, and then need not
zero the rest (FFTW writes those zeros inside its passes, and skips the columns that hold
none; the other backends fill the array in ``clear``). ``read`` (column ranges) tells an
inverse transform which columns of its result will be read.
"""

from __future__ import annotations

import contextlib
import logging
import os

import numpy as np
import pyopencl as cl
import pyopencl.array as cla

from ..validate import InputError
from .copies import read, write

log = logging.getLogger(__name__)


def backend_for(runtime):
    choice = os.environ.get("HOLO_FFT", "").strip().lower()
    if choice not in ("", "fftw", "vkfft", "numpy"):
        raise InputError(f"HOLO_FFT={choice!r}; allowed: 'fftw', 'vkfft', 'numpy' or unset")
    if choice == "vkfft" or (not choice and not runtime.is_cpu):
        try:
            return VkFFT(runtime)
        except ImportError:
            if choice:
                raise
            log.warning(
                "pyvkfft is not importable: FFTs on %s go through host copies", runtime.device.name
            )
    if choice in ("", "fftw"):
        try:
            return FFTW(runtime)
        except ImportError:
            if choice:
                raise
            log.warning("pyfftw is not importable: using numpy.fft (several times slower)")
    return HostNumpy(runtime)


class _Mapped:
    """The device array as a host array: a zero-copy map on CPU devices, a copy elsewhere."""

    def __init__(self, runtime, arr, flags=cl.map_flags.READ | cl.map_flags.WRITE):
        self.q, self.arr, self.copy, self.flags = runtime.queue, arr, not runtime.is_cpu, flags

    def __enter__(self) -> np.ndarray:
        if self.copy:
            self.host = read(self.arr)
        else:
            self.host, _ = cl.enqueue_map_buffer(
                self.q,
                self.arr.base_data,
                self.flags,
                self.arr.offset,
                self.arr.shape,
                self.arr.dtype,
            )
        return self.host

    def __exit__(self, *exc):
        if self.copy:
            if self.flags != cl.map_flags.READ:
                write(self.arr, self.host)
        else:
            self.host.base.release(self.q)


class FFTW:
    name = "fftw"
    convolves = True  # :meth:`convolve` on host arrays (propagation/convolution.py uses it)

    def __init__(self, runtime):
        from .host_fft import HostFFT

        self.runtime = runtime
        self.host = HostFFT()

    def clear(self, arr, nonzero) -> None:
        """Nothing: the passes zero what lies outside ``nonzero``."""

    def forward(self, arr, nonzero=None, read=None):
        self._planes(arr, "FFTW_FORWARD", nonzero, read)

    def backward(self, arr, nonzero=None, read=None):
        self._planes(arr, "FFTW_BACKWARD", nonzero, read)

    def _planes(self, arr, direction, nonzero, read):
        with _Mapped(self.runtime, arr) as host:  # a stack mapped once, its planes in turn
            for plane in host.reshape((-1,) + host.shape[-2:]):
                self.host.transform(plane, direction, nonzero, read)

    def convolve(self, field, transfer, padded=None):
        """The padded convolution of ``field`` (h, w; NumPy or device) by ``transfer`` (H, W,
        device, FFT order, with the inverse FFT's 1/(H·W); or its first quadrant, given the
        grid's shape ``padded``: :meth:`.host_fft.HostFFT.convolve`), cropped to (h, w): a NumPy
        array for a NumPy field, else a new device array. Raises ``InputError`` where the
        field is not finite (its DC term)."""
        rt = self.runtime
        on_device = not isinstance(field, np.ndarray)
        out = (
            cla.empty(rt.queue, field.shape, np.complex64)
            if on_device
            else np.empty(field.shape, np.complex64)
        )
        with contextlib.ExitStack() as maps:
            src = (
                maps.enter_context(_Mapped(rt, field, cl.map_flags.READ))
                if on_device
                else np.asarray(field, np.complex64)
            )
            dst = (
                maps.enter_context(_Mapped(rt, out, cl.map_flags.WRITE_INVALIDATE_REGION))
                if on_device
                else out
            )
            tf = maps.enter_context(_Mapped(rt, transfer, cl.map_flags.READ))
            dc = self.host.convolve(src, tf, dst, padded)
        if not np.isfinite(dc):
            raise InputError("field must be finite; it holds NaN or infinite values")
        return out


class VkFFT:
    name = "vkfft"
    convolves = False

    def __init__(self, runtime):
        from pyvkfft.opencl import VkFFTApp

        self._App = VkFFTApp
        self.runtime = runtime
        self.apps = {}

    def _app(self, shape):
        if shape not in self.apps:
            self.apps[shape] = self._App(
                shape, np.complex64, self.runtime.queue, ndim=2, inplace=True, norm=0
            )
        return self.apps[shape]

    def clear(self, arr, nonzero) -> None:
        arr.fill(0)

    def forward(self, arr, nonzero=None, read=None):
        self._app(arr.shape).fft(arr, arr)

    def backward(self, arr, nonzero=None, read=None):
        self._app(arr.shape).ifft(arr, arr)


class HostNumpy:
    name = "numpy"
    convolves = False

    def __init__(self, runtime):
        self.runtime = runtime

    def clear(self, arr, nonzero) -> None:
        arr.fill(0)

    def forward(self, arr, nonzero=None, read=None):
        with _Mapped(self.runtime, arr) as host:
            host[...] = np.fft.fft2(host)

    def backward(self, arr, nonzero=None, read=None):
        with _Mapped(self.runtime, arr) as host:
            host[...] = np.fft.ifft2(host) * (host.shape[-2] * host.shape[-1])
