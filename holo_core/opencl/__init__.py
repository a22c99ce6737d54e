"""OpenCL runtime: device choice and context (runtime.py), FFT backends (fft.py),
device-array helpers (arrays.py), packaged drivers made visible to the ICD loader (icd.py),
kernels/*.cl with the shared complex header."""

import os

from .icd import register_vendors

register_vendors()  # before pyopencl's ICD loader first looks for platforms
# pyopencl 2026.1 reads this unguarded when a program-cache write fails (KeyError otherwise)
os.environ.setdefault("PYOPENCL_CACHE_FAILURE_FATAL", "")

from .arrays import as_device, is_device_array, like_input, to_device
from .runtime import (
                      Runtime,
                      all_devices,
                      choose_device,
                      device_problem,
                      device_table,
                      get_runtime,
                      set_device,
)

__all__ = ["Runtime", "all_devices", "as_device", "choose_device", "device_problem",
           "device_table", "get_runtime",
           "is_device_array", "like_input", "set_device", "to_device"]
