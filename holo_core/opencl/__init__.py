"""OpenCL runtime, a stack from the floor up: whole-array copies to and from the host
(copies.py), FFT backends (fft.py; FFTW's passes on CPU devices in host_fft.py), device choice,
context and program cache (runtime.py), device-array helpers (arrays.py), kernel signatures
and their launch by keyword (kernel.py); packaged drivers made visible to the ICD loader
(icd.py), and the kernels' shared headers (holo_complex.h, real.h, fft_order.h,
spectrum_read.h, lane_series.h). Each kernel's .cl file lives beside the module that launches
it (``runtime.associated``), its signature written there."""

import os

from .icd import register_vendors

register_vendors()  # before pyopencl's ICD loader first looks for platforms
# pyopencl 2026.1 reads this unguarded when a program-cache write fails (KeyError otherwise)
os.environ.setdefault("PYOPENCL_CACHE_FAILURE_FATAL", "")

from .arrays import as_device, is_device_array, like_input, to_device
from .runtime import (
    Runtime,
    all_devices,
    associated,
    choose_device,
    device_problem,
    device_table,
    get_runtime,
    set_device,
)

__all__ = [
    "Runtime",
    "all_devices",
    "as_device",
    "associated",
    "choose_device",
    "device_problem",
    "device_table",
    "get_runtime",
    "is_device_array",
    "like_input",
    "set_device",
    "to_device",
]
