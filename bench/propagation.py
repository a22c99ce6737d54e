"""Propagation against the FFT bound and what a user would pick instead, side by side in one run.

For each size, the same method five ways, timed in alternating rounds (medians):

- the bound: FFTW with plans measured here once (FFTW_MEASURE, kept between runs in this
  bench's own wisdom file), NumPy for the padding, the multiply and the crop; with one thread
  and with all, the faster of the two;
- scipy.fft with ``workers`` = all CPUs (pad, ``fft2``, multiply, ``ifft2``, crop);
- Holo with the field on the device, and with NumPy in and out;
- plain NumPy (complex64), at the smallest size.

Methods: the angular spectrum (a field of n² samples, 2x padding: the transforms are (2n)²)
and Fresnel; the camera pass's and the plate view's transforms: a pupil of n² samples in FFT
order, zero-padded 2x into the corners of its spectrum's grid and transformed (``pupil``),
and the images' n² spectra padded 1.5x the same way and transformed back (``read``).
Prints the CPU, its load before and after, each median and its ratio to the bound and to
scipy, and the angular spectrum's error against float64 NumPy.

    python bench/propagation.py [--sizes 1024 2048 4096] [--rounds 5]
"""

import argparse
import math
import os
import pickle
import statistics
import sys
import time

import numpy as np
import pyfftw
import scipy.fft

from holo_core.camera import incoherent
from holo_core.opencl import get_runtime
from holo_core.opencl.arrays import by_rows, empty
from holo_core.optics import imaging
from holo_core.propagation import angular_spectrum, fresnel, grid, transfer_function
from holo_core.propagation.fresnel import fresnel_transfer_host

sys.path.insert(0, os.path.dirname(__file__))
import results  # the bench folder's own: the figures as data
from sweep import cpu_name  # the bench folder's own helper

LAM, PITCH, Z = 633e-9, 2e-6, 5e-3
THREADS = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


class Bound:
    """FFTW's 2-D transforms of one grid with measured plans, one thread and all of them."""

    def __init__(self, shape):
        self.work = pyfftw.empty_aligned(shape, np.complex64)
        self.plans = {
            th: [
                pyfftw.FFTW(
                    self.work,
                    self.work,
                    axes=(0, 1),
                    direction=d,
                    flags=("FFTW_MEASURE",),
                    threads=th,
                )
                for d in ("FFTW_FORWARD", "FFTW_BACKWARD")
            ]
            for th in sorted({1, THREADS})
        }

    def run(self, threads, direction):
        self.plans[threads][direction == "backward"].execute()


def wisdom_file():
    from platformdirs import user_cache_dir

    return os.path.join(user_cache_dir("holo"), "bench-bound-wisdom.pickle")


def bounds(shapes):
    """A :class:`Bound` per shape, their plans measured once and kept in this bench's own
    wisdom file (made after Holo's plans: those never see this wisdom)."""
    try:
        with open(wisdom_file(), "rb") as f:
            pyfftw.import_wisdom(pickle.load(f))
    except (OSError, pickle.UnpicklingError, EOFError):
        pass
    made = {shape: Bound(shape) for shape in sorted(set(shapes))}
    os.makedirs(os.path.dirname(wisdom_file()), exist_ok=True)
    with open(wisdom_file(), "wb") as f:
        pickle.dump(pyfftw.export_wisdom(), f)
    return made


def random_field(n, seed):
    rng = np.random.default_rng(seed)
    return (rng.normal(size=(n, n)) + 1j * rng.normal(size=(n, n))).astype(np.complex64)


