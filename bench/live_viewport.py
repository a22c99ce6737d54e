"""The viewport's path of a live plate view: from a camera change to its picture in shared
memory (worker process, view, shared memory, the copy out of it), and to a GPU texture where a
GPU context exists, against the same views made in this process, in one run.

The plate is ``bench/live.py``'s (``bench/shot.py``'s scene, its zone fitted to a 10 cm dolly,
``--looks`` coded looks) at ``--scale`` (0.5: 640×360), held by a
:class:`holo_core.worker.Views` worker; the camera wanders inside the zone (``live.py``'s
loop of ``--poses`` poses). Measured, each against the view's own time in this process
(:class:`holo_core.PlateViewer`, the same settings, the same poses):

- the latency of a coarse and of a full view: ``ask`` to ``latest`` returning its picture;
- the overhead of the path: that latency less the worker's own view time (its reply's);
- navigation: a camera moving every 1/60 s for ``--seconds`` (a viewport's mouse moves),
  coarse views asked on each move, newer ones superseding queued ones: the pictures that
  arrive a second, and the time from the last move to its full picture after a stop;
- the texture: the picture's rows flipped and scaled (``holo_addon.ui.live.texture_pixels``)
  and, in a Blender with a GPU context, made a ``gpu.types.GPUTexture`` (else said so).

    python bench/live_viewport.py [--scale 0.5] [--poses 6] [--looks 2] [--supersample 2]
                                  [--seconds 4] [--plates DIR]

``--plates DIR`` reads (or keeps) the recorded looks as ``bench/live.py`` does. Writes
``bench/results/live_viewport.json``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(Path(__file__).resolve().parent)]

import live  # noqa: E402  (the bench folder's own: the held plate and the wandering camera)
import shot  # noqa: E402

from holo_core import PlateViewer  # noqa: E402
from holo_core.io.hologram import write_hologram  # noqa: E402
from holo_core.worker import Views  # noqa: E402

MOVE = 1 / 60  # [s] between a moving viewport's camera changes
TARGET_RATE = 8.0  # the viewport refreshes a second while navigating, 640x360
TARGET_STILL = 0.3  # [s] the last move to the full picture
TARGET_COARSE = 0.1  # [s] the coarse picture after a move
STILL = 0.15  # [s] the add-on's stillness before it asks the full view (holo_addon.ui.live)


def load() -> float:
    return round(os.getloadavg()[0], 2)


def plate_files(args, folder: Path) -> tuple[list[Path], list]:
    """The looks' files: those ``--plates`` keeps, else recorded now into ``folder``."""
    holos, _ = live.held_plate(args.scale, args.looks, args.plates)
    names = (
        [args.plates / f"scale{args.scale:g}" / f"look{k}.exr" for k in range(args.looks)]
        if args.plates
        else [write_hologram(folder / f"look{k}.exr", h) for k, h in enumerate(holos)]
    )
    return names, holos


def latency(views: Views, camera, *, coarse: bool) -> tuple[float, float]:
    """(seconds from the ask to the picture out of shared memory, the worker's own)."""
    t = time.perf_counter()
    picture = views.wait(views.ask(camera, coarse=coarse), timeout=600)
    if picture.rgba is None:
        raise SystemExit(f"no picture: {picture.where or picture.error}")
    return time.perf_counter() - t, picture.seconds


def navigate(views: Views, cams, seconds: float) -> dict:
    """A camera moving every MOVE s along ``cams`` (looped, interpolated) for ``seconds``,
    a coarse view asked on each move; then still: its full view. The pictures a second, and
    the time from the last move to the full picture."""
    start = time.perf_counter()
    arrived, last, k = [], None, 0
    while time.perf_counter() - start < seconds:
        a, b = cams[k % len(cams)], cams[(k + 1) % len(cams)]
        f = (time.perf_counter() - start) % 1.0
        m = a.matrix_world * (1 - f) + b.matrix_world * f
        views.ask(replace(a, matrix_world=_pose(m)), coarse=True)
        k += 1
        t_end = time.perf_counter() + MOVE
        while time.perf_counter() < t_end:
            shown = views.latest()
            if shown is not None and shown is not last:
                arrived.append(time.perf_counter())
                last = shown
            time.sleep(0.001)
    moved = time.perf_counter()
    time.sleep(STILL)  # as the add-on waits before it asks the full view
    full = views.wait(views.ask(cams[0]), timeout=600)
    still = time.perf_counter() - moved
    span = arrived[-1] - arrived[0] if len(arrived) > 1 else float("nan")
    return {
        "moves": k,
        "pictures": len(arrived),
        "pictures a second": (len(arrived) - 1) / span if len(arrived) > 1 else 0.0,
        "last move to the full picture [s]": still,
        "full coarse": full.coarse,
    }


def _pose(m) -> np.ndarray:
    """A blend of two poses made a pose again (its rotation orthonormal)."""
    u, _, vt = np.linalg.svd(m[:3, :3])
    out = m.copy()
    out[:3, :3] = u @ vt
    return out


