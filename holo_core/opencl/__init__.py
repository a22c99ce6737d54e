"""OpenCL runtime: device choice and context (runtime.py), FFT backends (fft.py),
device-array helpers (arrays.py), kernels/*.cl with the shared complex header."""

from .arrays import as_device, is_device_array, like_input
from .runtime import Runtime, all_devices, choose_device, get_runtime, set_device

__all__ = ["Runtime", "all_devices", "as_device", "choose_device", "get_runtime",
           "is_device_array", "like_input", "set_device"]
