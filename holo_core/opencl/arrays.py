"""Fields in and out (NumPy or device arrays, complex64 on the device), buffer helpers, and the
per-runtime cache of host-made arrays. Fills on CPU devices are NumPy's on the mapped buffer
(a memset), cropping a native rectangle copy."""

from __future__ import annotations

import weakref
from collections import OrderedDict, deque
from dataclasses import replace

import numpy as np
import pyopencl as cl
import pyopencl.array as cla
from pyopencl.reduction import ReductionKernel
from pyopencl.scan import ExclusiveScanKernel

from ..validate import InputError, host_field
from .copies import read, write  # noqa: F401 (callers take every array helper from here)
from .runtime import Runtime, get_runtime


def is_device_array(a) -> bool:
    """Whether ``a`` is an OpenCL device array (a ``pyopencl.array.Array``).

    Parameters
    ----------
    a : object

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import to_device
    >>> from holo_core.opencl import is_device_array
    >>> is_device_array(np.ones((2, 2))), is_device_array(to_device(np.ones((2, 2))))
    (False, True)
    """
    return isinstance(a, cla.Array)


def as_device(field, name: str = "field", runtime: Runtime | None = None, check: bool = True):
    """A 2-D finite field on the device, checked, for a stage that runs there.

    Parameters
    ----------
    field : (H, W) array or pyopencl.array.Array
        NumPy input is checked on the host and uploaded as complex64; a device array must be
        2-D, C-contiguous and of the runtime's context (converted to complex64 if it is not).
    name : str
        The argument's name in error messages.
    runtime : Runtime, optional
        Default the process's (:func:`get_runtime`).
    check : bool
        Count a device array's NaN and infinite values on the device; False where the caller
        checks (e.g. in a DC term it computes anyway).

    Returns
    -------
    runtime : Runtime
    array : pyopencl.array.Array
        The field, complex64 (H, W).
    from_host : bool
        Whether it came from the host (:func:`like_input` sends the result back).

    Raises
    ------
    InputError
        Where the field is not 2-D, empty, of another context, not C-contiguous or not
        finite, naming ``name``.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.opencl import as_device
    >>> rt, d, from_host = as_device(np.ones((4, 4)))
    >>> d.dtype, d.shape, from_host
    (dtype('complex64'), (4, 4), True)
    """
    rt = runtime or get_runtime()
    if not is_device_array(field):
        return rt, rt.to_device(host_field(name, field), np.complex64), True
    if field.ndim != 2:
        raise InputError(f"{name} must be a 2-D array [rows=y, cols=x]; got {field.ndim}-D")
    if not field.size:
        raise InputError(
            f"{name} must hold at least 1x1 samples; got {field.shape[0]}x{field.shape[1]}"
        )
    if field.context != rt.context:
        raise InputError(f"{name} lives in another OpenCL context than the runtime's")
    if not field.flags.c_contiguous:
        raise InputError(f"{name} must be a C-contiguous device array")
    if field.dtype != np.complex64:
        field = field.astype(np.complex64)
    if check and nonfinite_count(rt, field):
        raise InputError(f"{name} must be finite; it holds NaN or infinite values")
    return rt, field, False


def to_device(array, runtime: Runtime | None = None):
    """Put a field on the OpenCL device, for propagations that stay there.

    Parameters
    ----------
    array : (H, W) or (..., H, W) complex array, or Field
        A finite field, or a batch; a :class:`~holo_core.scene.field.Field` comes back as a
        Field whose samples are on the device. What is on the device already stays.
    runtime : Runtime, optional
        Whose context to use; default the process's.

    Returns
    -------
    pyopencl.array.Array or Field
        A C-contiguous complex64 device array. Every propagation takes it and returns one with
        no copy to the host; ``.get()`` (a Field's ``to_numpy()``) brings a result back to
        NumPy.

    Raises
    ------
    InputError
        Where ``array`` is not a finite (..., H, W) array.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import angular_spectrum, to_device
    >>> d = to_device(np.ones((64, 64)))
    >>> v = angular_spectrum(d, wavelength=633e-9, pitch=4e-6, distance=1e-3)
    >>> v.shape, str(v.dtype), round(float(abs(v.get()[32, 32])), 3)
    ((64, 64), 'complex64', 1.0)
    """
    rt = runtime or get_runtime()
    if hasattr(array, "samples") and hasattr(array, "pose"):  # a Field (scene/field.py)
        return replace(array, samples=to_device(array.samples, rt))
    if is_device_array(array):
        if array.ndim < 2:
            raise InputError(f"array must be (H, W) or (..., H, W); got {array.ndim}-D")
        return array if array.dtype == np.complex64 else array.astype(np.complex64)
    a = np.asarray(array)
    if a.ndim > 2:
        for i, plane in enumerate(a.reshape(-1, *a.shape[-2:])):
            host_field(f"array plane {i}", plane)
    else:
        host_field("array", a)
    return rt.to_device(a, np.complex64)


