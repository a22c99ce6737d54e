"""Memory budgets: a large allocation is checked before it is made, and refused with the size
it needs and the size there is, rather than ending in the allocator's or the driver's error.

``HOLO_MEMORY_LIMIT`` (bytes, or with a K/M/G suffix) caps the host budget below what the
system reports available, for render farms that share a machine.
"""

from __future__ import annotations

import math
import os
import threading

import numpy as np

from .validate import InputError

# [bytes] the alignment of aligned_zeros: a CPU OpenCL device reads such arrays in place (a buffer
# over host memory is copied unless it starts aligned)
PAGE = 4096
# of the available host or device memory one step may take (the rest: the interpreter, the OS, the
# driver)
SHARE = 0.8


def gib(nbytes: float) -> str:
    return f"{nbytes / 2**30:.3g} GiB"


def host_available() -> int:
    """Bytes the host can give now: MemAvailable, capped by ``HOLO_MEMORY_LIMIT``."""
    available = None
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    available = int(line.split()[1]) * 1024
    except OSError:
        pass
    if available is None:
        available = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    limit = limit_from_env()
    return min(available, limit) if limit else available


def limit_from_env() -> int | None:
    text = os.environ.get("HOLO_MEMORY_LIMIT", "").strip().upper()
    if not text:
        return None
    scale = {"K": 2**10, "M": 2**20, "G": 2**30}.get(text[-1], 1)
    try:
        value = float(text.rstrip("KMG")) * scale
    except ValueError:
        raise InputError(
            f"HOLO_MEMORY_LIMIT must be a size in bytes, e.g. 8G; got {text!r}"
        ) from None
    if not value > 0:
        raise InputError(f"HOLO_MEMORY_LIMIT must be > 0; got {text!r}")
    return int(value)


def host_share(budget: float | None = None) -> float:
    """Bytes one step may take: SHARE of the host's available memory, and at most
    ``budget`` [bytes] where one is set."""
    share = SHARE * host_available()
    return share if budget is None else min(share, budget)


def check_host(what: str, nbytes: float) -> None:
    """Refuse ``what`` when it needs more than the host's share of available memory."""
    budget = host_share()
    if nbytes > budget:
        raise InputError(
            f"{what} needs {gib(nbytes)} of memory; {gib(budget)} is available "
            f"(lower the resolution or the size, or free memory)"
        )


def check_device(rt, what: str, nbytes: float, largest: float) -> None:
    """Refuse ``what`` on the OpenCL device ``rt`` when its buffers (``nbytes`` in all, the
    ``largest`` one buffer) exceed the device's memory or its largest allocation."""
    dev = rt.device
    if largest > dev.max_mem_alloc_size:
        raise InputError(
            f"{what} needs a {gib(largest)} buffer; {dev.name.strip()} allocates "
            f"at most {gib(dev.max_mem_alloc_size)}"
        )
    if nbytes > SHARE * dev.global_mem_size:
        raise InputError(
            f"{what} needs {gib(nbytes)} of device memory; {dev.name.strip()} has "
            f"{gib(dev.global_mem_size)}"
        )


def aligned_zeros(shape, dtype=np.complex64) -> np.ndarray:
    """A C-contiguous array of zeros whose data starts on a PAGE boundary: a plate's samples
    made so are read in place by a CPU OpenCL device (:func:`holo_core.opencl.arrays.
    host_buffer`), a view then copying none of them."""
    dtype = np.dtype(dtype)
    return _aligned(np.zeros(math.prod(shape) * dtype.itemsize + PAGE, np.uint8), shape, dtype)


def _aligned(raw: np.ndarray, shape, dtype) -> np.ndarray:
    start = -raw.ctypes.data % PAGE
    return raw[start : start + math.prod(shape) * dtype.itemsize].view(dtype).reshape(shape)


SLACK = 0.25  # HostBuffers' new buffers are this much larger than asked


class HostBuffers:
    """Page-aligned host arrays (as :func:`aligned_zeros`, their contents left as they are)
    handed out and handed back, so that recordings of like size one after another (a plate
    set's parts) fill the same memory. Memory a process touches for the first time the
    operating system maps and zeroes page by page: about 0.2 s a GiB on a bare machine, and
    up to 9 s on a virtual machine that hands freed memory back to its host (the development
    machine: 43 % of the shot's recording process in the kernel's page clearing). At most
    ``kept`` buffers wait for reuse; handing back is thread-safe (a writer thread's)."""

    def __init__(self, kept: int = 4):
        self.kept = kept
        self._free: list[np.ndarray] = []
        self._lock = threading.Lock()

    def take(self, shape, dtype=np.complex64) -> np.ndarray:
        """An array of ``shape`` and ``dtype``: a handed-back buffer large enough (the
        smallest such), else a new one of zeros, SLACK larger."""
        dtype = np.dtype(dtype)
        need = math.prod(shape) * dtype.itemsize + PAGE
        with self._lock:
            fits = [i for i, b in enumerate(self._free) if b.nbytes >= need]
            if fits:  # (by place: arrays compare element by element)
                raw = self._free.pop(min(fits, key=lambda i: self._free[i].nbytes))
                return _aligned(raw, shape, dtype)
        # a new buffer SLACK larger, that the next parts (a little larger or smaller) fit: its
        # pages beyond what they use are never touched, and so cost no memory
        return _aligned(np.zeros(int(need * (1 + SLACK)), np.uint8), shape, dtype)

    def give(self, array: np.ndarray) -> None:
        """Hand ``array`` (one :meth:`take` gave) back: the caller holds no view of it any
        more. Beyond ``kept``, the smallest is let go."""
        raw = array
        while raw.base is not None:
            raw = raw.base
        with self._lock:
            self._free.append(raw)
            while len(self._free) > self.kept:
                self._free.pop(min(range(len(self._free)), key=lambda i: self._free[i].nbytes))
