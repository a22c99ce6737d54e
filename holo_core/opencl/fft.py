"""2-D FFTs of complex64 device arrays, in place and unnormalised in both directions.

Callers fold the 1/N of the inverse into something they multiply anyway (a transfer function).
The backend depends on the device (``HOLO_FFT`` overrides: ``fftw``, ``vkfft``, ``numpy``):

* CPU devices keep buffers in host memory: FFTW (pyfftw) transforms the mapped buffer in place,
  with no copy. Plans are cached per process. By default they are FFTW_ESTIMATE plans, which
  depend on the sizes alone, so a frame is bit-identical across runs, processes and machines
  of one kind, with or without a cache. ``HOLO_FFTW_PLANNER=measure`` (or ``patient``) times
  the candidates instead and keeps FFTW wisdom in the user's cache directory: sometimes faster,
  but its choice follows the machine's load, so results may differ in the last bits.
* GPU devices: pyvkfft when it is importable; otherwise a host FFT through copies (logged).

``cols=(c0, c1)`` tells a transform that only those columns matter: for ``forward`` the others
are zero (zero padding), for ``backward`` only those columns of the result are read. The
strided column pass, the slow one, then skips the rest (2048² with 2x padding: 9.4 ms instead
of 13 ms for the full 2-D plan on the development machine).
"""

from __future__ import annotations

import logging
import os
import pickle
import platform

import numpy as np
import pyopencl as cl

from ..validate import InputError

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
            log.warning("pyvkfft is not importable: FFTs on %s go through host copies",
                        runtime.device.name)
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

    def __init__(self, runtime, arr):
        self.q, self.arr, self.copy = runtime.queue, arr, not runtime.is_cpu

    def __enter__(self) -> np.ndarray:
        if self.copy:
            self.host = self.arr.get()
        else:
            flags = cl.map_flags.READ | cl.map_flags.WRITE
            self.host, _ = cl.enqueue_map_buffer(self.q, self.arr.base_data, flags,
                                                 self.arr.offset, self.arr.shape, self.arr.dtype)
        return self.host

    def __exit__(self, *exc):
        if self.copy:
            self.arr.set(self.host)
        else:
            self.host.base.release(self.q)


class FFTW:
    name = "fftw"

    def __init__(self, runtime):
        import pyfftw
        self._pyfftw = pyfftw
        self.runtime = runtime
        self.threads = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") \
            else (os.cpu_count() or 1)
        effort = os.environ.get("HOLO_FFTW_PLANNER", "estimate").strip().upper()
        if effort not in ("ESTIMATE", "MEASURE", "PATIENT"):
            raise InputError(f"HOLO_FFTW_PLANNER={effort!r}; allowed: estimate, measure, patient")
        self.flags = (f"FFTW_{effort}",)
        self.plans = {}
        self.wisdom = effort != "ESTIMATE"  # wisdom would let measured plans into estimates
        if self.wisdom:
            self._load_wisdom()

    def forward(self, arr, cols=None):
        self._run(arr, cols, "FFTW_FORWARD")

    def backward(self, arr, cols=None):
        self._run(arr, cols, "FFTW_BACKWARD")

    def _run(self, arr, cols, direction):
        with _Mapped(self.runtime, arr) as host:
            for plan, view in self._passes(host, cols, direction):
                plan.update_arrays(view, view)
                plan.execute()

    def _passes(self, host, cols, direction):
        if cols is None or tuple(cols) == (0, host.shape[1]):
            return [(self._plan(host.shape, None, direction), host)]
        c0, c1 = cols
        col_pass = (self._plan(host.shape, (c0, c1), direction), host[:, c0:c1])
        row_pass = (self._plan(host.shape, "rows", direction), host)
        return [col_pass, row_pass] if direction == "FFTW_FORWARD" else [row_pass, col_pass]

    def _plan(self, shape, part, direction):
        key = (shape, part, direction)
        if key not in self.plans:
            pyfftw = self._pyfftw
            work = pyfftw.empty_aligned(shape, np.complex64)
            if part is None:
                view, axes = work, (0, 1)
            elif part == "rows":
                view, axes = work, (1,)
            else:
                view, axes = work[:, part[0]:part[1]], (0,)
            self.plans[key] = pyfftw.FFTW(view, view, axes=axes, direction=direction,
                                          flags=self.flags, threads=self.threads,
                                          planning_timelimit=10.0)
            if self.wisdom:
                self._save_wisdom()
        return self.plans[key]

    @staticmethod
    def _wisdom_path():
        from platformdirs import user_cache_dir
        return os.path.join(user_cache_dir("holo"), f"fftw-wisdom-{platform.node()}.pickle")

    def _load_wisdom(self):
        try:
            with open(self._wisdom_path(), "rb") as f:
                self._pyfftw.import_wisdom(pickle.load(f))
        except (OSError, pickle.UnpicklingError, EOFError, TypeError, ValueError):
            pass  # no or stale wisdom: plans are measured again

    def _save_wisdom(self):
        path = self._wisdom_path()
        try:
            os.makedirs(os.path.dirname(path), exist_ok=True)
            tmp = f"{path}.{os.getpid()}.tmp"
            with open(tmp, "wb") as f:
                pickle.dump(self._pyfftw.export_wisdom(), f)
            os.replace(tmp, path)
        except OSError as e:  # a read-only home is no reason to fail a transform
            log.debug("FFTW wisdom not saved: %s", e)


class VkFFT:
    name = "vkfft"

    def __init__(self, runtime):
        from pyvkfft.opencl import VkFFTApp
        self._App = VkFFTApp
        self.runtime = runtime
        self.apps = {}

    def _app(self, shape):
        if shape not in self.apps:
            self.apps[shape] = self._App(shape, np.complex64, self.runtime.queue, ndim=2,
                                         inplace=True, norm=0)
        return self.apps[shape]

    def forward(self, arr, cols=None):
        self._app(arr.shape).fft(arr, arr)

    def backward(self, arr, cols=None):
        self._app(arr.shape).ifft(arr, arr)


class HostNumpy:
    name = "numpy"

    def __init__(self, runtime):
        self.runtime = runtime

    def forward(self, arr, cols=None):
        with _Mapped(self.runtime, arr) as host:
            host[...] = np.fft.fft2(host)

    def backward(self, arr, cols=None):
        with _Mapped(self.runtime, arr) as host:
            host[...] = np.fft.ifft2(host) * host.size
