"""Looking around a held plate: views a second and each view's latency from the camera's change
to its picture, full and coarse, of a camera wandering inside the plate's zone, against the
camera pass of the same frame and render_view unplanned, in one run.

The scene is ``bench/shot.py``'s (a textured cube partly hiding a sphere 3.5 m from the camera,
a 1 m plate halfway, 40 mm f/2.8, its zone fitted to a 10 cm dolly), recorded once with
``--looks`` coded looks at each ``--scales`` (0.5: 640×360; 1: 1280×720) and held by a
:class:`holo_core.PlateViewer`. The camera wanders inside the zone: sideways over most of its
width, up and down, nearer and farther, its aim turning by a few degrees; its ``--poses``
poses are viewed by render_view alone (each view sized exactly and planned afresh), then by
the viewer once (first visits: every size met for the first time plans its transforms and
builds its kernels) and again (revisits). For each: the full view's seconds (the picture
render_view gives, planned with the viewer's slack) and the coarse view's (one look, one sample
a pixel, at most 320×180 pixels upsampled). The latency in the core is the view's own time: a
call returns its picture. Then one full view of the first pose stage by stage, the device
synchronised around each kernel and transform, each against the bound the issue sets: the
bytes of the window's samples the view reads over this machine's memory bandwidth, measured
here (a NumPy copy of 256 MiB).

    python bench/live.py [--scales 0.5 1.0] [--poses 8] [--looks 2] [--supersample 2]
                         [--plates DIR]

``--plates DIR`` keeps each scale's recorded looks there (``DIR/scaleS/lookK.exr``) and reads
them on the next run instead of recording again. Writes ``bench/results/live.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(Path(__file__).resolve().parent)]

import shot  # noqa: E402  (the bench folder's own: the shot's scene and camera)

from holo_core import PlateViewer  # noqa: E402
from holo_core.camera.render import render_camera  # noqa: E402
from holo_core.io.hologram import read_hologram, write_hologram  # noqa: E402
from holo_core.plate.looks import record_looks  # noqa: E402
from holo_core.scene.camera import look_at  # noqa: E402
from holo_core.scene.plate import Plate, ViewingZone  # noqa: E402

TARGET_FULL = {0.5: 8.0, 1.0: 2.0}  # the views a second at 640×360 and 1280×720
COARSE_LATENCY = 0.1  # [s] the coarse picture after a move


def load() -> float:
    return round(os.getloadavg()[0], 2)


def held_plate(scale: float, looks: int, folder: Path | None):
    """The shot's looks recorded for a 10 cm dolly at ``scale`` (read from ``folder`` where
    they are kept there), and the seconds it took."""
    names = [folder / f"scale{scale:g}" / f"look{k}.exr" for k in range(looks)] if folder else []
    if names and all(p.is_file() for p in names):
        t = time.perf_counter()
        holos = [read_hologram(p) for p in names]
        print(f"  the looks read from {names[0].parent} in {time.perf_counter() - t:.1f} s")
        return holos, None
    cams = [shot.camera(x, scale) for x in (-0.05, 0.0, 0.05)]
    zone = ViewingZone.fit(
        [c.position for c in cams],
        pupil=cams[0].aperture_diameter,
        margin=0.01,
        pixel=cams[0].pixel_angle(),
    )
    plate = Plate(matrix_world=np.eye(4), width=1.0, height=1.0, zone=zone)
    t = time.perf_counter()
    holos = record_looks(shot.scene(), looks=looks, plate=plate, seed=0)
    seconds = time.perf_counter() - t
    print(f"  {looks} looks recorded in {seconds:.1f} s (load {load()})")
    for path, h in zip(names, holos):
        path.parent.mkdir(parents=True, exist_ok=True)
        write_hologram(path, h)
    return holos, seconds


def wandering(scale: float, poses: int, zone: ViewingZone):
    """``poses`` cameras on a closed loop inside ``zone``: sideways over 80 % of the room its
    pupil has, up and down, nearer and farther by 70 %, the aim swinging ±2° and ±1.3°."""
    pupil = shot.camera(0.0, scale).aperture_diameter
    room = np.asarray(zone.half_extents) - [pupil / 2, pupil / 2, 0.0]
    centre = np.asarray(zone.centre)
    cams = []
    for i in range(poses):
        t = 2 * np.pi * i / poses
        eye = centre + room * [0.8 * np.sin(t), 0.7 * np.sin(2 * t + 1), 0.7 * np.cos(t)]
        aim = shot.TARGET + [0.06 * np.sin(t + 2), 0.04 * np.cos(t), 0.0]
        cam = shot.camera(0.0, scale, eye)
        cams.append(dataclasses.replace(cam, matrix_world=look_at(eye, aim, up=(0, 1, 0))))
    return cams


def timed(f, *a, **kw):
    t = time.perf_counter()
    out = f(*a, **kw)
    return out, time.perf_counter() - t


def one_scale(args, scale: float, rate: float) -> dict:
    """The figures of one scale (see the module docstring)."""
    holos, record_s = held_plate(scale, args.looks, args.plates)
    h = holos[0]
    cams = wandering(scale, args.poses, h.zone)
    size = f"{cams[0].resolution[0]}x{cams[0].resolution[1]}"
    viewer = PlateViewer(holos, supersample=args.supersample)
    outside = [i for i, c in enumerate(cams) if not viewer.contains(c)]
    if outside:
        raise SystemExit(f"poses {outside} lie outside the zone: {viewer.where(cams[outside[0]])}")
    middle = cams[0]  # the loop starts across the zone's middle
    render_camera(shot.scene(), middle, via="incoherent")  # warm: programs built
    passes = [timed(render_camera, shot.scene(), middle, via="incoherent")[1] for _ in range(2)]
    cam_s = statistics.median(passes)
    print(f"{size}: the camera pass {cam_s:.2f} s (load {load()})", flush=True)
    # the same path by render_view alone, each view planned afresh at its exact sizes (the
    # reference the viewer's plans are measured against)
    from holo_core.plate.view import render_view

    runs = {
        "render_view, unplanned (first visits)": [
            timed(render_view, holos, c, supersample=args.supersample)[1] for c in cams
        ]
    }
    key = "render_view, unplanned (first visits)"
    print(
        f"  {key}: median {statistics.median(runs[key]):.3f} s, {min(runs[key]):.3f}-"
        f"{max(runs[key]):.3f} (load {load()})",
        flush=True,
    )
    for visit in ("first", "again"):
        for coarse in (False, True):
            key = f"{'coarse' if coarse else 'full'} ({visit} visits)"
            runs[key] = [timed(viewer.view, c, coarse=coarse)[1] for c in cams]
            print(
                f"  {key}: median {statistics.median(runs[key]):.3f} s, "
                f"{min(runs[key]):.3f}-{max(runs[key]):.3f} (load {load()})",
                flush=True,
            )
    nbytes = shot.window_bytes(holos, middle)
    bound = nbytes / rate
    st, total = shot.synced_stages(lambda: viewer.view(middle))
    print(
        f"  one full view stage by stage: {total:.3f} s; the window's samples "
        f"{nbytes / 1e9:.2f} GB, {bound * 1e3:.0f} ms at {rate / 1e9:.1f} GB/s "
        f"({total / bound:.0f}x the bound)"
    )
    for name, s in sorted(st.items(), key=lambda kv: -kv[1]):
        print(f"    {name:28s} {s:.4f} s  {s / bound:6.1f}x the bound")
    viewer.close()
    full = statistics.median(runs["full (again visits)"])
    figures = {
        "image": size,
        "plate": f"{h.shape[1]} x {h.shape[0]} samples, {len(h.channels)} "
        f"channels, {len(holos)} looks",
        "recording [s]": record_s,
        "camera pass [s]": cam_s,
        "window's samples [GB]": nbytes / 1e9,
        "memory bandwidth [GB/s]": rate / 1e9,
        "the bound: the window read once [s]": bound,
        f"full views a second (goal >= {TARGET_FULL.get(scale, 0):g})": 1 / full,
        "full view / camera pass": full / cam_s,
        f"coarse latency, revisits [s] (goal <= {COARSE_LATENCY})": statistics.median(
            runs["coarse (again visits)"]
        ),
        "stages of one full view [s]": {
            name: {"s": s, "x the bound": s / bound} for name, s in st.items()
        },
    }
    figures.update(
        {
            f"{key} [s]": {
                "median": statistics.median(v),
                "min": min(v),
                "max": max(v),
                "views a second": 1 / statistics.median(v),
            }
            for key, v in runs.items()
        }
    )
    return figures


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "--scales",
        type=float,
        nargs="+",
        default=[0.5, 1.0],
        help="image sizes, of 1280x720 (0.5 1.0)",
    )
    p.add_argument("--poses", type=int, default=8, help="poses of the wandering camera (8)")
    p.add_argument("--looks", type=int, default=2, help="coded looks recorded (2)")
    p.add_argument("--supersample", type=int, default=2, help="the full views' (2)")
    p.add_argument(
        "--plates",
        type=Path,
        default=None,
        help="a folder keeping each scale's recorded looks between runs",
    )
    args = p.parse_args()
    print(f"CPU: {shot.cpu()}; load {load()} (1 min) at the start")
    rate = shot.bandwidth()
    print(f"memory bandwidth (a NumPy copy, read and write): {rate / 1e9:.1f} GB/s")
    figures = {}
    for scale in args.scales:
        for name, value in one_scale(args, scale, rate).items():
            figures[f"{round(1280 * scale)}x{round(720 * scale)}: {name}"] = value
    print(f"load at the end {load()}")
    results.write("live", figures)


if __name__ == "__main__":
    main()
