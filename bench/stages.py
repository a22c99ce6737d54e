"""Where the time goes, each stage against its bound, in one run: the camera pass at 1920×1080
(the demo's job), a plate view, and a slab step of the plate's recording.

A stage's time is measured with the device synchronised around it (exclusive of the stages
inside it), the median of ``--rounds`` runs. Its bound, measured in the same run:

- a transform: FFTW's 2-D transform of the same grid with a plan measured once (one thread;
  planning limited to ``--plan-seconds``, kept in this bench's own wisdom file; in a process
  of its own, after the stages), what the transform costs without the pruning;
- a padded convolution (a propagation): two such transforms and one pass of NumPy's multiply;
- an element-wise stage: the bytes it must read and write over this machine's copy
  bandwidth (a NumPy copy of 512 MiB, measured here);
- host stages (rasterising, the result's colour, alpha and depth, the files) are listed with
  their time alone.

    python bench/stages.py [--job JOB.pickle] [--plate-samples 2048] [--plan-seconds 60]

JOB comes from ``python bench/gpu_pass.py --make-job JOB.pickle`` (the demo scene at 1920×1080,
f/2.8; made here in a child process when it is missing).
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pyfftw

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), os.path.dirname(__file__)]

import results  # noqa: E402  (the bench folder's own: the figures as data)
from gpu_pass import Stages  # noqa: E402  (the bench folder's own helpers)
from sweep import cpu_name  # noqa: E402

from holo_core.opencl import get_runtime  # noqa: E402
from holo_core.opencl.host_fft import HostFFT  # noqa: E402


class Synced(Stages):
    """Every stage timed with the device synchronised around it."""

    def wrap(self, owner, attr, name, grid_of=None):
        return super().wrap(owner, attr, name, sync=True, grid_of=grid_of)


def transform_grid(self, a, direction, nonzero=None, read=None):
    return ("transform", a.shape)


def convolution_grid(self, field, transfer, out, padded=None):
    return ("convolution", padded or transfer.shape)


class Bounds:
    """FFTW's measured 2-D transforms (one thread), NumPy's multiply and the copy bandwidth."""

    def __init__(self, plan_seconds):
        self.plan_seconds = plan_seconds
        src = np.ones(2**26, np.complex64)  # 512 MiB
        dst = np.empty_like(src)
        times = []
        for _ in range(5):
            t = time.perf_counter()
            np.copyto(dst, src)
            times.append(time.perf_counter() - t)
        self.bandwidth = 2 * src.nbytes / min(times)  # bytes read and written per second
        del src, dst
        from platformdirs import user_cache_dir

        self.wisdom = os.path.join(user_cache_dir("holo"), "bench-bound-wisdom.pickle")
        try:
            with open(self.wisdom, "rb") as f:
                pyfftw.import_wisdom(pickle.load(f))
        except (OSError, pickle.UnpicklingError, EOFError):
            pass
        self.cache = {}

    def transform(self, shape) -> float:
        """Seconds of FFTW's measured 2-D transform of ``shape`` (median of 3)."""
        if shape not in self.cache:
            a = pyfftw.empty_aligned(shape, np.complex64)
            plan = pyfftw.FFTW(
                a,
                a,
                axes=(0, 1),
                flags=("FFTW_MEASURE",),
                threads=1,
                planning_timelimit=self.plan_seconds,
            )
            with open(self.wisdom, "wb") as f:
                pickle.dump(pyfftw.export_wisdom(), f)
            a[...] = 1
            times = []
            for _ in range(3):
                t = time.perf_counter()
                plan.execute()
                times.append(time.perf_counter() - t)
            self.cache[shape] = statistics.median(times)
        return self.cache[shape]

    def convolution(self, shape) -> float:
        a = np.ones(shape, np.complex64)
        t = time.perf_counter()
        np.multiply(a, a, out=a)
        multiply = time.perf_counter() - t
        return 2 * self.transform(shape) + multiply

    def memory(self, nbytes) -> float:
        return nbytes / self.bandwidth

    def of(self, grids) -> dict:
        """The bounds of ``grids`` ((kind, shape) pairs) and the bandwidth, as plain data."""
        return {
            "bandwidth": self.bandwidth,
            "grids": [
                [
                    kind,
                    list(shape),
                    self.transform(tuple(shape))
                    if kind == "transform"
                    else self.convolution(tuple(shape)),
                ]
                for kind, shape in grids
            ],
        }


