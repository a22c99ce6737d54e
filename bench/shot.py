"""A plate that serves a whole shot: the demo's scale recorded once, viewed over a camera move,
against each frame's own camera hologram, in one run.

The scene: a textured cube partly hiding a textured sphere, about a metre across 3.5 m from
the camera; a 1 m plate halfway; a 40 mm lens at f/2.8 and 1280×720; a dolly of ``--dolly``
(10 cm) across. The zone is fitted to the shot (every pupil of the move, ``--margin`` around
it); the plate is recorded once, its ``--looks`` coded looks in one pass. For three frames
(start, middle, end of the move) the camera hologram's pass (its looks' limit, what the
add-on renders by default) and the plate's view are timed and compared: PSNR inside the
objects, silhouette IoU. Then the frames as the add-on makes them, jobs handed to worker
processes that write their passes: a render's frames in the one worker it keeps (the plate
held after the first), a farm's single frames in a worker each (the plate's files read each
time), the camera pass's frames alike. Prints the CPU and its load, the plan, the recording's
time and the peak memory of all its processes, and for each way the frame count from which
the plate costs less than a pass per frame.

    python bench/shot.py [--scale 1.0] [--looks 2] [--dolly 0.1] [--supersample 2] [--repeat 3]
                          [--out DIR] [--in-process] [--stages]
    python bench/shot.py --set [--dolly 1.0 | --orbit 90] [--frames 5] [--stretch 0.1] ...

With ``--set`` (and always with ``--orbit DEG``: an orbit of DEG degrees at 3.5 m around the
objects' middle) the plate is a set of parts along the path (:mod:`holo_core.plate.path`),
the plates 1.75 m from the objects: it prints the part count, the recording's time, the set's
size on disk (its folder written and removed), and for ``--frames`` frames along the move the
part that serves it, its view against the camera pass, PSNR and IoU.
"""

import argparse
import math
import os
import platform
import sys
import tempfile
import threading
import time
from collections import defaultdict
from dataclasses import replace
from pathlib import Path

import numpy as np
import psutil
import results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from plate_scene import cube, sphere  # noqa: E402

from holo_core import estimate, worker  # noqa: E402
from holo_core.camera.render import render_camera  # noqa: E402
from holo_core.io.image import write_png  # noqa: E402
from holo_core.io.plate_paths import read_plate  # noqa: E402
from holo_core.job import CameraRoute, Job, Output, PlateRoute  # noqa: E402
from holo_core.plate.looks import record_looks  # noqa: E402
from holo_core.plate.parts import record_set  # noqa: E402
from holo_core.plate.path import part_for, parts_along, plan_parts  # noqa: E402
from holo_core.plate.plan import plan, plan_view  # noqa: E402
from holo_core.plate.recording import plate_plan  # noqa: E402
from holo_core.plate.view import render_view  # noqa: E402
from holo_core.scene.camera import Camera, look_at  # noqa: E402
from holo_core.scene.plate import SHOT_ZONE_MARGIN, Plate, ViewingZone  # noqa: E402

DISTANCE = 1.75  # [m] camera to plate, plate to the objects' middle
TARGET = np.array([0.0, 0.0, -DISTANCE])
PLATE = Plate(matrix_world=np.eye(4), width=1.0, height=1.0)


def scene():
    """A cube 0.5 m across in front, a sphere of radius 0.3 m behind and to the right."""
    return [
        cube(centre=np.array([-0.15, -0.08, -1.55]), size=0.5, angles=(0.35, 0.6)),
        sphere(centre=np.array([0.22, 0.1, -1.95]), radius=0.3, n=96),
    ]


def camera(x: float, scale: float, eye=None) -> Camera:
    eye = np.array([x, 0.0, DISTANCE]) if eye is None else np.asarray(eye, float)
    size = (round(1280 * scale), round(720 * scale))
    return Camera(
        matrix_world=look_at(eye, TARGET, up=(0, 1, 0)),
        lens=40,
        sensor_width=36,
        resolution=size,
        fstop=2.8,
        focus_distance=float(np.linalg.norm(np.array([-0.15, -0.08, -1.55]) - eye)),
    )


class PeakMemory:
    """The peak resident memory of this process and its children, sampled every 50 ms."""

    def __init__(self):
        self.peak, self._stop = 0, threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True)

    def _watch(self):
        me = psutil.Process()
        while not self._stop.is_set():
            total = me.memory_info().rss
            for child in me.children(recursive=True):
                try:
                    total += child.memory_info().rss
                except psutil.Error:
                    pass
            self.peak = max(self.peak, total)
            time.sleep(0.05)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()


