"""Angular spectrum speed: 1024² field, 2x padding, against plain NumPy of the same method.

Prints both times (min and median of repeated runs, device arrays in and out for Holo), their
ratio, and each result's error against a float64 NumPy reference. Run: make bench
"""

import os
import statistics
import sys
import time

import numpy as np

from holo_core.opencl import get_runtime
from holo_core.propagation import angular_spectrum, transfer_function
from holo_core.propagation.grid import padded_shape

sys.path.insert(0, os.path.dirname(__file__))
from sweep import cpu_name  # the bench folder's own helper

N, PITCH, LAM, Z, REPEATS = 1024, 2e-6, 633e-9, 5e-3, 15


def numpy_asm(field, tf, dtype):
    """The same method in plain NumPy: pad, fft2, multiply, ifft2, crop."""
    h, w = field.shape
    big = np.zeros(tf.shape, dtype)
    r0, c0 = (tf.shape[0] - h) // 2, (tf.shape[1] - w) // 2
    big[r0:r0 + h, c0:c0 + w] = field
    return np.fft.ifft2(np.fft.fft2(big) * tf)[r0:r0 + h, c0:c0 + w]


def timed(fn):
    fn()
    times = []
    for _ in range(REPEATS):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times), statistics.median(times)


def main():
    rt = get_runtime()
    rng = np.random.default_rng(1)
    field = (rng.normal(size=(N, N)) + 1j * rng.normal(size=(N, N))).astype(np.complex64)
    shape = padded_shape(field.shape, 2)
    tf64 = transfer_function(shape, wavelength=LAM, pitch=PITCH, distance=Z)
    reference = numpy_asm(field.astype(np.complex128), tf64, np.complex128)
    tf32 = tf64.astype(np.complex64)
    dev = rt.to_device(field)

    def holo():
        out = angular_spectrum(dev, wavelength=LAM, pitch=PITCH, distance=Z)
        rt.queue.finish()
        return out

    t_holo, m_holo = timed(holo)
    t_np, m_np = timed(lambda: numpy_asm(field, tf32, np.complex64))
    err = lambda a: np.linalg.norm(a - reference) / np.linalg.norm(reference)
    print(f"CPU: {cpu_name()}, load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} "
          f"cores; device: {rt.device.name} ({rt.device.platform.name.strip()}), FFT backend: "
          f"{rt.fft.name}")
    print(f"field {N}x{N}, padding 2 -> {shape[0]}x{shape[1]}, distance {Z} m")
    print(f"holo angular_spectrum : {t_holo * 1e3:7.1f} ms (median {m_holo * 1e3:.1f}), "
          f"error vs float64 {err(holo().get()):.2e}")
    print(f"plain numpy (complex64): {t_np * 1e3:7.1f} ms (median {m_np * 1e3:.1f}), "
          f"error vs float64 {err(numpy_asm(field, tf32, np.complex64)):.2e}")
    print(f"speed-up: {t_np / t_holo:.1f}x (targets: <= 30 ms, >= 6x, error <= 1e-5)")


if __name__ == "__main__":
    main()