class Measured:
    """The bounds measured by a child process (``--bounds-of``): FFTW's wisdom never meets
    Holo's in one process, where a plan Holo measures would keep both in its wisdom file."""

    def __init__(self, grids, plan_seconds):
        r = subprocess.run(
            [
                sys.executable,
                __file__,
                "--bounds-of",
                json.dumps(grids),
                "--plan-seconds",
                str(plan_seconds),
            ],
            capture_output=True,
            text=True,
            check=True,
        )
        data = json.loads(r.stdout.strip().splitlines()[-1])
        self.bandwidth = data["bandwidth"]
        self.grids = {(kind, tuple(shape)): t for kind, shape, t in data["grids"]}

    def transform(self, shape) -> float:
        return self.grids["transform", tuple(shape)]

    def convolution(self, shape) -> float:
        return self.grids["convolution", tuple(shape)]

    def memory(self, nbytes) -> float:
        return nbytes / self.bandwidth


def fft_stages(stages: Stages) -> list:
    """Time every host transform and convolution by its grid (the wrappers' undo)."""
    return [
        stages.wrap(HostFFT, "transform", "transforms", transform_grid),
        stages.wrap(HostFFT, "convolve", "convolutions (propagations)", convolution_grid),
    ]


def median_of(rounds: list[tuple[Stages, float]]) -> tuple[Stages, float]:
    """One :class:`Stages` holding each stage's and grid's median over ``rounds`` (each a
    Stages and its total seconds), and the median total."""
    out = Stages()
    for key in {k for st, _ in rounds for k in st.seconds}:
        out.seconds[key] = statistics.median(st.seconds.get(key, 0.0) for st, _ in rounds)
    for key in {k for st, _ in rounds for k in st.grids}:
        cells = [st.grids.get(key, [0.0, 0]) for st, _ in rounds]
        out.grids[key] = [statistics.median(c[0] for c in cells), cells[0][1]]
    return out, statistics.median(t for _, t in rounds)


def measured(run, wrap, rounds, sync) -> tuple[Stages, float]:
    """``run()`` ``rounds`` times, each with stages ``wrap(stages)`` put in place: the
    medians (:func:`median_of`)."""
    results = []
    for _ in range(rounds):
        stages = Synced(sync)
        undo = wrap(stages)
        stages.on = True
        t = time.perf_counter()
        run()
        results.append((stages, time.perf_counter() - t))
        for u in undo:
            u()
    return median_of(results)


def report(title, stages: Stages, total, bounds: Measured, memory_bytes, host):
    """The stages' table: time, bound, ratio; ``memory_bytes``: stage -> bytes it moves;
    ``host``: stages with no bound."""
    print(f"\n{title}: {total:.2f} s in all (load {os.getloadavg()[0]:.1f})")
    print(f"  {'stage':44s} {'seconds':>8s} {'bound':>8s} {'x bound':>8s}")
    rows = {f"{title}: all": {"s": total}}
    for (kind, shape), (seconds, calls) in sorted(stages.grids.items(), key=lambda kv: -kv[1][0]):
        bound = calls * (
            bounds.transform(shape) if kind == "transform" else bounds.convolution(shape)
        )
        label = f"{calls} {kind}{'s' * (calls > 1)} of {shape[0]}x{shape[1]}"
        print(f"  {label:44s} {seconds:8.3f} {bound:8.3f} {seconds / bound:8.2f}")
        rows[f"{title}: {label}"] = {"s": seconds, "bound [s]": bound, "× bound": seconds / bound}
    for name, seconds in sorted(stages.seconds.items(), key=lambda kv: -kv[1]):
        if name in ("transforms", "convolutions (propagations)"):
            continue
        if name in memory_bytes:
            bound = bounds.memory(memory_bytes[name])
            print(f"  {name:44s} {seconds:8.3f} {bound:8.3f} {seconds / bound:8.2f}")
            rows[f"{title}: {name}"] = {
                "s": seconds,
                "bound [s]": bound,
                "× bound": seconds / bound,
            }
        else:
            print(f"  {name:44s} {seconds:8.3f} {'(host)' if name in host else '':>8s}")
            rows[f"{title}: {name}"] = {"s": seconds, "bound [s]": "(host)" if name in host else ""}
    other = total - sum(stages.seconds.values())
    print(f"  {'other':44s} {other:8.3f}")
    rows[f"{title}: other"] = {"s": other}
    return rows