def break_even(how: str, record_s: float, frame_s: float, cam_s: float) -> None:
    if cam_s > frame_s:
        n = math.ceil(record_s / (cam_s - frame_s))
        print(
            f"{how}: the plate (recorded once in {record_s:.0f} s, {frame_s:.2f} s a frame) "
            f"costs less than a pass per frame from {n} frames on; 24 frames: "
            f"{record_s + 24 * frame_s:.0f} s against {24 * cam_s:.0f} s"
        )
    else:
        print(f"{how}: a frame ({frame_s:.2f} s) costs more than the camera pass: no break-even")


def worker_frames(route, cams, folder: Path, *, resident: bool, meshes=()) -> list[float]:
    """Each camera's frame made as the add-on makes it: a job handed to a worker process
    (``resident``: the one a render keeps between its frames), its pass written; the seconds
    of each, from the job's hand-over to its result."""
    out = []
    for i, cam in enumerate(cams):
        job = Job(
            camera=cam, route=route, points=tuple(meshes), output=Output(folder=folder, frame=i + 1)
        )
        out.append(timed(worker.run, job, resident=resident)[1])
    return out


def timed(f, *args, **kw):
    t = time.perf_counter()
    out = f(*args, **kw)
    return out, time.perf_counter() - t


def psnr(view, reference, inside) -> float:
    err = view.rgb[inside] - reference.rgb[inside]
    return float(20 * np.log10(reference.rgb[inside].max() / np.sqrt(np.mean(err**2))))


def iou(a, b) -> float:
    return float((a & b).sum() / max((a | b).sum(), 1))


