"""Point-emitter object waves: the direct OpenCL sum against float64 NumPy, and the wavefront
recording planes for 100,000 points on a 1024² hologram, timed in the same run.

The direct sum's rate is given per second of wall time and per second of this process's CPU
time (all its threads, the OpenCL runtime's included): on a machine shared with other jobs
the second, times the cores, is what the sum reaches with the machine to itself.

    python bench/record.py      (or: make bench)
"""

import os
import sys
import time
import warnings

import numpy as np

from holo_core.opencl import get_runtime
from holo_core.plate.point_sources import point_wave
from holo_core.plate.point_sum import Grid, cone_weight
from holo_core.propagation import grid

sys.path.insert(0, os.path.dirname(__file__))
import results  # the bench folder's own: the figures as data
from sweep import cpu_name  # the bench folder's own helper

LAM, PITCH, SHAPE = 633e-9, 8e-6, (1024, 1024)


def numpy_sum(pos, amp, shape):
    g = Grid(shape, PITCH, LAM)
    y, x = grid.coords(shape[0], PITCH)[:, None], grid.coords(shape[1], PITCH)[None, :]
    out = np.zeros(shape, np.complex128)
    for (px, py, pz), a in zip(pos, amp):
        rho2 = (x - px) ** 2 + (y - py) ** 2
        r = np.sqrt(rho2 + pz * pz)
        out += a * np.exp(2j * np.pi / LAM * r) / r * cone_weight(rho2, (g.cone * pz) ** 2)
    return out


def pairs_in_cones(pos, shape):
    """Point-pixel pairs inside the points' cones: the pairs the kernel computes (each
    point's disc of radius cone·|z|, row by row, clipped to the hologram)."""
    g = Grid(shape, PITCH, LAM)
    y, x = grid.coords(shape[0], PITCH), grid.coords(shape[1], PITCH)
    half = np.sqrt(np.clip((g.cone * pos[:, 2:]) ** 2 - (y - pos[:, 1:2]) ** 2, 0, None))
    lo = np.searchsorted(x, pos[:, :1] - half, "left")
    hi = np.searchsorted(x, pos[:, :1] + half, "right")
    return int((hi - lo).sum())


def best(f, runs=3):
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        result = f()
        times.append(time.perf_counter() - t)
    return min(times), result


def best_cpu(f, runs=3):
    """(the least wall seconds, the least process CPU seconds) of ``runs`` calls, and the
    result."""
    wall, cpu = [], []
    for _ in range(runs):
        t, c = time.perf_counter(), time.process_time()
        result = f()
        wall.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    return (min(wall), min(cpu)), result


def scene(n, rng):
    half = SHAPE[1] * PITCH / 2
    return (
        np.c_[rng.uniform(-half, half, (n, 2)), rng.uniform(-0.2, -0.1, n)],
        np.exp(2j * np.pi * rng.random(n)),
    )