# --- the camera pass --------------------------------------------------------------------------


def camera_pass(job_path: Path, rt, rounds) -> list:
    from holo_core import runner
    from holo_core.camera import incoherent
    from holo_core.camera import raster as camera_raster
    from holo_core.camera import render as camera_render
    from holo_core.job import Job

    with open(job_path, "rb") as f:
        job = Job.from_dict(pickle.load(f))
    job = replace(
        job, output=replace(job.output, folder=Path(tempfile.mkdtemp(prefix="holo-stages-")))
    )
    runner.run(job)  # warm: programs built, plans read or measured
    views = []

    def wrap(stages):
        undo = [
            stages.wrap(camera_raster, name, "emitters (host)")
            for name in ("choose_optics", "rasterize", "point_emitters", "merged")
        ]
        undo += [
            stages.wrap(incoherent.IncoherentImages, "__init__", "device setup and uploads"),
            stages.wrap(incoherent.IncoherentImages, "_transfer_functions", "PSF kernels (pupils)"),
            stages.wrap(incoherent.IncoherentImages, "images", "maps, products, reads (kernels)"),
            stages.wrap(
                camera_render._Accumulator, "result", "result: colour, alpha, depth (host)"
            ),
            stages.wrap(runner, "_write_pass", "write EXR and PNG (host)"),
        ]
        return undo + fft_stages(stages)

    stages, total = measured(
        lambda: views.append(runner.run(job).view), wrap, rounds, rt.queue.finish
    )
    view = views[-1]
    h, w = view.info["pupil_samples"]
    fine = view.rgb.shape[0] * view.rgb.shape[1] * view.info["resolution_limit_px"] ** -2
    grid, read = 4 * h * w, 9 * h * w * 1.0  # the 2x grid; the 1.5x read grid (about)
    memory_bytes = {  # what each element-wise stage must read and write, at least
        # 3 maps: 3 products (read the PSF's transform, write the accumulator), 3 embeddings
        # (read it, write the read grid's corners), 3 reads (the read grid once, the pixels)
        "maps, products, reads (kernels)": 8 * (3 * 2 * grid + 3 * 2 * grid + 3 * read + 3 * fine),
        # 2 pupils (h·w) into the 2x grid, and the PSFs' products (read 2, write 2 grids)
        "PSF kernels (pupils)": 8 * (2 * 2 * h * w + 4 * grid),
    }
    return [
        (
            f"camera pass, {view.rgb.shape[1]}x{view.rgb.shape[0]}, pupil {w}x{h} "
            f"({view.info['layers']} layer)",
            stages,
            total,
            memory_bytes,
            {
                "emitters (host)",
                "result: colour, alpha, depth (host)",
                "write EXR and PNG (host)",
                "device setup and uploads",
            },
        )
    ]


# --- a plate's recording (its slab steps) and a view ------------------------------------------


