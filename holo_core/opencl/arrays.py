"""Fields in and out: NumPy arrays or OpenCL device arrays, complex64 on the device."""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla
from pyopencl.reduction import ReductionKernel

from ..validate import host_field
from .runtime import Runtime, get_runtime


def is_device_array(a) -> bool:
    return isinstance(a, cla.Array)


def as_device(field, name: str = "field", runtime: Runtime | None = None, check: bool = True):
    """``(runtime, device array, came_from_host)`` for a 2-D finite field.

    NumPy input is checked on the host and uploaded as complex64; a device array must be 2-D,
    C-contiguous and belong to the runtime's context, and is checked for NaN/Inf on the device
    unless ``check`` is false (the caller then checks, e.g. in a DC term it computes anyway).
    """
    rt = runtime or get_runtime()
    if not is_device_array(field):
        return rt, rt.to_device(host_field(name, field), np.complex64), True
    if field.ndim != 2:
        raise ValueError(f"{name} must be a 2-D array [rows=y, cols=x]; got {field.ndim}-D")
    if field.context != rt.context:
        raise ValueError(f"{name} lives in another OpenCL context than the runtime's")
    if not field.flags.c_contiguous:
        raise ValueError(f"{name} must be a C-contiguous device array")
    if field.dtype != np.complex64:
        field = field.astype(np.complex64)
    if check and nonfinite_count(rt, field):
        raise ValueError(f"{name} must be finite; it holds NaN or infinite values")
    return rt, field, False


def like_input(result: cla.Array, from_host: bool):
    """Back to the caller's kind of array: NumPy if the input was NumPy."""
    return result.get() if from_host else result


def nonfinite_count(rt: Runtime, a: cla.Array) -> int:
    key = "nonfinite"
    if key not in rt.cache:
        rt.cache[key] = ReductionKernel(rt.context, np.int32, neutral="0", reduce_expr="a+b",
                                        map_expr="isfinite(x[i]) ? 0 : 1",
                                        arguments="__global const float *x")
    return int(rt.cache[key](a.view(np.float32).reshape(-1)).get())
