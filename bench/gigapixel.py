"""Gigapixel plates: recorded tile by tile on a local Dask cluster into a Zarr store, and viewed,
with the peak memory of every process (this one, the scheduler, the workers) and the time,
against the plate recorded in memory at the largest size both can do, in the same run.

The scene: point emitters spread evenly over the plate (so the work per sample is the same at
every size), 1–2 cm behind a plate of 4 µm pitch at 532 nm; 10⁴ points at 32768². The view:
640×360 on a 12 mm sensor, 100 mm at f/16, 5 cm in front of the plate's centre, which sees a part of the plate:
only the tiles in its window are read.

    python bench/gigapixel.py [--sizes 8192 16384 32768] [--memory-sizes 8192]
                              [--tile 2048] [--dir DIR]

Prints per size: points, recording time, Mpx/s per core, peak memory [GB] of all processes,
the view's time, window and tiles read; then the tiled route's time against the in-memory one.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT)]

import psutil  # noqa: E402  (Dask's own dependency)

from holo_core.io.image import write_png  # noqa: E402
from holo_core.plate.points import record_points  # noqa: E402
from holo_core.plate.tiles import record_tiled  # noqa: E402
from holo_core.plate.view import render_view  # noqa: E402
from holo_core.scene.camera import Camera, look_at  # noqa: E402

PITCH, WAVELENGTH, POINTS_PER_GPX = 4e-6, 532e-9, 1e4 / 32768**2 * 1e9


class PeakMemory:
    """The largest sum of resident memory over this process and all its descendants, sampled
    every 50 ms while the block runs."""

    def __enter__(self):
        self.peak, self._stop = 0, threading.Event()
        self._thread = threading.Thread(target=self._sample, daemon=True)
        self._thread.start()
        return self

    def _sample(self):
        me = psutil.Process()
        while not self._stop.wait(0.05):
            total = 0
            for p in [me, *me.children(recursive=True)]:
                try:
                    total += p.memory_info().rss
                except psutil.Error:
                    pass
            self.peak = max(self.peak, total)

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()


def scene(size, seed=1):
    n = round(POINTS_PER_GPX * size * size / 1e9)
    half = size * PITCH / 2
    rng = np.random.default_rng(seed)
    positions = np.c_[rng.uniform(-half, half, (n, 2)), rng.uniform(-0.02, -0.01, n)]
    return positions, rng.uniform(0.2, 1.0, (n, 1))


def camera():
    eye = np.array([0.002, 0.001, 0.05])
    return Camera(
        matrix_world=look_at(eye, (0.002, 0.001, -0.015), up=(0, 1, 0)),
        lens=100,
        sensor_width=12,
        resolution=(640, 360),
        fstop=16,
        focus_distance=0.065,
    )


def timed(f, *args, **kw):
    with PeakMemory() as mem:
        t = time.perf_counter()
        out = f(*args, **kw)
        seconds = time.perf_counter() - t
    return out, seconds, mem.peak / 1e9


def measure(size, mode, tile, work: Path, out: Path | None) -> dict:
    """One size by one route, in this (fresh) process: times [s] and peaks [GB]."""
    pos, col = scene(size)
    if mode == "memory":
        _, rec_s, rec_gb = timed(
            record_points,
            pos,
            col,
            shape=(size, size),
            pitch=PITCH,
            wavelengths=(WAVELENGTH,),
            method="direct",
            keep_object_wave=True,
        )
        return {"record_s": rec_s, "record_gb": rec_gb}
    url = work / f"plate{size}.zarr"
    h, rec_s, rec_gb = timed(
        record_tiled,
        pos,
        col,
        url=url,
        shape=(size, size),
        pitch=PITCH,
        wavelengths=(WAVELENGTH,),
        tile=tile,
    )
    view, view_s, view_gb = timed(render_view, h, camera(), supersample=1)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        write_png(
            out / f"view{size}.png",
            np.clip(view.rgb / max(view.rgb.max(), 1e-30), 0, 1) ** (1 / 2.2),
        )
    return {
        "points": len(pos),
        "record_s": rec_s,
        "record_gb": rec_gb,
        "view_s": view_s,
        "view_gb": view_gb,
    }


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[8192, 16384, 32768])
    p.add_argument(
        "--memory-sizes",
        type=int,
        nargs="*",
        default=[8192],
        help="sizes also recorded in memory (the reference; 16384² needs ~40 GB)",
    )
    p.add_argument("--tile", type=int, default=2048)
    p.add_argument("--dir", type=Path, default=None, help="where the stores go (a temp dir)")
    p.add_argument("--out", type=Path, default=None, help="a folder for the views' PNGs")
    p.add_argument("--one", nargs=2, metavar=("SIZE", "MODE"), help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.one:  # a child: one measurement, printed as JSON on the last line
        print(json.dumps(measure(int(args.one[0]), args.one[1], args.tile, args.dir, args.out)))
        return
    cores = os.cpu_count() or 1
    work = Path(tempfile.mkdtemp(dir=args.dir))
    print(f"{cores} cores; stores in {work}; each measurement in a fresh process", flush=True)

    def child(size, mode):
        cmd = [
            sys.executable,
            __file__,
            "--one",
            str(size),
            mode,
            "--tile",
            str(args.tile),
            "--dir",
            str(work),
        ] + (["--out", str(args.out)] if args.out else [])
        run = subprocess.run(cmd, capture_output=True, text=True, check=True)
        return json.loads(run.stdout.strip().splitlines()[-1])

    tiled, memory = {}, {}
    try:
        for size in args.sizes:
            r = tiled[size] = child(size, "tiled")
            print(
                f"{size}²: {r['points']} points, recorded in {r['record_s']:.1f} s "
                f"({size * size / 1e6 / r['record_s'] / cores:.2f} Mpx/s per core), peak "
                f"{r['record_gb']:.2f} GB; view {r['view_s']:.1f} s, peak {r['view_gb']:.2f} "
                f"GB",
                flush=True,
            )
            shutil.rmtree(work / f"plate{size}.zarr", ignore_errors=True)
        for size in args.memory_sizes:
            r = memory[size] = child(size, "memory")
            ratio = (
                f", tiled/in-memory time {tiled[size]['record_s'] / r['record_s']:.2f}"
                if size in tiled
                else ""
            )
            print(
                f"{size}² in memory: {r['record_s']:.1f} s, peak {r['record_gb']:.2f} GB{ratio}",
                flush=True,
            )
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print("\nsize    points  record [s]  Mpx/s/core  peak [GB]  view [s]  view peak [GB]")
    for size, r in tiled.items():
        print(
            f"{size:6d}  {r['points']:6d}  {r['record_s']:10.1f}  "
            f"{size * size / 1e6 / r['record_s'] / cores:10.2f}  {r['record_gb']:9.2f}  "
            f"{r['view_s']:8.1f}  {r['view_gb']:14.2f}"
        )
    if len(tiled) > 1:  # time = fixed + per-sample: the fit's slope is the linear part
        n = np.array([s * s for s in tiled], float)
        t = np.array([r["record_s"] for r in tiled.values()])
        slope, fixed = np.polyfit(n, t, 1)
        worst = np.abs(fixed + slope * n - t).max() / t.max()
        print(
            f"time = {fixed:.1f} s + {slope * 1e9:.1f} s per Gpx (largest deviation "
            f"{worst:.1%} of the longest): {1e-6 / slope / cores:.2f} Mpx/s per core "
            f"beyond the cluster's start"
        )
    table = {
        f"{size}², tiled": {
            "points": r["points"],
            "record [s]": r["record_s"],
            "Mpx/s per core": size * size / 1e6 / r["record_s"] / cores,
            "peak [GB]": r["record_gb"],
            "a 640x360 view [s]": r["view_s"],
            "the view's peak [GB]": r["view_gb"],
        }
        for size, r in tiled.items()
    }
    table.update(
        {
            f"{size}², in memory": {"record [s]": r["record_s"], "peak [GB]": r["record_gb"]}
            for size, r in memory.items()
        }
    )
    results.write("gigapixel", table)


if __name__ == "__main__":
    main()
