"""The holographic pass of one saved job, timed per FFT backend: cold and warm seconds.

A job is the plain data the add-on hands its worker (:meth:`holo_core.job.Job.to_dict`),
pickled. Each FFT backend (``HOLO_FFT``) runs in a fresh process of its own, as the add-on's
worker does: the first :func:`holo_core.runner.run` call includes the OpenCL device probe,
the program builds and the FFT plans (with empty kernel caches unless ``--keep-caches``), the
later ones run warm. With ``--processes 2`` a second process per backend starts on the caches
the first one filled (a render in Blender is such a process). A last call, every device stage
synchronised, breaks the pass into stages (with one run, it stands for the warm pass). Prints the
seconds per backend, the ratio of the warm passes against the first backend, and how far the
backends' pictures differ.

    python bench/gpu_pass.py JOB.pickle [--backends vkfft numpy] [--runs 2] [--device gpu]
                             [--suite]

The whole GPU check in one call: ``--suite`` first runs the core's tests on the device
(``HOLO_DEVICE``, the OpenCL and FFT caches in a fresh folder, so that nothing carried from
another machine is read) and prints their summary line, then times the pass.

On a machine with an NVIDIA GPU: pyopencl, NVIDIA's OpenCL driver (a vendor file in
/etc/OpenCL/vendors naming libnvidia-opencl.so.1) and pyvkfft built with
``VKFFT_BACKEND=opencl``. The demo's job at 1920×1080 f/2.8 comes from (bpy needed; Blender's
native libraries never meet an OpenCL driver, so this runs in a process of its own):

    python bench/gpu_pass.py --make-job out/job_1080p.pickle [--resolution 1920 1080] [--fstop 2.8]
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import pickle
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from dataclasses import replace
from pathlib import Path

import numpy as np
import results as bench_results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]


# --- the job ----------------------------------------------------------------------------------


def make_job(path: Path, resolution, fstop, samples) -> None:
    """The demo scene (holo_addon.demo) read into the worker's job and pickled to ``path``."""
    import bpy

    sys.path.insert(0, str(ROOT))
    from holo_addon import register
    from holo_addon.demo import build_scene
    from holo_addon.render import pipeline

    bpy.ops.wm.read_factory_settings(use_empty=True)
    register()
    scene = build_scene(bpy, resolution=tuple(resolution), fstop=fstop)
    scene.holo.output_dir = str(path.resolve().parent / "holo") + os.sep
    scene.holo.mode = "CAMERA"  # the demo's settings
    scene.holo.samples = samples
    job = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get()).job
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as f:
        pickle.dump(job.to_dict(), f, protocol=pickle.HIGHEST_PROTOCOL)
    print(f"{path}: {resolution[0]}x{resolution[1]}, f/{fstop}, {samples} samples")


# --- one backend in this process ---------------------------------------------------------------


class Stages:
    """Exclusive seconds per stage: a stage's time less that of the stages inside it; and, for
    stages wrapped with ``grid_of``, the seconds and calls per grid it names."""

    def __init__(self, sync=None):
        self.seconds = defaultdict(float)
        self.grids = defaultdict(lambda: [0.0, 0])  # grid_of(...) -> [seconds, calls]
        self.stack = []
        self.on = False
        self.sync = sync

    def wrap(self, owner, attr, name, sync=False, grid_of=None):
        """Time ``owner.attr`` as the stage ``name`` (the device synchronised around it with
        ``sync``); returns what undoes the wrapping."""
        fn = getattr(owner, attr, None)
        if fn is None:  # a stage this version of the core does not have: its time is 'other'
            return lambda: None

        def timed(*args, **kwargs):
            if not self.on:
                return fn(*args, **kwargs)
            if sync and self.sync:
                self.sync()
            self.stack.append(0.0)
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                if sync and self.sync:
                    self.sync()
                spent = time.perf_counter() - t0
                inner = self.stack.pop()
                self.seconds[name] += spent - inner
                if self.stack:
                    self.stack[-1] += spent
                if grid_of is not None:
                    cell = self.grids[grid_of(*args, **kwargs)]
                    cell[0] += spent - inner
                    cell[1] += 1

        setattr(owner, attr, timed)
        return lambda: setattr(owner, attr, fn)