def texture(picture) -> dict:
    """The texture's costs: the values (in any process), the GPU texture (in a Blender with
    a GPU context; else said so)."""
    try:
        import bpy  # noqa: F401  (Blender as a module: its add-on's function, gpu)

        from holo_addon.ui.live import texture_pixels
    except ImportError as e:
        return {"texture": f"not measured: {e}"}
    t = time.perf_counter()
    for _ in range(10):
        pixels = texture_pixels(picture.rgba, 0.0)
    values = (time.perf_counter() - t) / 10
    out = {"texture values [s]": values}
    try:
        import gpu

        h, w, _ = picture.rgba.shape
        t = time.perf_counter()
        data = gpu.types.Buffer("FLOAT", pixels.size, pixels)
        gpu.types.GPUTexture((w, h), format="RGBA16F", data=data)
        out["GPU texture [s]"] = time.perf_counter() - t
    except (SystemError, ImportError) as e:
        out["GPU texture"] = f"not measured: no GPU context here ({e})"
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scale", type=float, default=0.5, help="of 1280x720 (0.5: 640x360)")
    p.add_argument("--poses", type=int, default=6, help="poses of the wandering camera (6)")
    p.add_argument("--looks", type=int, default=2, help="coded looks recorded (2)")
    p.add_argument("--supersample", type=int, default=2, help="the full views' (2)")
    p.add_argument("--seconds", type=float, default=4.0, help="of navigation (4)")
    p.add_argument(
        "--plates",
        type=Path,
        default=None,
        help="a folder keeping the recorded looks between runs (bench/live.py's)",
    )
    args = p.parse_args()
    print(f"CPU: {shot.cpu()}; load {load()} (1 min) at the start")
    with tempfile.TemporaryDirectory(prefix="holo-live-viewport-") as folder:
        names, holos = plate_files(args, Path(folder))
        cams = live.wandering(args.scale, args.poses, holos[0].zone)
        size = f"{cams[0].resolution[0]}x{cams[0].resolution[1]}"
        here = {"full": [], "coarse": []}
        with PlateViewer(holos, supersample=args.supersample) as viewer:
            for c in cams[:1] + cams:  # the first again: its plans made before it is timed
                for kind in here:
                    t = time.perf_counter()
                    viewer.view(c, coarse=kind == "coarse")
                    here[kind].append(time.perf_counter() - t)
        here = {k: v[1:] for k, v in here.items()}
        del holos, viewer
        print(
            f"{size}, in this process: full {statistics.median(here['full']):.3f} s, coarse "
            f"{statistics.median(here['coarse']):.3f} s a view (median; load {load()})"
        )
        with Views(names, supersample=args.supersample) as views:
            t = time.perf_counter()
            views.wait(views.ask(cams[0]), timeout=600)
            first = time.perf_counter() - t
            print(f"  the worker's first picture: {first:.2f} s (start, plate read, plans)")
            there = {"full": [], "coarse": []}
            worker_s = {"full": [], "coarse": []}
            for c in cams:
                for kind in there:
                    s, own = latency(views, c, coarse=kind == "coarse")
                    there[kind].append(s)
                    worker_s[kind].append(own)
            rows = {}
            for kind in there:
                med, own = statistics.median(there[kind]), statistics.median(worker_s[kind])
                path = statistics.median(a - b for a, b in zip(there[kind], worker_s[kind]))
                print(
                    f"  {kind}: each [s] "
                    + ", ".join(f"{a:.3f} ({b:.3f})" for a, b in zip(there[kind], worker_s[kind]))
                )
                rows[kind] = {
                    "camera change to picture [s]": med,
                    "worker's view [s]": own,
                    "path's overhead [s]": path,
                    "in this process [s]": statistics.median(here[kind]),
                    "ratio to in this process": med / statistics.median(here[kind]),
                }
                print(
                    f"  {kind}: {med:.3f} s from the change to the picture in shared memory; "
                    f"the worker's view {own:.3f} s, the path {1e3 * path:.1f} ms; "
                    f"{med / statistics.median(here[kind]):.2f}x this process's view "
                    f"(load {load()})"
                )
            moving = navigate(views, cams, args.seconds)
            print(
                f"  navigating: {moving['pictures a second']:.1f} pictures a second "
                f"(goal >= {TARGET_RATE:g}); last move to the full picture "
                f"{moving['last move to the full picture [s]']:.2f} s (goal <= "
                f"{TARGET_STILL:g} s) (load {load()})"
            )
            tex = texture(views.latest())
            for name, value in tex.items():
                print(f"  {name}: {value if isinstance(value, str) else f'{value:.4f}'}")
            restarts = views.starts
    figures = {
        "image": size,
        "poses": args.poses,
        "looks": args.looks,
        "supersample": args.supersample,
        "first picture [s]": first,
        "full": rows["full"],
        "coarse": rows["coarse"],
        f"coarse latency [s] (goal <= {TARGET_COARSE:g})": rows["coarse"][
            "camera change to picture [s]"
        ],
        f"navigating: pictures a second (goal >= {TARGET_RATE:g})": moving["pictures a second"],
        f"last move to the full picture [s] (goal <= {TARGET_STILL:g})": moving[
            "last move to the full picture [s]"
        ],
        "navigating: moves": moving["moves"],
        "navigating: pictures": moving["pictures"],
        "worker starts": restarts,
        **tex,
    }
    print(f"load at the end {load()}")
    results.write("live_viewport", figures)


if __name__ == "__main__":
    main()