def main():
    warnings.simplefilter("ignore")
    rng = np.random.default_rng(1)
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    print(
        f"CPU: {cpu_name()}, {cores} cores, load average {os.getloadavg()[0]:.1f}; device: "
        f"{get_runtime().device.name.strip()}"
    )
    pos, amp = scene(2000, rng)
    point_wave(pos[:8], amp[:8], wavelength=LAM, pitch=PITCH, shape=SHAPE, method="direct")
    (t_cl, cpu), o = best_cpu(
        lambda: point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=SHAPE, method="direct"),
        runs=5,
    )
    few = 40  # float64 NumPy on a subset, same hologram
    t_np, ref = best(lambda: numpy_sum(pos[:few], amp[:few], SHAPE), runs=1)
    sub = point_wave(
        pos[:few], amp[:few], wavelength=LAM, pitch=PITCH, shape=SHAPE, method="direct"
    )
    pairs = pairs_in_cones(pos, SHAPE)
    err = err_direct = np.abs(sub - ref).max() / np.abs(ref).max()
    rate_np = pairs_in_cones(pos[:few], SHAPE) / t_np
    print(
        f"direct sum, {len(pos)} points x {SHAPE[0]}x{SHAPE[1]}: {t_cl:.3f} s, "
        f"{pairs / t_cl:.3g} pairs/s in the cones; {pairs / cpu:.3g} per CPU second, "
        f"x{cores} cores {cores * pairs / cpu:.3g} (target 1e10; load "
        f"{os.getloadavg()[0]:.1f}; "
        f"{len(pos) * SHAPE[0] * SHAPE[1] / t_cl:.3g} counting every pixel, "
        f"{pairs / (len(pos) * SHAPE[0] * SHAPE[1]):.0%} of which are in a cone); "
        f"float64 NumPy {rate_np:.3g} pairs/s; ratio {pairs / t_cl / rate_np:.0f}x; "
        f"max relative error {err:.2e} (target 1e-4)"
    )

    pos, amp = scene(100_000, rng)
    point_wave(pos[:1000], amp[:1000], wavelength=LAM, pitch=PITCH, shape=SHAPE, method="wrp")
    t_wrp, fast = best(
        lambda: point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=SHAPE, method="wrp"), runs=2
    )
    t_dir, direct = best(
        lambda: point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=SHAPE, method="direct"),
        runs=1,
    )
    err = np.linalg.norm(fast - direct) / np.linalg.norm(direct)
    print(
        f"100,000 points on {SHAPE[0]}x{SHAPE[1]}: recording planes {t_wrp:.2f} s per colour "
        f"(target 5 s), direct {t_dir:.2f} s, ratio {t_dir / t_wrp:.1f}x; relative error "
        f"{err:.2e} (bound 1e-2)"
    )
    figures = {
        "direct sum, 2,000 points: pairs/s in the cones (wall)": pairs / t_cl,
        "… per CPU second of the process": pairs / cpu,
        "… per CPU second × cores (target 1e10)": cores * pairs / cpu,
        "float64 NumPy, pairs/s": rate_np,
        "direct sum / NumPy": pairs / t_cl / rate_np,
        "direct sum's largest error against NumPy (target 1e-4)": err_direct,
        "100,000 points: recording planes [s per colour] (target 5)": t_wrp,
        "100,000 points: direct sum [s]": t_dir,
        "direct / recording planes": t_dir / t_wrp,
        "recording planes against the direct sum (bound 1e-2)": err,
    }
    figures.update(zones(rng))
    results.write("record", figures, device=get_runtime().device.name.strip())


def zones(rng, shape=(512, 512), n=2000):
    """Where the two methods part: the direct sum weights each cone in space, the recording
    planes in angle (their transfer function). Both rims map onto each other by stationary
    phase, which holds to ~1/N for a cone of N Fresnel zones (N = rho²/(λ|z|))."""
    print("recording planes vs direct sum by the cones' Fresnel zones N (512², 2,000 points):")
    found = {}
    for z, fill in ((-0.15, 0.8), (-0.15, 0.4), (-0.15, 0.2), (-0.04, 0.2)):
        half = shape[1] * PITCH / 2
        pos = np.c_[rng.uniform(-half, half, (n, 2)), np.full(n, z)]
        amp = np.exp(2j * np.pi * rng.random(n))
        band = fill * LAM / (2 * PITCH)
        d, w = (
            point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=shape, band=band, method=m)
            for m in ("direct", "wrp")
        )
        cone = Grid(shape, PITCH, LAM, fill=fill).cone
        zones_n, diff = abs(z) * cone**2 / LAM, np.linalg.norm(w - d) / np.linalg.norm(d)
        print(f"  N = {zones_n:5.1f}: relative difference {diff:.2e}")
        found[f"recording planes against the direct sum at N = {zones_n:.0f} Fresnel zones"] = diff
    return found


if __name__ == "__main__":
    main()