def child(job_path: Path, backend: str, runs: int, result_path: Path) -> None:
    logging.basicConfig(level=logging.INFO, format="  %(name)s: %(message)s", stream=sys.stderr)
    t0 = time.perf_counter()
    from holo_core import runner
    from holo_core.camera import incoherent, recording
    from holo_core.camera import raster as camera_raster
    from holo_core.camera import render as camera_render
    from holo_core.job import Job
    from holo_core.opencl import get_runtime

    imported = time.perf_counter() - t0
    with open(job_path, "rb") as f:
        job = Job.from_dict(pickle.load(f))
    job = replace(
        job, output=replace(job.output, folder=Path(tempfile.mkdtemp(prefix="holo-gpu-pass-")))
    )

    stages = Stages()
    for name in ("choose_optics", "rasterize", "point_emitters", "merged"):
        stages.wrap(camera_raster, name, "emitters (host)")
    stages.wrap(recording.PupilFields, "__init__", "device setup and uploads", sync=True)
    stages.wrap(recording.PupilFields, "object_wave", "object wave kernels", sync=True)
    stages.wrap(recording.PupilFields, "image", "image kernels and readback", sync=True)
    # the incoherent route (the add-on's default: the looks' limit in one pass)
    stages.wrap(incoherent.IncoherentImages, "__init__", "device setup and uploads", sync=True)
    stages.wrap(
        incoherent.IncoherentImages, "_transfer_functions", "PSF transfer functions", sync=True
    )
    stages.wrap(incoherent.IncoherentImages, "images", "maps, products, reads (kernels)", sync=True)
    stages.wrap(camera_render._Accumulator, "add", "accumulate looks (host)")
    stages.wrap(camera_render._Accumulator, "add_expected", "accumulate looks (host)")
    stages.wrap(camera_render._Accumulator, "result", "result: colour, depth (host)")
    stages.wrap(runner, "_write_pass", "write EXR and PNG")

    timings = []
    for _ in range(runs):
        t = time.perf_counter()
        runner.run(job)
        timings.append(time.perf_counter() - t)
        print(f"  {backend}: run {timings[-1]:.3f} s", file=sys.stderr, flush=True)
    rt = get_runtime()
    stages.sync = rt.queue.finish
    stages.wrap(rt.fft, "forward", "FFT forward", sync=True)
    stages.wrap(rt.fft, "backward", "FFT backward", sync=True)
    stages.on = True
    t = time.perf_counter()
    view = runner.run(job).view
    profiled = time.perf_counter() - t
    stages.on = False
    np.save(result_path.with_suffix(".npy"), view.rgb * view.alpha[..., None])
    result_path.write_text(
        json.dumps(
            {
                "backend": rt.fft.name,
                "device": rt.device.name.strip(),
                "platform": rt.device.platform.name.strip(),
                "driver": rt.device.driver_version,
                "import_s": imported,
                "runs_s": timings,
                "profiled_s": profiled,
                "stages": dict(stages.seconds),
                "info": {k: v for k, v in view.info.items() if k != "pass_key"},
            }
        )
    )


# --- the parent ---------------------------------------------------------------------------------


def run_suite(device: str) -> bool:
    """The core's tests on ``device`` in a child process with fresh OpenCL and FFT caches."""
    cache = Path(tempfile.mkdtemp(prefix="holo-gpu-suite-"))
    env = dict(
        os.environ,
        HOLO_DEVICE=device,
        XDG_CACHE_HOME=str(cache),
        PYOPENCL_CACHE_FAILURE_FATAL="",
        PYTHONUNBUFFERED="1",
    )
    print(f"== the core's tests on HOLO_DEVICE={device!r} (caches in {cache})", flush=True)
    r = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests/core"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
    )
    lines = r.stdout.strip().splitlines()
    failed = [line for line in lines if line.startswith(("FAILED", "ERROR"))]
    print("\n".join(failed + lines[-1:]), flush=True)
    return r.returncode == 0


def run_backend(args, backend, cache, index, out: Path) -> dict | None:
    env = dict(os.environ, HOLO_FFT=backend, PYTHONUNBUFFERED="1", XDG_CACHE_HOME=str(cache))
    if args.device:
        env["HOLO_DEVICE"] = args.device
    if index == 0 and not args.keep_caches:
        env["CUDA_CACHE_DISABLE"] = "1"  # NVIDIA's driver-side kernel cache
    result = out / f"{backend}-{index}.json"
    cmd = [
        sys.executable,
        str(Path(__file__).resolve()),
        str(args.job),
        "--child",
        backend,
        "--runs",
        str(args.runs),
        "--result",
        str(result),
    ]
    print(
        f"== HOLO_FFT={backend}, process {index + 1}"
        f"{' (empty caches)' if index == 0 and not args.keep_caches else ''}",
        flush=True,
    )
    t = time.perf_counter()
    if subprocess.run(cmd, check=False, env=env).returncode != 0 or not result.is_file():
        print(f"   {backend}: the process failed")
        return None
    r = json.loads(result.read_text())
    r["process_s"] = time.perf_counter() - t
    r["picture"] = result.with_suffix(".npy")
    return r


