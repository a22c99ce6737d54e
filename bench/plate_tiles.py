"""Plates of meshes recorded tile by tile on a local Dask cluster into a Zarr store, against the
same plate recorded in memory, in one run, with the peak memory of every process (this one,
the scheduler, the workers) and the time.

The scene is bench/shot.py's (a textured cube partly hiding a textured sphere, about a metre
across 3.5 m from the camera, a 1 m plate halfway, 40 mm at f/2.8, 1280x720 times --scale).
Each size is the zone fitted to a dolly of one of --dollies: a wider zone asks more samples of
the same emitters (the band grows, the emitters do not). Each route runs in a fresh process.

    python bench/plate_tiles.py [--scale 0.5] [--dollies 0.1 0.4] [--tile 2048] [--dir DIR]

Prints per size: the samples and emitters, the recording's time and the peak memory of all
processes, tiled and in memory, and whether the two plates are equal bit for bit (else their
largest difference); the CPU and its load.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(ROOT / "bench")]

from gigapixel import timed  # noqa: E402
from shot import PLATE, camera, cpu, scene  # noqa: E402

from holo_core.io.tiled_wave import open_plate  # noqa: E402
from holo_core.plate.looks import record_plate  # noqa: E402
from holo_core.scene.plate import Plate, ViewingZone  # noqa: E402


def plate_for(dolly, scale) -> Plate:
    cams = [camera(x, scale) for x in (-dolly / 2, dolly / 2)]
    zone = ViewingZone.fit(
        [c.position for c in cams],
        pupil=cams[0].aperture_diameter,
        margin=0.01,
        pixel=cams[0].pixel_angle(),
    )
    return Plate(matrix_world=PLATE.matrix_world, width=PLATE.width, height=PLATE.height, zone=zone)


def measure(dolly, scale, mode, tile, url) -> dict:
    """One size by one route, in this (fresh) process: the time [s] and peak [GB]; in memory,
    also the comparison with the tiled store at ``url``."""
    plate = plate_for(dolly, scale)
    if mode == "tiled":
        h, seconds, peak = timed(record_plate, scene(), plate=plate, seed=0, url=url, tile=tile)
        parts = json.loads((Path(url) / "zarr.json").read_text())["attributes"]["recording"]
        return {
            "shape": list(h.shape),
            "emitters": parts["parts"]["emitters"],
            "seconds": seconds,
            "peak": peak,
        }
    h, seconds, peak = timed(record_plate, scene(), plate=plate, seed=0)
    tiled = open_plate(url)
    worst, equal = 0.0, True
    for c in range(len(h.wavelengths)):  # a channel at a time: the store read in its tiles
        a, b = h.object_wave[c], tiled.object_wave[c]
        equal &= bool(np.array_equal(a, b))
        worst = max(worst, float(np.abs(a - b).max() / np.abs(a).max()))
    return {"seconds": seconds, "peak": peak, "equal": equal, "worst": worst}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scale", type=float, default=0.5, help="image size, of 1280x720 (0.5)")
    p.add_argument(
        "--dollies",
        type=float,
        nargs="+",
        default=[0.1, 0.4],
        help="the camera moves the zones are fitted to [m] (0.1 0.4)",
    )
    p.add_argument("--tile", type=int, default=2048)
    p.add_argument("--dir", type=Path, default=None, help="where the stores go (a temp dir)")
    p.add_argument("--one", nargs=3, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.one:  # a child: one measurement, printed as JSON on the last line
        dolly, mode, url = args.one
        print(json.dumps(measure(float(dolly), args.scale, mode, args.tile, url)))
        return
    work = Path(tempfile.mkdtemp(dir=args.dir))
    print(
        f"CPU: {cpu()}; load {os.getloadavg()[0]:.1f} (1 min) at the start; stores in "
        f"{work}; each route in a fresh process",
        flush=True,
    )

    def child(dolly, mode, url):
        cmd = [
            sys.executable,
            __file__,
            "--one",
            str(dolly),
            mode,
            str(url),
            "--scale",
            str(args.scale),
            "--tile",
            str(args.tile),
        ]
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode:
            raise SystemExit(run.stderr[-2000:])
        return json.loads(run.stdout.strip().splitlines()[-1])

    rows = []
    try:
        for dolly in args.dollies:
            url = work / f"plate{dolly:g}.zarr"
            tiled = child(dolly, "tiled", url)
            whole = child(dolly, "memory", url)
            rows.append((dolly, tiled, whole))
            (r, c), n = tiled["shape"], tiled["emitters"]
            same = "bit-equal" if whole["equal"] else f"differ by {whole['worst']:.2e}"
            print(
                f"dolly {dolly:g} m: {c} x {r} samples ({r * c / 1e6:.1f} Mpx), {n:,} "
                f"emitters; tiled {tiled['seconds']:.1f} s, peak {tiled['peak']:.2f} GB; in "
                f"memory {whole['seconds']:.1f} s, peak {whole['peak']:.2f} GB; {same} (load "
                f"{os.getloadavg()[0]:.1f})",
                flush=True,
            )
            shutil.rmtree(url, ignore_errors=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print("\ndolly [m]  Mpx    emitters  tiled [s]  peak [GB]  memory [s]  peak [GB]  equal")
    for dolly, tiled, whole in rows:
        (r, c) = tiled["shape"]
        print(
            f"{dolly:9g}  {r * c / 1e6:5.1f}  {tiled['emitters']:8d}  {tiled['seconds']:9.1f}"
            f"  {tiled['peak']:9.2f}  {whole['seconds']:10.1f}  {whole['peak']:9.2f}  "
            f"{'bit' if whole['equal'] else whole['worst']}"
        )
    print(f"load at the end {os.getloadavg()[0]:.1f}")
    results.write(
        "plate_tiles",
        {
            f"dolly {dolly:g} m": {
                "samples": f"{tiled['shape'][1]} x {tiled['shape'][0]}",
                "emitters": tiled["emitters"],
                "tiled [s]": tiled["seconds"],
                "tiled peak [GB]": tiled["peak"],
                "in memory [s]": whole["seconds"],
                "in memory peak [GB]": whole["peak"],
                "plates": "bit-equal" if whole["equal"] else whole["worst"],
            }
            for dolly, tiled, whole in rows
        },
    )


if __name__ == "__main__":
    main()