def cpu() -> str:
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip() + f", {os.cpu_count()} cores"
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scale", type=float, default=1.0, help="image size, of 1280x720 (1)")
    p.add_argument("--looks", type=int, default=2, help="coded looks recorded (2)")
    p.add_argument("--dolly", type=float, default=0.1, help="the camera's move [m] (0.1)")
    p.add_argument(
        "--margin",
        type=float,
        default=SHOT_ZONE_MARGIN,
        help=f"zone margin [m] ({SHOT_ZONE_MARGIN}: Fit Zone to Shot's)",
    )
    p.add_argument(
        "--supersample",
        type=int,
        default=2,
        help="fine pixels per pixel of the views (2, the plan's reference view)",
    )
    p.add_argument(
        "--repeat",
        type=int,
        default=3,
        help="each frame's view and pass timed this many times, the median kept (3)",
    )
    p.add_argument("--out", type=Path, default=None, help="a folder for the frames' PNGs")
    p.add_argument(
        "--in-process",
        action="store_true",
        help="only the frames in this process: not the add-on's worker frames",
    )
    p.add_argument(
        "--stages",
        action="store_true",
        help="also one view of the middle frame with the device synchronised "
        "around each kernel and transform: where its time goes",
    )
    p.add_argument(
        "--orbit",
        type=float,
        default=None,
        metavar="DEG",
        help="an orbit of DEG degrees at 3.5 m around the objects' middle, in "
        "place of the dolly (a plate set)",
    )
    p.add_argument(
        "--set", action="store_true", help="a set of parts along the path in place of one plate"
    )
    p.add_argument("--frames", type=int, default=3, help="frames along the move (3)")
    p.add_argument(
        "--stretch", type=float, default=0.1, help="[m] of path a part of the set serves (0.1)"
    )
    args = p.parse_args()
    if args.set or args.orbit is not None:
        return set_route(args)
    xs = np.linspace(-args.dolly / 2, args.dolly / 2, 3)
    cams = [camera(x, args.scale) for x in xs]
    meshes = scene()
    print(f"CPU: {cpu()}; load {os.getloadavg()[0]:.1f} (1 min) at the start")
    zone = ViewingZone.fit(
        [c.position for c in cams],
        pupil=cams[0].aperture_diameter,
        margin=args.margin,
        pixel=cams[0].pixel_angle(),
    )
    plate = Plate(
        matrix_world=PLATE.matrix_world, width=PLATE.width, height=PLATE.height, zone=zone
    )
    every = np.concatenate([m.vertices for m in meshes])
    planned = plan(
        (plate.width, plate.height),
        [every.min(0), every.max(0)],
        zone=zone,
        pixel_angle=cams[0].pixel_angle(),
        looks=args.looks,
    )
    print(f"plan: {planned.describe()}")
    print(
        f"view plan (middle frame): "
        f"{plan_view(planned, position=cams[1].position, pixel_angle=cams[1].pixel_angle(), pupil=cams[1].aperture_diameter, resolution=cams[1].resolution).describe()}"
    )
    with PeakMemory() as memory:  # every look in one pass, as the pipeline records them
        plates, record_s = timed(record_looks, meshes, looks=args.looks, plate=plate, seed=0)
    print(
        f"  {args.looks} look(s) in one pass: {record_s:.1f} s (load {os.getloadavg()[0]:.1f})",
        flush=True,
    )
    # both renderers warm at the frame's size (programs built, FFT plans read or measured)
    render_camera(meshes, cams[1], via="incoherent")
    render_view(plates, cams[1], supersample=args.supersample)
    h = plates[0]
    print(
        f"recording: {h.shape[1]}x{h.shape[0]} samples x {len(h.channels)} channels x "
        f"{args.looks} looks in {record_s:.1f} s; peak memory of all processes "
        f"{memory.peak / 2**30:.2f} GiB"
    )
    rows = []
    for i, cam in enumerate(cams):
        view, ref, views, passes = against_pass(plates, cam, meshes, args)
        cam_s, view_s = float(np.median(passes)), float(np.median(views))
        inside = (ref.alpha >= 1) & (view.alpha >= 1)
        rows.append(
            (xs[i], psnr(view, ref, inside), iou(view.alpha > 0.5, ref.alpha > 0.5), view_s, cam_s)
        )
        print(
            f"frame at x = {xs[i] * 100:+.1f} cm: PSNR {rows[-1][1]:.2f} dB, IoU "
            f"{rows[-1][2]:.4f}; view {view_s:.2f} s ({min(views):.2f}-{max(views):.2f}), "
            f"camera pass {cam_s:.2f} s ({min(passes):.2f}-{max(passes):.2f}) (load "
            f"{os.getloadavg()[0]:.1f})",
            flush=True,
        )
        if args.out is not None:
            args.out.mkdir(parents=True, exist_ok=True)
            for name, v in (("plate", view), ("camera", ref)):
                write_png(
                    args.out / f"frame{i}_{name}.png",
                    np.clip(v.rgb * v.alpha[..., None], 0, 1) ** (1 / 2.2),
                )
    view_s = float(np.mean([r[3] for r in rows]))
    cam_s = float(np.mean([r[4] for r in rows]))
    print(
        f"\na view {view_s:.2f} s = {view_s / cam_s:.2f} x the camera pass ({cam_s:.2f} s), "
        f"the medians of {args.repeat} runs a frame averaged over the frames"
    )
    break_even("in one process (the plate in memory)", record_s, view_s, cam_s)
    if args.stages:
        view_stages(plates, cams[1], args.supersample)
    if not args.in_process:
        addon_frames(args, cams, meshes, plate)
    print(
        f"PSNR {min(r[1] for r in rows):.2f}-{max(r[1] for r in rows):.2f} dB, IoU "
        f"{min(r[2] for r in rows):.4f}-{max(r[2] for r in rows):.4f}; load at the end "
        f"{os.getloadavg()[0]:.1f}"
    )
    figures = {
        "plate": f"{h.shape[1]} x {h.shape[0]} samples, {len(h.channels)} channels, "
        f"{args.looks} looks",
        "recording [s]": record_s,
        "recording's peak memory [GiB]": memory.peak / 2**30,
        "a view / the camera pass (goal <= 0.5)": view_s / cam_s,
    }
    figures.update(
        {
            f"frame at x = {x * 100:+.1f} cm": {
                "PSNR [dB]": p,
                "IoU": q,
                "view [s]": v,
                "camera pass [s]": c,
            }
            for x, p, q, v, c in rows
        }
    )
    results.write("shot", figures)