def report(results: dict) -> None:
    first = next(iter(results.values()))[0]
    print(f"\ndevice: {first['device']} ({first['platform']}, driver {first['driver']})")
    info = first["info"]
    print(
        f"pass: {info.get('pupil_samples')} pupil samples, {info.get('samples')} looks, "
        f"{info.get('layers')} depth layer(s)"
    )
    print(
        f"{'backend':<8} {'process':>7} {'import':>7} {'first':>8} {'warm':>8} "
        f"{'profiled':>8}  stages of the profiled call (exclusive)"
    )
    for procs in results.values():
        for i, r in enumerate(procs):
            warm = f"{min(r['runs_s'][1:]):.2f}s" if len(r["runs_s"]) > 1 else "-"
            print(
                f"{r['backend']:<8} {i + 1:>7} {r['import_s']:>6.2f}s {r['runs_s'][0]:>7.2f}s "
                f"{warm:>8} {r['profiled_s']:>7.2f}s"
            )
        r = procs[0]
        total = r["profiled_s"]
        for name, s in sorted(r["stages"].items(), key=lambda kv: -kv[1]):
            print(f"{'':>46} {name:<32} {s:7.3f} s ({s / total:5.1%})")
        print(f"{'':>46} {'other':<32} {total - sum(r['stages'].values()):7.3f} s")
    names = list(results)
    base = results[names[0]][0]
    base_warm = min(base["runs_s"][1:] or [base["profiled_s"]])
    ref = np.load(base["picture"])
    for other in names[1:]:
        r = results[other][0]
        warm = min(r["runs_s"][1:] or [r["profiled_s"]])
        diff = np.abs(np.load(r["picture"]) - ref).max() / max(float(np.abs(ref).max()), 1e-30)
        print(
            f"warm {names[0]} / {other}: {base_warm / warm:.3f} "
            f"({base_warm:.2f} s / {warm:.2f} s); pictures differ by {diff:.1e} of the peak"
        )


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("job", type=Path)
    p.add_argument(
        "--backends",
        nargs="+",
        default=["vkfft", "numpy"],
        help="HOLO_FFT values, the first is the reference of the ratios",
    )
    p.add_argument(
        "--runs",
        type=int,
        default=2,
        help="timed runs per process, before the profiled one (with one, "
        "the profiled call stands for the warm pass)",
    )
    p.add_argument("--processes", type=int, default=1, help="processes per backend")
    p.add_argument("--device", default="gpu", help="HOLO_DEVICE ('' for the default)")
    p.add_argument(
        "--keep-caches",
        action="store_true",
        help="let the first process use the user's kernel caches",
    )
    p.add_argument("--make-job", action="store_true", help="write the demo's job to JOB")
    p.add_argument(
        "--suite",
        action="store_true",
        help="run the core's tests on the device first (the whole GPU check)",
    )
    p.add_argument("--resolution", type=int, nargs=2, default=(1920, 1080))
    p.add_argument("--fstop", type=float, default=2.8)
    p.add_argument("--samples", type=int, default=16)
    p.add_argument("--child", help=argparse.SUPPRESS)
    p.add_argument("--result", type=Path, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.make_job:
        return make_job(args.job, args.resolution, args.fstop, args.samples)
    if args.child:
        return child(args.job, args.child, max(args.runs, 1), args.result)
    suite_ok = run_suite(args.device) if args.suite else True
    out = Path(tempfile.mkdtemp(prefix="holo-gpu-pass-"))
    results = {}
    for backend in args.backends:
        cache = Path(tempfile.mkdtemp(prefix=f"holo-cache-{backend}-"))
        for i in range(args.processes):
            r = run_backend(args, backend, cache, i, out)
            if r is None:
                break
            results.setdefault(backend, []).append(r)
    if results:
        report(results)
        bench_results.write(
            "gpu_pass",
            {
                f"{backend}, process {i + 1}": {
                    "import [s]": r["import_s"],
                    "first pass [s]": r["runs_s"][0],
                    "warm pass [s]": min(r["runs_s"][1:]) if len(r["runs_s"]) > 1 else "",
                    "profiled [s]": r["profiled_s"],
                }
                for backend, procs in results.items()
                for i, r in enumerate(procs)
            },
            device=next(iter(results.values()))[0]["device"],
        )
    return 0 if len(results) == len(args.backends) and suite_ok else 1


if __name__ == "__main__":
    sys.exit(main())
