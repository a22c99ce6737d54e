"""OpenCL context, device choice and the program cache.

Device choice, by argument or the ``HOLO_DEVICE`` environment variable:

``gpu`` / ``cpu`` / ``accelerator``
    the first device of that type;
``P:D`` or ``P``
    platform P, device D (default 0), as listed by ``python -m holo_core devices``;
any other text
    the first device whose name contains it (case-insensitive).

Without a choice: the first GPU when one exists, else the first CPU device (PoCL's).
"""

from __future__ import annotations

import logging
import os
import threading
import warnings
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
import pyopencl as cl
import pyopencl.array as cla

log = logging.getLogger(__name__)

KERNELS = Path(__file__).parent / "kernels"
_TYPES = {"gpu": cl.device_type.GPU, "cpu": cl.device_type.CPU,
          "accelerator": cl.device_type.ACCELERATOR}


def all_devices() -> list[tuple[int, int, cl.Device]]:
    """Every (platform index, device index, device) OpenCL sees."""
    found = []
    for p, platform in enumerate(cl.get_platforms()):
        try:
            devices = platform.get_devices()
        except cl.Error:  # a platform with no device of any type
            devices = []
        found += [(p, d, dev) for d, dev in enumerate(devices)]
    return found


def choose_device(spec: str | None = None) -> cl.Device:
    """The device ``spec`` names (see the module docstring), or the default device."""
    spec = (spec if spec is not None else os.environ.get("HOLO_DEVICE", "")).strip()
    devices = all_devices()
    if not devices:
        raise RuntimeError("OpenCL sees no device; install pocl-binary-distribution "
                           "(pip) for a CPU device, or a GPU vendor's OpenCL driver")
    key = spec.lower()
    if not key:
        gpus = [d for _, _, d in devices if d.type & cl.device_type.GPU]
        cpus = [d for _, _, d in devices if d.type & cl.device_type.CPU]
        return (gpus or cpus or [devices[0][2]])[0]
    if key in _TYPES:
        match = [d for _, _, d in devices if d.type & _TYPES[key]]
    elif all(part.isdigit() for part in key.split(":")) and key.count(":") <= 1:
        p, _, d = key.partition(":")
        match = [dev for pi, di, dev in devices if pi == int(p) and di == int(d or 0)]
    else:
        match = [d for _, _, d in devices if key in d.name.lower()]
    if not match:
        listing = "; ".join(f"{p}:{d} {dev.name}" for p, d, dev in devices)
        raise ValueError(f"HOLO_DEVICE={spec!r} matches no device; allowed: 'gpu', 'cpu', "
                         f"'accelerator', 'P:D' or part of a device name. Devices: {listing}")
    return match[0]


def is_cpu(device: cl.Device) -> bool:
    return bool(device.type & cl.device_type.CPU)


@dataclass(eq=False)
class Runtime:
    """One OpenCL context and in-order queue, with cached programs, kernels and scratch buffers.

    Not thread-safe: use one runtime per thread (the default runtime is per process).
    """

    device: cl.Device
    context: cl.Context = field(init=False)
    queue: cl.CommandQueue = field(init=False)
    _programs: dict = field(default_factory=dict, init=False, repr=False)
    _kernels: dict = field(default_factory=dict, init=False, repr=False)
    _fft: object = field(default=None, init=False, repr=False)
    cache: dict = field(default_factory=dict, init=False, repr=False)

    def __post_init__(self):
        self.context = cl.Context([self.device])
        self.queue = cl.CommandQueue(self.context)
        log.info("OpenCL device: %s (%s)", self.device.name, self.device.platform.name)

    @cached_property  # device queries cost ~0.3 ms each, asked on every transform
    def is_cpu(self) -> bool:
        return is_cpu(self.device)

    @cached_property
    def has_fp64(self) -> bool:
        return bool(self.device.double_fp_config) or "cl_khr_fp64" in self.device.extensions

    @cached_property
    def real(self) -> type:
        """The kernels' ``real`` (coordinates, phases): float64 where the device has it."""
        return np.float64 if self.has_fp64 else np.float32

    @cached_property
    def real_options(self) -> tuple[str, ...]:
        """Build options that make the kernels' ``real`` match :attr:`real`."""
        return ("-DHOLO_FP64",) if self.has_fp64 else ()

    def program(self, name: str, options: tuple[str, ...] = ()) -> cl.Program:
        """``kernels/<name>.cl`` built for this context, once per option set."""
        key = (name, options)
        if key not in self._programs:
            source = (KERNELS / f"{name}.cl").read_text()
            opts = [f"-I{KERNELS}", *options]
            with warnings.catch_warnings():  # PoCL's clang notes vector ABIs; not our concern
                warnings.simplefilter("ignore", cl.CompilerWarning)
                self._programs[key] = cl.Program(self.context, source).build(options=opts)
        return self._programs[key]

    def kernel(self, program: str, name: str, options: tuple[str, ...] = ()) -> cl.Kernel:
        """A kernel object, created once (repeated retrieval from a program is slow)."""
        key = (program, name, options)
        if key not in self._kernels:
            self._kernels[key] = cl.Kernel(self.program(program, options), name)
        return self._kernels[key]

    @property
    def fft(self):
        """The FFT backend for this device (see :mod:`holo_core.opencl.fft`)."""
        if self._fft is None:
            from .fft import backend_for
            self._fft = backend_for(self)
        return self._fft

    def scratch(self, tag: str, shape: tuple[int, ...], dtype=np.complex64) -> cla.Array:
        """A reusable work array; its content is undefined on return."""
        key = ("scratch", tag, tuple(shape), np.dtype(dtype))
        if key not in self.cache:
            self.cache[key] = cla.empty(self.queue, shape, dtype)
        return self.cache[key]

    def to_device(self, host: np.ndarray, dtype=None) -> cla.Array:
        a = np.ascontiguousarray(host, dtype=dtype)
        return cla.to_device(self.queue, a)


_default: Runtime | None = None
_lock = threading.Lock()


def get_runtime() -> Runtime:
    """The process-wide runtime on the default device (``HOLO_DEVICE`` or auto)."""
    global _default
    with _lock:
        if _default is None:
            _default = Runtime(choose_device())
        return _default


def set_device(spec: str | None) -> Runtime:
    """Replace the process-wide runtime with one on the device ``spec`` names."""
    global _default
    with _lock:
        _default = Runtime(choose_device(spec))
        return _default