class Convolution:
    """The padded convolution of an n² field by the transfer function ``tf`` (2x padding)."""

    def __init__(self, rt, n, tf, holo):
        self.rt, self.n, self.tf, self.holo = rt, n, tf, holo
        self.field = random_field(n, 1)
        self.dev = rt.to_device(self.field)
        self.shapes = [tf.shape]
        holo(self.field)  # Holo's plans, before any of the bound's

    def methods(self, bound: Bound):
        n, tf, field = self.n, self.tf, self.field
        shape = tf.shape
        r0, c0 = (shape[0] - n) // 2, (shape[1] - n) // 2
        tf_bound = (tf / tf.size).astype(np.complex64)  # FFTW's inverse is unnormalised
        tf32 = tf.astype(np.complex64)

        def fftw(threads):
            def run():
                w = bound.work
                w[...] = 0
                w[r0 : r0 + n, c0 : c0 + n] = field
                bound.run(threads, "forward")
                np.multiply(w, tf_bound, out=w)
                bound.run(threads, "backward")
                return w[r0 : r0 + n, c0 : c0 + n].copy()

            return run

        def scipy_fft():
            big = np.zeros(shape, np.complex64)
            big[r0 : r0 + n, c0 : c0 + n] = field
            spec = scipy.fft.fft2(big, workers=THREADS, overwrite_x=True)
            spec *= tf32
            return scipy.fft.ifft2(spec, workers=THREADS, overwrite_x=True)[
                r0 : r0 + n, c0 : c0 + n
            ]

        def numpy_fft():
            big = np.zeros(shape, np.complex64)
            big[r0 : r0 + n, c0 : c0 + n] = field
            return np.fft.ifft2(np.fft.fft2(big) * tf32)[r0 : r0 + n, c0 : c0 + n]

        def holo_device():
            out = self.holo(self.dev)
            self.rt.queue.finish()
            return out

        methods = {f"FFTW measured, {th} thread{'s' * (th > 1)}": fftw(th) for th in bound.plans}
        methods["scipy.fft, workers=all"] = scipy_fft
        if n <= 1024:
            methods["NumPy"] = numpy_fft
        methods["Holo, field on the device"] = holo_device
        methods["Holo, NumPy in and out"] = lambda: self.holo(field)
        return methods