def set_route(args) -> None:
    """The shot's move served by a set of parts along it: placed, recorded, written, and each
    frame viewed from its part against its camera pass."""
    # the path the parts are placed along: the move 5 cm (or 5°) a step, the frames among them
    span = args.orbit / 5 if args.orbit is not None else args.dolly / 0.05
    at = np.unique(
        np.r_[np.linspace(-0.5, 0.5, max(2, round(span) + 1)), np.linspace(-0.5, 0.5, args.frames)]
    )
    if args.orbit is not None:

        def eye(t):
            a = math.radians(args.orbit * t)
            return TARGET + 2 * DISTANCE * np.array([math.sin(a), 0.0, math.cos(a)])

        labels = [f"at {args.orbit * t:+.1f}°" for t in np.linspace(-0.5, 0.5, args.frames)]
        move = f"a {args.orbit:g}° orbit at {2 * DISTANCE:g} m"
    else:

        def eye(t):
            return np.array([args.dolly * t, 0.0, DISTANCE])

        labels = [
            f"at x = {args.dolly * t * 100:+.1f} cm" for t in np.linspace(-0.5, 0.5, args.frames)
        ]
        move = f"a {args.dolly * 100:g} cm dolly"
    cams = [camera(0.0, args.scale, eye(t)) for t in np.linspace(-0.5, 0.5, args.frames)]
    path = [camera(0.0, args.scale, eye(t)) for t in at]
    meshes = scene()
    every = np.concatenate([m.vertices for m in meshes])
    print(f"CPU: {cpu()}; load {os.getloadavg()[0]:.1f} (1 min) at the start")
    parts = parts_along(
        path,
        [every.min(0), every.max(0)],
        distance=DISTANCE,
        stretch=args.stretch,
        margin=args.margin,
    )
    plans = [plate_plan(meshes, plate=part.plate).plan for part in parts]
    samples = sum(q.samples for q in plans)
    # Plan Plate's estimate of the recording (this machine's calibration where measured) as
    # on an idle machine: the bench runs alone (a load average still holds the run before),
    # in this process, its kernels built
    expected = estimate.plate_set(
        plan_parts(parts, every, looks=args.looks, meshes=meshes), warm=True, load_average=0
    )
    print(
        f"{move}, {cams[0].resolution[0]}x{cams[0].resolution[1]}: {len(parts)} parts of "
        f"{args.stretch * 100:g} cm of path, {samples / 1e6:.1f} Mpx in all (a part "
        f"{plans[0].shape[1]}x{plans[0].shape[0]}); the recording's estimate "
        f"{expected.words()}"
    )
    with tempfile.TemporaryDirectory() as folder:  # each part written as it is recorded
        with PeakMemory() as memory:
            plates, record_s = timed(
                record_set, meshes, parts, looks=args.looks, seed=0, folder=Path(folder) / "set"
            )
        disk = sum(f.stat().st_size for f in (Path(folder) / "set").iterdir())
        print(
            f"recording: {len(parts)} parts x {args.looks} looks in {record_s:.1f} s "
            f"({record_s / len(parts):.2f} s a part), each written as recorded; peak memory "
            f"of all processes {memory.peak / 2**30:.2f} GiB; on disk {disk / 2**30:.3f} GiB "
            f"(load {os.getloadavg()[0]:.1f}); estimated {expected.seconds:.1f} s "
            f"({expected.seconds / record_s:.2f} x)",
            flush=True,
        )
        rows = set_frames(args, plates, cams, labels, meshes)
        summary(rows)
    # one file a move, so that the dollies and the orbit sit side by side
    name = (
        f"shot_set_orbit{args.orbit:g}"
        if args.orbit is not None
        else f"shot_set_dolly{args.dolly * 100:g}cm"
    )
    figures = {
        "move": f"{move}, {cams[0].resolution[0]}x{cams[0].resolution[1]}, "
        f"{args.looks} looks, supersample {args.supersample}",
        "parts": len(parts),
        "samples [Mpx]": samples / 1e6,
        "recording [s]": record_s,
        "recording's estimate [s] (goal within 25 %)": expected.seconds,
        "estimate / recording": expected.seconds / record_s,
        "estimate by this machine's calibration": expected.calibrated,
        "disk [GiB]": disk / 2**30,
        "recording's peak memory [GiB]": memory.peak / 2**30,
        "a view / the camera pass (goal <= 0.5)": float(
            np.mean([r[2] for r in rows]) / np.mean([r[3] for r in rows])
        ),
    }
    figures.update(
        {
            f"frame {label}": {
                "PSNR [dB] (goal >= 30)": q,
                "IoU (goal >= 0.98)": u,
                "view [s]": v,
                "camera pass [s]": c,
            }
            for label, (q, u, v, c) in zip(labels, rows)
        }
    )
    results.write(name, figures)