# a row's work items go in whole multiples of this: a CPU runtime vectorises only a work group of
# whole vector lanes (Intel's: 16 floats with AVX-512)
LANES = 16


def by_rows(shape) -> tuple[int, int]:
    """The global size (columns rounded up to whole ``LANES``, rows) of a kernel over an
    (h, w) array: consecutive work items along a row (CPU runtimes vectorise, GPUs coalesce
    along the first dimension); the kernel returns at once for a column >= w."""
    return -(-shape[1] // LANES) * LANES, shape[0]


def put_plane(rt: Runtime, stack: cla.Array, index: int, plane: cla.Array) -> None:
    """Copy the C-contiguous ``plane`` into plane ``index`` of the contiguous ``stack``
    (..., H, W), device to device."""
    if plane.nbytes * (index + 1) > stack.nbytes or plane.dtype != stack.dtype:
        raise InputError(f"plane {index} of {plane.shape} does not fit the stack {stack.shape}")
    cl.enqueue_copy(
        rt.queue,
        stack.base_data,
        plane.base_data,
        byte_count=plane.nbytes,
        src_offset=plane.offset,
        dst_offset=stack.offset + index * plane.nbytes,
    )


def empty(rt: Runtime, shape, dtype=np.complex64) -> cla.Array:
    return cla.empty(rt.queue, tuple(shape), dtype)


def copy(a: cla.Array) -> cla.Array:
    return a.copy()


def read_first(rt: Runtime, a: cla.Array) -> np.ndarray:
    """The first element of ``a`` on the host (one small read)."""
    out = np.empty(1, a.dtype)
    cl.enqueue_copy(rt.queue, out, a.data)
    return out


def like_input(result, from_host: bool):
    """A result back in the caller's kind of array.

    Parameters
    ----------
    result : ndarray or pyopencl.array.Array
        A stage's result.
    from_host : bool
        Whether the input was NumPy (:func:`as_device`'s third value).

    Returns
    -------
    ndarray or pyopencl.array.Array
        ``result`` copied to NumPy where the input was NumPy and it is on the device; as it is
        otherwise (a NumPy result, from a stage that ran on the host, stays NumPy).

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.opencl import as_device, like_input
    >>> rt, d, from_host = as_device(np.ones((4, 4)))
    >>> type(like_input(d, from_host)).__name__
    'ndarray'
    """
    return result.get() if from_host and is_device_array(result) else result


def nonfinite_count(rt: Runtime, a: cla.Array) -> int:
    """How many float components of ``a`` are not finite (a reduction on the device)."""
    return _count(
        rt, "nonfinite", "isfinite(x[i]) ? 0 : 1", "float", a.view(np.float32).reshape(-1)
    )


def nonzero_count(rt: Runtime, a: cla.Array) -> int:
    """How many complex samples of ``a`` are not zero (a reduction on the device)."""
    return _count(
        rt, "nonzero", "(x[i].x != 0.0f || x[i].y != 0.0f) ? 1 : 0", "float2", a.reshape(-1)
    )


def _count(rt: Runtime, key: str, test: str, ctype: str, flat: cla.Array) -> int:
    """The sum of ``test`` (1 or 0) over ``flat``'s elements of C type ``ctype``; its
    reduction kernel built once per runtime."""
    if key not in rt.cache:
        rt.cache[key] = ReductionKernel(
            rt.context,
            np.int32,
            neutral="0",
            reduce_expr="a+b",
            map_expr=test,
            arguments=f"__global const {ctype} *x",
        )
    return int(rt.cache[key](flat).get())


CACHE_BYTES = 512 * 2**20  # device memory kept for host-made arrays, least recently used out
RECYCLED = 8  # arrays of one kind and shape made for the cache before the oldest is reused


def fill(rt: Runtime, a: cla.Array, value) -> None:
    """Every element of ``a`` set to ``value``: on a CPU device by NumPy on the mapped buffer
    (a memset, several times faster there than pyopencl's fill kernel or clEnqueueFillBuffer:
    docs, Performance), elsewhere by pyopencl's fill."""
    if not rt.is_cpu:
        a.fill(value)
        return
    host, _ = cl.enqueue_map_buffer(
        rt.queue, a.base_data, cl.map_flags.WRITE_INVALIDATE_REGION, a.offset, a.shape, a.dtype
    )
    host[...] = value
    host.base.release(rt.queue)


def embed(rt: Runtime, dst: cla.Array, src: cla.Array, r0: int, c0: int) -> None:
    """dst = zeros with ``src`` placed at row ``r0``, column ``c0``."""
    fill(rt, dst, 0)
    place(rt, dst, src, r0, c0)


def place(rt: Runtime, dst: cla.Array, src: cla.Array, r0: int, c0: int) -> None:
    """``src`` copied into ``dst`` at row ``r0``, column ``c0``; the rest of ``dst`` as it
    was."""
    _rect(rt, dst, src, (0, 0), (r0, c0), src.shape)


def window(rt: Runtime, src: cla.Array, shape, r0: int, c0: int) -> cla.Array:
    """A new array of ``shape`` cut from ``src`` at row ``r0``, column ``c0``."""
    out = cla.empty(rt.queue, tuple(shape), np.complex64)
    _rect(rt, out, src, (r0, c0), (0, 0), shape)
    return out


def _rect(rt, dst, src, src_rc, dst_rc, shape):
    item = src.dtype.itemsize
    (src_buf, src_row), (dst_buf, dst_row) = _rows(src), _rows(dst)
    cl.enqueue_copy(
        rt.queue,
        dst_buf,
        src_buf,
        src_origin=(src_rc[1] * item, src_rc[0] + src_row),
        dst_origin=(dst_rc[1] * item, dst_rc[0] + dst_row),
        region=(shape[1] * item, shape[0]),
        src_pitches=(src.shape[-1] * item,),
        dst_pitches=(dst.shape[-1] * item,),
    )


def _rows(a: cla.Array):
    """(buffer, first row) of a 2-D array, also of a view starting on a row of a larger one
    (a plane of a stack, ``stack[c]``), read in place: no sub-buffer, no copy."""
    row = a.shape[-1] * a.dtype.itemsize
    if a.offset % row:
        raise InputError("a view must start on a row of its buffer")
    return a.base_data, a.offset // row


def cached(rt, key, make):
    """``(device array, notes)`` for ``make() -> (host or device array, notes)``, made once
    per runtime and ``key``; the least recently used go beyond ``CACHE_BYTES``."""
    lru = rt.cache.setdefault("spectral-lru", OrderedDict())
    if key in lru:
        lru.move_to_end(key)
        return lru[key]
    made, notes = make()  # a host array (uploaded as complex64) or a device array
    lru[key] = (made if is_device_array(made) else rt.to_device(made, np.complex64)), notes
    while sum(v[0].nbytes for v in lru.values()) > CACHE_BYTES and len(lru) > 1:
        lru.popitem(last=False)
    return lru[key]


def upload_window(dst, host, planes, row0: int, col0: int) -> None:
    """Copy the window of rows ``row0`` … and columns ``col0`` … of ``host`` (C, H, W) (a
    C-contiguous NumPy array), its planes ``planes`` (a sequence of indices), into the device
    stack ``dst`` (len(planes), rows, cols): one rectangle copy per plane, no host copy."""
    rows, cols = dst.shape[1:]
    item = host.dtype.itemsize
    for m, p in enumerate(planes):
        cl.enqueue_copy(
            dst.queue,
            dst.data,
            host[p],
            buffer_origin=(0, m * rows),
            host_origin=(col0 * item, row0),
            region=(cols * item, rows),
            buffer_pitches=(cols * item,),
            host_pitches=(host.shape[2] * item,),
        )


def host_buffer(rt, host) -> cl.Buffer | None:
    """A read-only buffer over the NumPy array ``host``'s own memory, where the device is a
    CPU and ``host`` is C-contiguous and starts on the device's base alignment (as
    :func:`holo_core.memory.aligned_zeros` makes it): kernels then read it in place, no byte
    copied. None otherwise (a GPU would copy the whole array; the caller copies what it
    needs)."""
    if not (rt.is_cpu and isinstance(host, np.ndarray) and host.flags.c_contiguous):
        return None
    if host.ctypes.data % max(rt.device.mem_base_addr_align // 8, 1):
        return None
    return cl.Buffer(rt.context, cl.mem_flags.READ_ONLY | cl.mem_flags.USE_HOST_PTR, hostbuf=host)


def exclusive_scan(rt, counts: cla.Array, out: cla.Array) -> None:
    """out[i] = counts[0] + … + counts[i − 1] (int32 device arrays of one length)."""
    if "exclusive-scan" not in rt.cache:
        rt.cache["exclusive-scan"] = ExclusiveScanKernel(rt.context, np.int32, "a+b", "0")
    rt.cache["exclusive-scan"](counts, out, queue=rt.queue)


def extent(a: cla.Array) -> tuple[float, float]:
    """(min, max) of a device array's values."""
    return float(cla.min(a).get()), float(cla.max(a).get())


RESIDENT_SHARE = 0.5  # of a GPU's memory, at most, for the copies resident() keeps


def resident(rt, host) -> cl.Buffer | None:
    """A buffer the kernels read the NumPy array ``host`` from, copied at most once: on a CPU
    the array's own memory (:func:`host_buffer`); on another device a copy made on first use
    and kept while ``host`` lives, within RESIDENT_SHARE of the device's memory (the copies
    used least recently dropped first), so that a plate's views on a GPU read its samples
    where they are rather than over the bus each view (1.8 GB a view of the shot's plate).
    ``host`` is made read-only while its copy is kept: a write would leave the copy stale, so
    it raises instead. None where neither applies (the caller copies what it needs)."""
    if rt.is_cpu or not (isinstance(host, np.ndarray) and host.flags.c_contiguous):
        return host_buffer(rt, host)
    kept = rt.cache.setdefault("resident", OrderedDict())  # id(host) -> _Resident
    key = id(host)
    if key in kept:
        kept.move_to_end(key)
        return kept[key].buffer
    budget = RESIDENT_SHARE * rt.device.global_mem_size
    if host.nbytes > budget:
        return None
    while kept and sum(r.buffer.size for r in kept.values()) + host.nbytes > budget:
        kept.popitem(last=False)[1].release()  # the least recently used copy goes
    kept[key] = _Resident(
        kept,
        key,
        host,
        cl.Buffer(rt.context, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR, hostbuf=host),
    )
    return kept[key].buffer


class _Resident:
    """A device copy of a host array, dropped with the array (an array freed, its id can name
    another one); the array read-only while the copy is kept."""

    def __init__(self, kept: OrderedDict, key: int, host: np.ndarray, buffer: cl.Buffer):
        self.buffer, self.host = buffer, weakref.ref(host)
        self.writable = host.flags.writeable
        host.flags.writeable = False
        self.finalizer = weakref.finalize(host, kept.pop, key, None)

    def release(self) -> None:
        """Drops the copy and makes the array writable again (as it was)."""
        self.finalizer.detach()
        host = self.host()
        if host is not None and self.writable:
            host.flags.writeable = True


def recycled(rt, kind: str, shape, dtype=np.complex64) -> cla.Array:
    """A device array for a new :func:`cached` entry of ``kind``: a fresh one until ``RECYCLED``
    of that kind and shape exist, then the oldest of them, its entry dropped from the cache.
    A sweep of new distances then writes each transfer function into memory already in use,
    where a fresh allocation costs the first touch of its pages (at 2048², more than the
    kernel that fills it)."""
    ring = rt.cache.setdefault(("recycled", kind, tuple(shape), np.dtype(dtype)), deque())
    if len(ring) < RECYCLED:
        arr = empty(rt, shape, dtype)
    else:
        arr = ring.popleft()
        lru = rt.cache.get("spectral-lru", {})
        for key in [k for k, (v, _) in lru.items() if v is arr]:
            del lru[key]
    ring.append(arr)
    return arr