def plate(samples: int, rt, rounds) -> list:
    from plate_scene import PLATE, camera, meshes

    from holo_core.plate import composition, pupil_images, slabs
    from holo_core.plate.looks import record_plate
    from holo_core.plate.view import render_view

    centre = camera("centre", 1.0)
    # warm: programs built, the FFT plans of these grids read (or measured, once per machine)
    render_view(record_plate(meshes(), plate=PLATE, camera=centre, resolution=samples), centre)
    plates = []
    stages, total = measured(
        lambda: plates.append(
            record_plate(meshes(), plate=PLATE, camera=centre, resolution=samples)
        ),
        lambda st: (
            [st.wrap(slabs, "record_slabs", "slab recording (host: emitters, masks)")]
            + fft_stages(st)
        ),
        rounds,
        rt.queue.finish,
    )
    h = plates[-1]
    tables = [
        (
            f"plate recording by slabs, {h.shape[1]}x{h.shape[0]} (its slab steps are the "
            f"convolutions)",
            stages,
            total,
            {},
            {"slab recording (host: emitters, masks)"},
        )
    ]
    stages, total = measured(
        lambda: render_view(h, centre),
        lambda st: (
            [
                st.wrap(
                    pupil_images, "field_at_pupil", "window to the pupil (propagation, rotation)"
                ),
                st.wrap(pupil_images.PupilImage, "image", "pupil to image (window, read pixels)"),
                st.wrap(composition, "compose", "compose the looks (host)"),
            ]
            + fft_stages(st)
        ),
        rounds,
        rt.queue.finish,
    )
    return tables + [
        (
            f"plate view, {centre.resolution[0]}x{centre.resolution[1]} from the "
            f"{h.shape[1]}x{h.shape[0]} plate",
            stages,
            total,
            {},
            {"compose the looks (host)"},
        )
    ]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--job", type=Path, default=ROOT / "out" / "job_1080p.pickle")
    p.add_argument("--plate-samples", type=int, default=2048)
    p.add_argument("--plan-seconds", type=float, default=60.0)
    p.add_argument("--parts", nargs="+", default=["camera", "plate"])
    p.add_argument("--rounds", type=int, default=3, help="runs of a pass or a view (medians)")
    p.add_argument("--bounds-of", help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.bounds_of:  # the child: the bounds alone, printed as JSON
        print(json.dumps(Bounds(args.plan_seconds).of(json.loads(args.bounds_of))))
        return
    if "camera" in args.parts and not args.job.is_file():
        subprocess.run(
            [sys.executable, str(ROOT / "bench" / "gpu_pass.py"), str(args.job), "--make-job"],
            check=True,
        )
    rt = get_runtime()
    print(
        f"CPU: {cpu_name()}, load average {os.getloadavg()[0]:.1f}; device: "
        f"{rt.device.name.strip()} ({rt.device.platform.name.strip()}), FFT {rt.fft.name}"
    )
    tables = []
    if "camera" in args.parts:
        tables += camera_pass(args.job, rt, args.rounds)
    if "plate" in args.parts:
        tables += plate(args.plate_samples, rt, args.rounds)
    grids = sorted({(kind, tuple(shape)) for _, st, *_ in tables for kind, shape in st.grids})
    bounds = Measured([[kind, list(shape)] for kind, shape in grids], args.plan_seconds)
    print(
        f"copy bandwidth {bounds.bandwidth / 1e9:.1f} GB/s (read + written); the bounds "
        f"measured after the stages, in a process of their own"
    )
    figures = {"copy bandwidth, read + written [GB/s]": {"s": bounds.bandwidth / 1e9}}
    for title, stages, total, memory_bytes, host in tables:
        figures.update(report(title, stages, total, bounds, memory_bytes, host))
    print(f"\nload average at the end {os.getloadavg()[0]:.1f}")
    results.write(
        "stages",
        figures,
        device=f"{rt.device.name.strip()} ({rt.device.platform.name.strip()}), FFT {rt.fft.name}",
    )


if __name__ == "__main__":
    main()
