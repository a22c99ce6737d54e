"""OpenCL context, device choice and the program cache.

A device counts only when it passes a probe: a small program (the kernels' complex header,
float arithmetic, float64 where the device claims it) builds and runs with the right answer.
Devices that fail are skipped with the reason logged; ``python -m holo_core devices`` lists
every device with its status.

Device choice, by argument or the ``HOLO_DEVICE`` environment variable:

``gpu`` / ``cpu`` / ``accelerator``
    the first usable device of that type;
``P:D`` or ``P``
    platform P, device D (default 0), as listed by ``python -m holo_core devices``;
any other text
    the first usable device whose name or platform name contains it (case-insensitive).

Without a choice, the first usable device in this order: GPUs; Intel's CPU runtime (the
fastest CPU driver measured, and the one that runs on every current x86-64 CPU); PoCL (its
PyPI build predates AMD Zen 4/5 and fails to build programs there); anything else.
"""

from __future__ import annotations

import logging
import os
import sys
import threading
import time
import warnings
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
import platformdirs
import pyopencl as cl
import pyopencl.array as cla

from ..validate import InputError
from .fft import backend_for

log = logging.getLogger(__name__)
# drivers that print build logs make pyopencl warn for its own generated kernels
warnings.filterwarnings("ignore", category=cl.CompilerWarning)

HEADERS = Path(__file__).parent  # the kernels' shared headers (holo_complex.h, …)
_TYPES = {
    "gpu": cl.device_type.GPU,
    "cpu": cl.device_type.CPU,
    "accelerator": cl.device_type.ACCELERATOR,
}
# CPU drivers in order of preference, by platform name (see the module docstring)
_CPU_DRIVERS = ("intel", "portable computing language")
# LLVM CPU names with AVX-512, for PoCL, which compiles for the target its version string names
AVX512_TARGETS = {
    "skylake-avx512",
    "cascadelake",
    "cooperlake",
    "cannonlake",
    "icelake-client",
    "icelake-server",
    "tigerlake",
    "rocketlake",
    "sapphirerapids",
    "graniterapids",
    "emeraldrapids",
    "znver4",
    "znver5",
    "knl",
    "knm",
}


def all_devices() -> list[tuple[int, int, cl.Device]]:
    """Every device OpenCL sees, usable or not.

    Returns
    -------
    list of (int, int, pyopencl.Device)
        (platform index, device index, device), in listing order (the ``P:D`` that
        ``HOLO_DEVICE`` and ``python -m holo_core devices`` use).

    See Also
    --------
    device_table : the same devices with their status.

    Examples
    --------
    >>> from holo_core.opencl import all_devices
    >>> for p, d, device in all_devices():   # doctest: +SKIP
    ...     print(f"{p}:{d} {device.name.strip()}")
    0:0 AMD EPYC
    1:0 pthread-AMD EPYC
    """
    found = []
    for p, platform in enumerate(cl.get_platforms()):
        try:
            devices = platform.get_devices()
        except cl.Error:  # a platform with no device of any type
            devices = []
        found += [(p, d, dev) for d, dev in enumerate(devices)]
    return found


_PROBE = """
#include "holo_complex.h"
__kernel void probe(__global const float *x, __global float2 *y)
{
    int i = get_global_id(0);
    y[i] = cmul(cexpi(x[i]), (float2)(sqrt(x[i]), 1.0f));
#ifdef HOLO_FP64
    y[i].x += (float)((double)x[i] * 1e-12);
#endif
}
"""
_probed: dict[int, str] = {}  # device pointer -> "" (usable) or why not