def set_frames(args, plates, cams, labels, meshes) -> list:
    """Each frame from its part against its camera pass: (PSNR, IoU, view s, pass s)."""
    render_camera(meshes, cams[0], via="incoherent")  # both renderers warm
    render_view(plates, cams[0], supersample=args.supersample)
    rows = []
    for i, cam in enumerate(cams):
        k, _ = part_for(plates, cam)
        _, read_s = timed(plates.part_looks, k)  # its files read when the part changes
        view, ref, views, passes = against_pass(plates, cam, meshes, args)
        cam_s, view_s = float(np.median(passes)), float(np.median(views))
        inside = (ref.alpha >= 1) & (view.alpha >= 1)
        rows.append(
            (psnr(view, ref, inside), iou(view.alpha > 0.5, ref.alpha > 0.5), view_s, cam_s)
        )
        print(
            f"frame {labels[i]} (part {k}, read in {read_s:.2f} s): PSNR {rows[-1][0]:.2f} "
            f"dB, IoU {rows[-1][1]:.4f}; view {view_s:.2f} s, camera pass {cam_s:.2f} s "
            f"(view / pass {view_s / cam_s:.2f}) (load {os.getloadavg()[0]:.1f})",
            flush=True,
        )
        if args.out is not None:
            args.out.mkdir(parents=True, exist_ok=True)
            for name, v in (("set", view), ("camera", ref)):
                write_png(
                    args.out / f"frame{i}_{name}.png",
                    np.clip(v.rgb * v.alpha[..., None], 0, 1) ** (1 / 2.2),
                )
    return rows


def against_pass(plates, cam, meshes, args):
    """(the view, the camera pass, the view's seconds, the pass's seconds), each timed
    ``--repeat`` times, alternated, so that a slow spell of the host hits both."""
    passes, views = [], []
    for _ in range(args.repeat):
        ref, t = timed(render_camera, meshes, cam, via="incoherent")
        passes.append(t)
        view, t = timed(render_view, plates, cam, supersample=args.supersample)
        views.append(t)
    return view, ref, views, passes


def summary(rows) -> None:
    r = np.array(rows)
    view_s, cam_s = r[:, 2].mean(), r[:, 3].mean()
    print(
        f"\nPSNR {r[:, 0].min():.2f}-{r[:, 0].max():.2f} dB, IoU {r[:, 1].min():.4f}-"
        f"{r[:, 1].max():.4f}; a view {view_s:.2f} s = {view_s / cam_s:.2f} x the camera "
        f"pass ({cam_s:.2f} s); load at the end {os.getloadavg()[0]:.1f}"
    )


def bandwidth() -> float:
    """Bytes a second this machine reads and writes in a NumPy copy of 256 MiB (best of 5)."""
    src = np.ones(2**25, np.complex64)
    dst = np.empty_like(src)
    best = min(timed(np.copyto, dst, src)[1] for _ in range(5))
    return 2 * src.nbytes / best


def window_bytes(holos, cam) -> int:
    """The bytes of the samples a view of ``cam`` must read: its window (the carrier
    route's, :func:`holo_core.plate.window.carrier_window`) of every channel of every look."""
    from holo_core.plate.window import camera_in_plate, carrier_window, image_corners

    h = holos[0]
    rotation, position = camera_in_plate(h, cam)
    r0, r1, c0, c1 = carrier_window(
        h, position, rotation, cam.aperture_diameter, image_corners(cam, rotation)
    )
    return (r1 - r0) * (c1 - c0) * len(h.channels) * len(holos) * 8


def synced_stages(view) -> tuple[dict, float]:
    """One call of ``view()`` with the device synchronised around each kernel launch and each
    transform: ({stage: seconds}, total seconds), the rest as 'host and launches'."""
    from functools import partial

    from holo_core.opencl import get_runtime
    from holo_core.opencl.kernel import Kernel

    rt = get_runtime()
    seconds = defaultdict(float)

    def synced(name, f, /, *a, **kw):
        rt.queue.finish()
        t = time.perf_counter()
        out = f(*a, **kw)
        rt.queue.finish()
        seconds[name] += time.perf_counter() - t
        return out

    launch, fft = Kernel.launch, rt.fft

    def launched(self, *a, **kw):
        return synced(self.name, launch, self, *a, **kw)

    Kernel.launch = launched  # every launch, until put back
    fft.forward, fft.backward = (
        partial(synced, f"FFT {n}", getattr(fft, n)) for n in ("forward", "backward")
    )
    try:
        _, total = timed(view)
    finally:
        Kernel.launch = launch
        del fft.forward, fft.backward
    seconds["host and launches"] = total - sum(seconds.values())
    return dict(seconds), total


