"""A focus sweep: 100 distances of a 1024² field (2x padding), each a new transfer function,
against the same propagation repeated at one distance (its transfer function cached) and
against plain NumPy rebuilding its float64 kernel per step, all in this run.

Each sweep step is followed by a step at the repeated distance (alternating, so both see the
same load); a third series times a new distance's transfer function alone, as the angular
spectrum makes it (from the cached chirp). Prints the medians, the transfer function against
a propagation (issue 37: <= 0.2), a sweep step against a repeated one (<= 1.2), the ratio
against NumPy, and the sweep's error against float64 NumPy at three of its distances. Run:
make bench, or python bench/sweep.py [--steps N] [--size N].
"""

import argparse
import os
import statistics
import time

import numpy as np
import results  # the bench folder's own: the figures as data
from results import cpu_name  # propagation.py, record.py and stages.py take it from here

from holo_core.opencl import get_runtime, to_device
from holo_core.opencl.arrays import recycled
from holo_core.propagation import angular_spectrum, transfer_function
from holo_core.propagation.angular_spectrum import BAND_EDGE
from holo_core.propagation.convolution import symmetric
from holo_core.propagation.grid import padded_shape
from holo_core.propagation.transfer import asm_transfer, quadrant_shape

PITCH, LAM = 2e-6, 633e-9


def numpy_step(field, shape, z):
    """Plain NumPy of the same method, its float64 kernel rebuilt for the new distance."""
    tf = transfer_function(shape, wavelength=LAM, pitch=PITCH, distance=z).astype(np.complex64)
    h, w = field.shape
    big = np.zeros(shape, np.complex64)
    r0, c0 = (shape[0] - h) // 2, (shape[1] - w) // 2
    big[r0 : r0 + h, c0 : c0 + w] = field
    return np.fft.ifft2(np.fft.fft2(big) * tf)[r0 : r0 + h, c0 : c0 + w]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--numpy-steps", type=int, default=5)
    args = ap.parse_args()
    rt = get_runtime()
    n = args.size
    rng = np.random.default_rng(1)
    field = (rng.normal(size=(n, n)) + 1j * rng.normal(size=(n, n))).astype(np.complex64)
    shape = padded_shape(field.shape, 2)
    distances = np.linspace(4e-3, 6e-3, args.steps)
    dev = to_device(field)

    def step(z):
        out = angular_spectrum(dev, wavelength=LAM, pitch=PITCH, distance=float(z))
        rt.queue.finish()
        return out

    quadrant = symmetric(rt, (0.0, 0.0))
    tf_shape = quadrant_shape(shape) if quadrant else shape

    def transfer(z):  # a new distance's transfer function alone, as angular_spectrum makes it
        asm_transfer(
            rt,
            shape,
            wavelength=LAM,
            pitch=(PITCH, PITCH),
            distance=float(z),
            offset=(0.0, 0.0),
            band_limit=True,
            edge=BAND_EDGE,
            quadrant=quadrant,
            out=recycled(rt, "bench", tf_shape),
        )  # its own buffers: the cache's stay
        rt.queue.finish()

    step(5e-3)  # programs built, FFT planned, the repeated distance's transfer cached
    transfer(5e-3)
    repeated, sweep, made = [], [], []
    for z in distances:
        for series, run, at in (
            (sweep, step, z),
            (repeated, step, 5e-3),
            (made, transfer, z + 1e-9),
        ):
            t = time.perf_counter()
            run(at)
            series.append(time.perf_counter() - t)
    t = time.perf_counter()
    stack = angular_spectrum(dev, wavelength=LAM, pitch=PITCH, distance=distances)
    rt.queue.finish()
    batch = (time.perf_counter() - t) / len(distances)
    plain = []
    for z in distances[: args.numpy_steps]:
        t = time.perf_counter()
        numpy_step(field, shape, z)
        plain.append(time.perf_counter() - t)
    errors = []
    for i in (0, len(distances) // 2, len(distances) - 1):
        ref = numpy_step(field.astype(np.complex128), shape, distances[i])
        got = stack[i].get()
        errors.append(float(np.linalg.norm(got - ref) / np.linalg.norm(ref)))
    rep, new, tf, np_med = (statistics.median(v) for v in (repeated, sweep, made, plain))
    print(
        f"CPU: {cpu_name()}, load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} "
        f"cores; device: {rt.device.name.strip()} "
        f"({rt.device.platform.name.strip()}), FFT {rt.fft.name}, float64 "
        f"{'yes' if rt.has_fp64 else 'no (split float32 route)'}"
    )
    print(
        f"field {n}x{n}, padding 2 -> {shape[0]}x{shape[1]}, {len(distances)} distances "
        f"{distances[0]:g} to {distances[-1]:g} m"
    )
    print(f"repeated distance (cached transfer): {rep * 1e3:7.1f} ms per step (median)")
    print(
        f"a new distance's transfer function : {tf * 1e3:7.1f} ms, {tf / rep:.2f}x a "
        f"propagation (target <= 0.2)"
    )
    print(
        f"sweep, new distance each step      : {new * 1e3:7.1f} ms per step (median), "
        f"{new / rep:.2f}x a repeated step (target <= 1.2)"
    )
    print(f"sweep as one batched call          : {batch * 1e3:7.1f} ms per step")
    print(
        f"plain NumPy, kernel rebuilt per step: {np_med * 1e3:7.1f} ms per step "
        f"({len(plain)} steps): holo is {np_med / new:.1f}x faster"
    )
    print(f"error vs float64 NumPy at 3 distances: {', '.join(f'{e:.1e}' for e in errors)}")
    print(f"load average at the end {os.getloadavg()[0]:.1f}")
    results.write(
        "sweep",
        {
            "field": f"{n}x{n}, padded to {shape[0]}x{shape[1]}, {len(distances)} distances",
            "repeated distance, cached transfer [ms/step]": rep * 1e3,
            "a new distance's transfer function [ms]": tf * 1e3,
            "transfer function / propagation (target <= 0.2)": tf / rep,
            "sweep, a new distance each step [ms/step]": new * 1e3,
            "sweep step / repeated step (target <= 1.2)": new / rep,
            "sweep as one batched call [ms/step]": batch * 1e3,
            "plain NumPy, kernel rebuilt per step [ms/step]": np_med * 1e3,
            "Holo's speed-up over plain NumPy": np_med / new,
            "largest error against float64 NumPy": max(errors),
        },
        device=f"{rt.device.name.strip()} ({rt.device.platform.name.strip()}), FFT {rt.fft.name}",
    )


if __name__ == "__main__":
    main()