def _probe(device: cl.Device) -> str:
    x = np.linspace(0.0, 40.0, 256, dtype=np.float32)
    want = np.exp(1j * x.astype(np.float64)) * (np.sqrt(x.astype(np.float64)) + 1j)
    fp64 = _has_fp64(device)
    if fp64:
        want = want + x * 1e-12
    try:
        ctx = cl.Context([device])
        queue = cl.CommandQueue(ctx)
        clear_stale_cache_lock()  # a process's first build: a killed worker's lock goes first
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            prg = cl.Program(ctx, _PROBE).build(
                options=[f"-I{HEADERS}", *(["-DHOLO_FP64"] if fp64 else [])]
            )
        xd = cla.to_device(queue, x)
        yd = cla.empty(queue, x.shape, np.complex64)
        cl.Kernel(prg, "probe")(queue, x.shape, None, xd.data, yd.data)
        got = yd.get()
    except Exception as e:  # noqa: BLE001 -- any driver failure makes the device unusable, nothing more
        first_line = (str(e).strip().splitlines() or [repr(e)])[0]
        return f"{type(e).__name__}: {first_line}"
    err = float(np.max(np.abs(got - want)) / np.max(np.abs(want)))
    return "" if err < 1e-5 else f"wrong probe result (relative error {err:.1e})"


def device_problem(device: cl.Device) -> str:
    """Why a device is unusable, or "" when it passes the probe.

    The probe (the module docstring's) runs once per device and process; a failure is logged
    as a warning the first time.

    Parameters
    ----------
    device : pyopencl.Device

    Returns
    -------
    str
        "" (usable) or the reason: the exception's type and first line, or a wrong result
        with its relative error.

    Examples
    --------
    >>> from holo_core.opencl import choose_device, device_problem
    >>> device_problem(choose_device())
    ''
    """
    key = device.int_ptr
    if key not in _probed:
        _probed[key] = _probe(device)
        if _probed[key]:
            log.warning(
                "OpenCL device %s (%s) skipped: %s",
                device.name.strip(),
                device.platform.name.strip(),
                _probed[key],
            )
    return _probed[key]


def _rank(device: cl.Device) -> tuple[int, int]:
    if device.type & cl.device_type.GPU:
        return (0, 0)
    if device.type & cl.device_type.CPU:
        name = device.platform.name.lower()
        return (1, next((i for i, d in enumerate(_CPU_DRIVERS) if d in name), len(_CPU_DRIVERS)))
    return (2, 0)


def _describe(p: int, d: int, dev: cl.Device) -> str:
    return f"{p}:{d} {dev.name.strip()} ({dev.platform.name.strip()})"


def _matching(spec: str, devices):
    key = spec.lower()
    if not key:
        return devices
    if key in _TYPES:
        return [t for t in devices if t[2].type & _TYPES[key]]
    if all(part.isdigit() for part in key.split(":")) and key.count(":") <= 1:
        p, _, d = key.partition(":")
        return [t for t in devices if t[0] == int(p) and t[1] == int(d or 0)]
    return [t for t in devices if key in t[2].name.lower() or key in t[2].platform.name.lower()]


def choose_device(spec: str | None = None) -> cl.Device:
    """The best usable device a choice names, or the default one.

    Parameters
    ----------
    spec : str, optional
        'gpu', 'cpu', 'accelerator', 'P:D' (platform P, device D) or part of a device's or a
        platform's name (case-insensitive); None reads ``HOLO_DEVICE``, and an empty choice
        takes the first usable device in the order of the module docstring (GPUs, Intel's CPU
        runtime, PoCL, anything else).

    Returns
    -------
    pyopencl.Device
        The first matching device that passes the probe (:func:`device_problem`).

    Raises
    ------
    InputError
        Where ``spec`` names no usable device: the message names ``HOLO_DEVICE``, what it
        matched, why each failed, and the usable devices.
    RuntimeError
        Where no device works at all.

    Examples
    --------
    >>> from holo_core import InputError
    >>> from holo_core.opencl import choose_device
    >>> try:
    ...     choose_device("no-such-device")
    ... except InputError as e:
    ...     print(str(e)[:53])
    HOLO_DEVICE='no-such-device' names no usable device;
    """
    spec = (spec if spec is not None else os.environ.get("HOLO_DEVICE", "")).strip()
    devices = sorted(all_devices(), key=lambda t: _rank(t[2]))
    for p, d, dev in _matching(spec, devices):
        if not device_problem(dev):
            return dev
    usable = [_describe(*t) for t in devices if not device_problem(t[2])]
    tried = [f"{_describe(*t)}: {device_problem(t[2])}" for t in _matching(spec, devices)]
    if not spec:
        raise RuntimeError(
            "no usable OpenCL device"
            + (
                f" ({'; '.join(tried)})"
                if tried
                else "; install pocl-binary-distribution or intel-opencl-rt (pip) for a "
                "CPU device, or a GPU vendor's OpenCL driver"
            )
        )
    raise InputError(
        f"HOLO_DEVICE={spec!r} names no usable device"
        + (f" ({'; '.join(tried)})" if tried else "")
        + "; allowed: 'gpu', 'cpu', 'accelerator', 'P:D' or part of a device or "
        f"platform name. Usable: {'; '.join(usable) or 'none'}"
    )