def view_stages(plates, cam, supersample) -> None:
    """One view with the device synchronised around each kernel launch and each transform:
    the seconds of each, and what is left for the host (and the launches' own cost), each
    against the view's bound: the bytes of its window's samples over this machine's memory
    bandwidth (measured here)."""
    from holo_core.opencl import get_runtime

    rt = get_runtime()
    seconds, total = synced_stages(lambda: render_view(plates, cam, supersample=supersample))
    nbytes, rate = window_bytes(list(plates), cam), bandwidth()
    bound = nbytes / rate
    print(
        f"a view's stages, each synchronised ({rt.device.name.strip()}, FFT {rt.fft.name}): "
        f"{total:.3f} s in all; its window's samples {nbytes / 1e9:.2f} GB, read once at "
        f"{rate / 1e9:.1f} GB/s (a NumPy copy): {bound * 1e3:.0f} ms, the bound "
        f"({total / bound:.0f}x it)"
    )
    for name, s in sorted(seconds.items(), key=lambda kv: -kv[1]):
        print(f"  {name:28s} {s:.4f} s  {s / bound:6.1f}x the bound")
    import cProfile
    import pstats

    profile = cProfile.Profile()
    profile.runcall(render_view, plates, cam, supersample=supersample)
    print("the same view's Python functions by their own time (the device not synchronised):")
    stats = pstats.Stats(profile, stream=sys.stdout)
    stats.sort_stats("tottime").print_stats(15)
    print("... and by their time with what they call:")
    stats.sort_stats("cumulative").print_stats(25)


def addon_frames(args, cams, meshes, plate) -> None:
    """The frames as the add-on makes them, and their break-even counts."""
    # the add-on's frames: jobs handed to a worker process. A render's frames share one: its
    # first frame records the plate and writes its files, the next view it held in memory; a
    # farm rendering one frame a Blender starts one a frame, which reads the plate's files
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        paths = tuple(folder / f"look{k}.exr" for k in range(args.looks))
        route = PlateRoute(plate=plate, holograms=paths, supersample=args.supersample)
        viewed = replace(route, record=False)
        try:
            first = worker_frames(route, cams[:1], folder / "kept", resident=True, meshes=meshes)[0]
            held = worker_frames(viewed, cams[1:] + cams, folder / "kept", resident=True)
            cam_held = worker_frames(
                CameraRoute(supersample=args.supersample),
                cams * 2,
                folder / "cam",
                resident=True,
                meshes=meshes,
            )
        finally:
            worker.release()
        size = sum(p.stat().st_size for p in paths)
        read_s = float(
            np.median([timed(lambda: [read_plate(p) for p in paths])[1] for _ in range(2)])
        )
        fresh = worker_frames(viewed, cams, folder / "fresh", resident=False)
        cam_fresh = worker_frames(
            CameraRoute(supersample=args.supersample),
            cams,
            folder / "cam-fresh",
            resident=False,
            meshes=meshes,
        )
    frame_s, cam_frame = float(np.median(held)), float(np.median(cam_held[1:]))
    print(
        f"the add-on's render, its frames in the worker it keeps: the first {first:.1f} s "
        f"(the process started, the plate recorded and its files written, its view), then "
        f"{frame_s:.2f} s a frame ({min(held):.2f}-{max(held):.2f}); the camera pass "
        f"{cam_frame:.2f} s a frame ({min(cam_held[1:]):.2f}-{max(cam_held[1:]):.2f}); "
        f"passes written (load {os.getloadavg()[0]:.1f})"
    )
    break_even(
        "the add-on's render (one worker for its frames)", first - frame_s, frame_s, cam_frame
    )
    fresh_s, cam_fresh_s = float(np.median(fresh)), float(np.median(cam_fresh))
    print(
        f"the plate's files: {size / 2**30:.2f} GiB, read in {read_s:.1f} s from the page "
        f"cache; a worker started for each frame (a farm's single frames, the files read "
        f"each time): {fresh_s:.2f} s a frame ({min(fresh):.2f}-{max(fresh):.2f}); the "
        f"camera pass so: {cam_fresh_s:.2f} s ({min(cam_fresh):.2f}-{max(cam_fresh):.2f})"
    )
    break_even("a worker a frame", first - fresh_s, fresh_s, cam_fresh_s)


if __name__ == "__main__":
    main()