class Transform:
    """An n² block in FFT order zero-padded into the corners of a size² grid and transformed:
    'forward' (the pupil's: camera pass and plate view) or 'backward' (the images' spectra
    into the camera pass's read grid)."""

    def __init__(self, rt, n, size, direction):
        self.rt, self.n, self.size, self.direction = rt, n, size, direction
        self.block = random_field(n, 2)
        self.parts = [
            ((dr, dc), (sr, sc))
            for (dr, sr) in zip(
                (slice(*r) for r in grid.embedded(n, size)),
                (slice(0, (n + 1) // 2), slice((n + 1) // 2, n)),
            )
            for (dc, sc) in zip(
                (slice(*r) for r in grid.embedded(n, size)),
                (slice(0, (n + 1) // 2), slice((n + 1) // 2, n)),
            )
        ]
        self.shapes = [(size, size)]
        self.pupil, self.padded = rt.to_device(self.block), empty(rt, (size, size))
        self.flat = [rt.to_device(np.ones(n), np.float32)] * 2
        self.nonzero = (grid.embedded(n, size),) * 2
        self.options = rt.real_options + (
            f"-DTAPS={imaging.TAPS}",
            f"-DES_TABLE={imaging.ES_TABLE}",
        )
        self.holo()  # Holo's plans, before any of the bound's

    def place(self, w):
        w[...] = 0
        for dst, src in self.parts:
            w[dst] = self.block[src]

    def holo(self):
        rt, n = self.rt, self.n
        rt.fft.clear(self.padded, self.nonzero)
        if self.direction == "forward":  # the pupil stage's own kernel (open iris, no lens)
            imaging.window(
                rt,
                self.padded,
                self.pupil,
                (n, n),
                pitch=(1.0, 1.0),
                radius=4.0 * n,
                taper=0.0,
                k=0.0,
                focus=0.0,
                apodization=self.flat,
                options=self.options,
            )
            rt.fft.forward(self.padded, nonzero=self.nonzero)
        else:  # the images' spectra into the read grid (camera/incoherent.py's kernel)
            incoherent.EMBED_DEAPODIZED.launch(
                rt,
                by_rows((n, n)),
                options=self.options,
                Q=self.padded,
                H=self.size,
                W=self.size,
                A=self.pupil,
                h=n,
                w=n,
                ay=self.flat[0],
                ax=self.flat[1],
            )
            rt.fft.backward(self.padded, nonzero=self.nonzero)
        rt.queue.finish()
        return self.padded

    def methods(self, bound: Bound):
        forward = self.direction == "forward"

        def fftw(threads):
            def run():
                self.place(bound.work)
                bound.run(threads, self.direction)
                return bound.work

            return run

        def scipy_fft():
            w = np.empty((self.size, self.size), np.complex64)
            self.place(w)
            if forward:
                return scipy.fft.fft2(w, workers=THREADS, overwrite_x=True)
            return scipy.fft.ifft2(w, workers=THREADS, overwrite_x=True, norm="forward")

        methods = {f"FFTW measured, {th} thread{'s' * (th > 1)}": fftw(th) for th in bound.plans}
        methods["scipy.fft, workers=all"] = scipy_fft
        methods["Holo, on the device"] = self.holo
        return methods


def timed(methods, rounds):
    """Median seconds of each method over alternating rounds (one warm-up call each)."""
    for f in methods.values():
        f()
    times = {k: [] for k in methods}
    for _ in range(rounds):
        for k, f in methods.items():
            t = time.perf_counter()
            f()
            times[k].append(time.perf_counter() - t)
    return {k: statistics.median(v) for k, v in times.items()}


def report(title, medians, bound_keys):
    bound = min(medians[k] for k in bound_keys)
    scipy_t = medians["scipy.fft, workers=all"]
    print(f"{title}   (load {os.getloadavg()[0]:.1f})")
    for k, t in medians.items():
        print(
            f"  {k:30s} {t * 1e3:9.1f} ms  {t / bound:5.2f}x the bound  {t / scipy_t:5.2f}x scipy"
        )
    return {"bound [ms]": bound * 1e3, **{f"{k}, × bound": t / bound for k, t in medians.items()}}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1024, 2048, 4096])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--methods", nargs="+", default=["asm", "fresnel", "pupil", "read"])
    args = ap.parse_args()
    rt = get_runtime()
    print(
        f"CPU: {cpu_name()}, {THREADS} CPUs, load average {os.getloadavg()[0]:.1f}; device: "
        f"{rt.device.name.strip()} ({rt.device.platform.name.strip()}), FFT {rt.fft.name} "
        f"({getattr(getattr(rt.fft, 'host', None), 'threads', '-')} threads)"
    )
    print("bound = the faster FFTW row; ratios are medians of alternating rounds\n")
    asm = lambda u: angular_spectrum(u, wavelength=LAM, pitch=PITCH, distance=Z)
    fre = lambda u: fresnel(u, wavelength=LAM, pitch=PITCH, distance=Z)
    cases = []  # (title, case), Holo's plans made as each is built
    for n in args.sizes:
        shape = grid.padded_shape((n, n), 2)
        if "asm" in args.methods:
            tf = transfer_function(shape, wavelength=LAM, pitch=PITCH, distance=Z)
            cases.append(
                (
                    f"angular spectrum, {n}² field, 2x padding ({shape[0]}²)",
                    Convolution(rt, n, tf, asm),
                )
            )
        if "fresnel" in args.methods:
            tf = fresnel_transfer_host(shape, LAM, (PITCH, PITCH), Z, (0.0, 0.0))
            cases.append(
                (f"Fresnel, {n}² field, 2x padding ({shape[0]}²)", Convolution(rt, n, tf, fre))
            )
        if "pupil" in args.methods:
            cases.append(
                (
                    f"camera pass / plate view: {n}² pupil into its 2x padded spectrum "
                    f"({2 * n}²), forward",
                    Transform(rt, n, 2 * n, "forward"),
                )
            )
        if "read" in args.methods:
            size = grid.next_fast_len(math.ceil(1.5 * n))
            cases.append(
                (
                    f"camera pass: {n}² spectrum into its 1.5x read grid ({size}²), inverse",
                    Transform(rt, n, size, "backward"),
                )
            )
    made = bounds([s for _, case in cases for s in case.shapes])
    table = {}
    for title, case in cases:
        methods = case.methods(made[case.shapes[0]])
        table[title] = report(
            title, timed(methods, args.rounds), [k for k in methods if k.startswith("FFTW")]
        )
        if isinstance(case, Convolution) and case.holo is asm and case.n <= 1024:
            table[title]["error against float64 NumPy"] = error(case)
    print(f"\nload average at the end {os.getloadavg()[0]:.1f}")
    results.write(
        "propagation",
        table,
        device=f"{rt.device.name.strip()} ({rt.device.platform.name.strip()}), FFT {rt.fft.name}",
    )


def error(case: Convolution):
    """Holo's angular spectrum against the same method in float64 NumPy."""
    shape, n = case.tf.shape, case.n
    big = np.zeros(shape, complex)
    r0 = (shape[0] - n) // 2
    big[r0 : r0 + n, r0 : r0 + n] = case.field
    ref = np.fft.ifft2(np.fft.fft2(big) * case.tf)[r0 : r0 + n, r0 : r0 + n]
    got = case.holo(case.field)
    err = float(np.linalg.norm(got - ref) / np.linalg.norm(ref))
    print(f"  Holo's error against float64 NumPy: {err:.2e}")
    return err


if __name__ == "__main__":
    main()