def device_table(spec: str | None = None) -> list[tuple[str, str, bool]]:
    """Every device with its status: the ``python -m holo_core devices`` table.

    Parameters
    ----------
    spec : str, optional
        The choice the ``chosen`` column follows (:func:`choose_device`'s).

    Returns
    -------
    list of (str, str, bool)
        (description 'P:D name (platform)', 'usable' or why not, chosen), in listing order;
        nothing is chosen where ``spec`` names no usable device.

    Examples
    --------
    >>> from holo_core.opencl import device_table
    >>> sum(chosen for _, _, chosen in device_table())   # one device is the default
    1
    """
    try:
        chosen = choose_device(spec).int_ptr
    except (ValueError, RuntimeError):
        chosen = None
    return [
        (_describe(p, d, dev), device_problem(dev) or "usable", dev.int_ptr == chosen)
        for p, d, dev in all_devices()
    ]


def _has_fp64(device: cl.Device) -> bool:
    return bool(device.double_fp_config) or "cl_khr_fp64" in device.extensions


def is_cpu(device: cl.Device) -> bool:
    return bool(device.type & cl.device_type.CPU)


@dataclass(eq=False)
class Runtime:
    """One OpenCL context and in-order queue, with cached programs, kernels and scratch buffers.

    Not thread-safe: use one runtime per thread (the default runtime, :func:`get_runtime`'s,
    is per process).

    Parameters
    ----------
    device : pyopencl.Device
        The device (:func:`choose_device`'s); the context and queue are made on it.

    Notes
    -----
    ``program(source, options)`` builds a ``.cl`` file (:func:`associated`'s) once per option
    set, ``kernel(program, name, options)`` makes a kernel object once; ``fft`` is the
    device's FFT backend (``holo_core/opencl/fft.py``); ``scratch(tag, shape, dtype)`` and
    ``workspace(tag, shape, dtype)`` are reusable work arrays (one per shape, or one growing
    buffer per tag); ``real`` is the kernels' coordinate type, float64 where the device has
    it.

    Examples
    --------
    >>> from holo_core.opencl import Runtime, choose_device
    >>> rt = Runtime(choose_device())
    >>> rt.to_device([[1 + 2j]], "complex64").get()
    array([[1.+2.j]], dtype=complex64)
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

    @cached_property  # a device query is a driver call, and this is asked on every transform
    def is_cpu(self) -> bool:
        return is_cpu(self.device)

    @cached_property
    def lanes(self) -> int:
        """Rows per work item of the vectorised CPU kernels (float16 rows), 1 on GPUs. PoCL
        compiles for the LLVM target named in its version string: on a target without AVX-512
        (AMD Zen 4 is "znver3" to LLVM 14) float16 arguments break the ABI and the kernel is
        lost (INVALID_KERNEL_NAME), so it gets float8 rows there."""
        if not self.is_cpu:
            return 1
        version = self.device.version.strip()
        if "HSTR:" in version and not any(version.endswith("-" + t) for t in AVX512_TARGETS):
            return 8
        return 16

    @property
    def series_group(self) -> tuple[int, int] | None:
        """The work-group shape of the recurrence kernels (the point and zone sums), whose work
        items each own a tile of lanes x columns: (1, 1) on CPUs, where a work item is one
        thread running its own vectors; None on GPUs, where the driver packs the items into
        warps (a group of one would leave 31 of a warp's 32 threads idle)."""
        return (1, 1) if self.is_cpu else None

    @cached_property
    def has_fp64(self) -> bool:
        return _has_fp64(self.device)

    @cached_property
    def real(self) -> type:
        """The kernels' ``real`` (coordinates, phases): float64 where the device has it."""
        return np.float64 if self.has_fp64 else np.float32

    @cached_property
    def real_options(self) -> tuple[str, ...]:
        """Build options that make the kernels' ``real`` match :attr:`real`."""
        return ("-DHOLO_FP64",) if self.has_fp64 else ()

    def program(self, source: Path, options: tuple[str, ...] = ()) -> cl.Program:
        """The program in the file ``source`` (a module's :func:`associated` ``.cl`` file)
        built for this context, once per option set."""
        key = (source, options)
        if key not in self._programs:
            text = Path(source).read_text()
            opts = [f"-I{HEADERS}", *options]
            clear_stale_cache_lock()
            with warnings.catch_warnings():  # PoCL's clang notes vector ABIs; not our concern
                warnings.simplefilter("ignore", cl.CompilerWarning)
                self._programs[key] = cl.Program(self.context, text).build(options=opts)
        return self._programs[key]

    def kernel(self, program: Path, name: str, options: tuple[str, ...] = ()) -> cl.Kernel:
        """A kernel object, created once (repeated retrieval from a program is slow)."""
        key = (program, name, options)
        if key not in self._kernels:
            self._kernels[key] = cl.Kernel(self.program(program, options), name)
        return self._kernels[key]

    @property
    def fft(self):
        """The FFT backend for this device (see :mod:`holo_core.opencl.fft`)."""
        if self._fft is None:
            self._fft = backend_for(self)
        return self._fft

    def scratch(self, tag: str, shape: tuple[int, ...], dtype=np.complex64) -> cla.Array:
        """A reusable work array; its content is undefined on return."""
        key = ("scratch", tag, tuple(shape), np.dtype(dtype))
        if key not in self.cache:
            self.cache[key] = cla.empty(self.queue, shape, dtype)
        return self.cache[key]

    def workspace(self, tag: str, shape: tuple[int, ...], dtype=np.complex64) -> cla.Array:
        """A reusable work array of any shape: one buffer per tag, grown by a quarter more than
        asked when a call needs more; its content is undefined on return. For arrays whose
        shape follows the input (a plate view's window follows the camera), where
        :meth:`scratch` would keep one of each shape met (a move whose window changes size, one a
        frame)."""
        dtype = np.dtype(dtype)
        nbytes = max(int(np.prod(shape)) * dtype.itemsize, 1)
        key = ("workspace", tag)
        if key not in self.cache or self.cache[key].size < nbytes:
            self.cache.pop(key, None)  # the smaller buffer goes before the larger is made
            self.cache[key] = cl.Buffer(self.context, cl.mem_flags.READ_WRITE, nbytes + nbytes // 4)
        return cla.Array(self.queue, shape, dtype, data=self.cache[key])

    def to_device(self, host: np.ndarray, dtype=None) -> cla.Array:
        a = np.ascontiguousarray(host, dtype=dtype)
        return cla.to_device(self.queue, a)


def associated(module_file: str) -> Path:
    """The kernels' file beside a host module.

    Parameters
    ----------
    module_file : str
        The module's ``__file__``.

    Returns
    -------
    pathlib.Path
        The same path with the suffix ``.cl``: ``camera/recording.py`` launches the kernels
        of ``camera/recording.cl``.

    Examples
    --------
    >>> from holo_core.opencl import associated
    >>> associated("holo_core/camera/recording.py").as_posix()
    'holo_core/camera/recording.cl'
    """
    return Path(module_file).with_suffix(".cl")


_default: Runtime | None = None
_lock = threading.Lock()


def get_runtime() -> Runtime:
    """The process-wide runtime on the default device (``HOLO_DEVICE`` or auto).

    Made on first use, then the same one (thread-safe; the runtime itself is not).

    Returns
    -------
    Runtime

    Raises
    ------
    InputError
        Where ``HOLO_DEVICE`` names no usable device.
    RuntimeError
        Where no device works.

    Examples
    --------
    >>> from holo_core.opencl import get_runtime
    >>> get_runtime() is get_runtime()
    True
    """
    global _default
    with _lock:
        if _default is None:
            _default = Runtime(choose_device())
        return _default


def set_device(spec: str | None) -> Runtime:
    """Replace the process-wide runtime with one on the device a choice names.

    Parameters
    ----------
    spec : str or None
        :func:`choose_device`'s choice (None: ``HOLO_DEVICE`` or auto).

    Returns
    -------
    Runtime
        The new process-wide runtime (:func:`get_runtime` returns it from then on).

    Raises
    ------
    InputError
        Where ``spec`` names no usable device (the runtime is left as it was).

    Examples
    --------
    A choice that names no device leaves the process-wide runtime as it was:

    >>> from holo_core import InputError
    >>> from holo_core.opencl import get_runtime, set_device
    >>> before = get_runtime()
    >>> try:
    ...     set_device("no-such-device")
    ... except InputError:
    ...     pass
    >>> get_runtime() is before
    True
    """
    global _default
    with _lock:
        _default = Runtime(choose_device(spec))
        return _default


STALE_LOCK = 10.0  # [s] pyopencl holds its program cache's lock for milliseconds
UNLINK_WINDOW = 0.05  # [s] a holder closes the lock, then removes it at once


def clear_stale_cache_lock() -> None:
    """Remove pyopencl's program-cache lock where a killed process left it (a cancelled
    worker killed while it read the cache): the next process would otherwise wait a minute
    for it and then fail. A living holder keeps the lock open: where the system lists open
    files (Linux's /proc), a lock that no process has open, twice UNLINK_WINDOW apart, is
    stale however recent; elsewhere, one older than STALE_LOCK."""
    lock = cache_lock()
    try:
        found = lock.stat()
    except FileNotFoundError:
        return
    held = _held_open(lock)
    if held is None:
        stale = time.time() - found.st_mtime > STALE_LOCK
    else:
        if not held:
            time.sleep(UNLINK_WINDOW)
        stale = not held and not _held_open(lock) and _same_file(lock, found)
    if stale:
        lock.unlink(missing_ok=True)
        log.warning("removed a stale OpenCL program-cache lock %s", lock)


def _same_file(path: Path, found: os.stat_result) -> bool:
    try:
        return os.path.samestat(path.stat(), found)
    except FileNotFoundError:
        return False


def cache_lock() -> Path:
    """The lock file of pyopencl's program cache (where pyopencl puts it)."""
    base = os.getenv("XDG_CACHE_HOME") if sys.platform == "darwin" else None
    base = (
        os.path.join(base, "pyopencl")
        if base
        else platformdirs.user_cache_dir("pyopencl", "pyopencl")
    )
    version = ".".join(str(i) for i in sys.version_info)
    return Path(base) / f"pyopencl-compiler-cache-v2-py{version}" / "lock"


def _held_open(path: Path) -> bool | None:
    """Whether a process this user may see has ``path`` open (None: the system does not
    say). Another user's processes cannot hold a lock in this user's cache."""
    proc = Path("/proc")
    if not (proc / "self" / "fd").is_dir():
        return None
    target = os.path.realpath(path)
    for fds in proc.glob("[0-9]*/fd"):
        try:
            if any(os.readlink(fd) == target for fd in fds.iterdir()):
                return True
        except OSError:  # a process gone, or another user's
            continue
    return False
