"""The estimates (:mod:`holo_core.estimate`) against what happens: for a tiny plate, the shot's
plate (``bench/shot.py``'s scene at ``--shot-scale``) and the demo's camera pass (``make
demo``'s job at ``--demo-resolution``, its radiance rendered by Cycles), each job run as the
add-on runs it, in a new worker process, first with a fresh cache (a temporary
``XDG_CACHE_HOME`` holding only this machine's calibration: programs compiled, FFT plans
measured) and then with that cache warm. Prints each estimate, its parts, the measured time
and their ratio, and whether it is within the target (25 %, or 2 s for short jobs); the same
by the default rates. Calibrates first (``python -m holo_core calibrate``, into a temporary
cache) unless ``--calibration FILE`` gives one.

    python bench/estimates.py [--shot-scale 0.5] [--demo-resolution 640 360] [--no-demo]
                              [--calibration FILE]
"""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]
BENCH = Path(__file__).resolve().parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(BENCH)]

from holo_core import calibration, estimate, worker  # noqa: E402
from holo_core.job import Job, Output, PlateRoute  # noqa: E402
from holo_core.plate.plan import plan_view  # noqa: E402
from holo_core.plate.recording import plate_plan  # noqa: E402
from holo_core.scene.plate import Plate, ViewingZone  # noqa: E402

TARGET, SHORT = 0.25, 2.0  # the estimate within 25 % of the measured time, or 2 s


def tiny_plate(folder: Path) -> Job:
    """tests/plate_scene.py's cube and sphere on its 10 cm plate, viewed at 160 x 90."""
    import plate_scene

    cam = plate_scene.camera(scale=0.25)
    zone = ViewingZone.fit(
        [cam.position], pupil=cam.aperture_diameter, margin=0.002, pixel=cam.pixel_angle()
    )
    plate = Plate(matrix_world=np.eye(4), width=0.1, height=0.1, zone=zone)
    route = PlateRoute(plate=plate, holograms=(folder / "tiny0.exr", folder / "tiny1.exr"))
    return Job(
        camera=cam,
        route=route,
        points=tuple(plate_scene.meshes()),
        output=Output(folder=folder / "tiny"),
    )


def shot_plate(folder: Path, scale: float) -> Job:
    """bench/shot.py's plate (its zone fitted to the 10 cm dolly), its middle frame viewed."""
    import shot

    cams = [shot.camera(x, scale) for x in (-0.05, 0.0, 0.05)]
    zone = ViewingZone.fit(
        [c.position for c in cams],
        pupil=cams[0].aperture_diameter,
        margin=0.01,
        pixel=cams[0].pixel_angle(),
    )
    plate = Plate(
        matrix_world=shot.PLATE.matrix_world,
        width=shot.PLATE.width,
        height=shot.PLATE.height,
        zone=zone,
    )
    route = PlateRoute(plate=plate, holograms=(folder / "shot0.exr", folder / "shot1.exr"))
    return Job(
        camera=cams[1],
        route=route,
        points=tuple(shot.scene()),
        output=Output(folder=folder / "shot"),
    )


DEMO_JOB = """
import pickle, sys
from pathlib import Path
import bpy
from holo_addon import register
from holo_addon.demo import build_scene
from holo_addon.render import pipeline
bpy.ops.wm.read_factory_settings(use_empty=True)
register()
scene = build_scene(bpy, resolution=(int(sys.argv[1]), int(sys.argv[2])))
scene.holo.output_dir = sys.argv[3]
scene.render.filepath = sys.argv[3]
job = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get()).lit()
Path(sys.argv[4]).write_bytes(pickle.dumps(job.to_dict()))
"""


def demo_pass(folder: Path, resolution) -> Job:
    """make demo's job (its camera pass, Lighting: Scene), read by the add-on through bpy in
    its own process, with the scene written for Cycles' radiance."""
    import pickle

    out = folder / "demo.pickle"
    subprocess.run(
        [
            sys.executable,
            "-c",
            DEMO_JOB,
            *map(str, resolution),
            str(folder / "demo") + os.sep,
            str(out),
        ],
        check=True,
        cwd=ROOT,
        capture_output=True,
        env=worker.environment(),
    )
    return Job.from_dict(pickle.loads(out.read_bytes()))


def planned(job: Job):
    """(the plan, the view's plan) of a plate job; (None, None) for a camera pass."""
    if not isinstance(job.route, PlateRoute):
        return None, None
    p = plate_plan(
        list(job.points) + list(job.triangles),
        plate=job.route.plate,
        camera=job.camera,
        looks=len(job.route.holograms),
    ).plan
    eye = job.route.plate.to_plate(np.asarray(job.camera.position)[None])[0]
    return p, plan_view(
        p,
        position=eye,
        pixel_angle=job.camera.pixel_angle(),
        pupil=job.camera.aperture_diameter,
        resolution=job.camera.resolution,
    )


def within(est: float, measured: float) -> bool:
    return abs(est - measured) <= max(TARGET * measured, SHORT)


def run_case(name, make, calibration_file: Path, tmp: Path) -> dict:
    folder = tmp / name
    folder.mkdir()
    cache = folder / "cache"
    (cache / "holo").mkdir(parents=True)
    shutil.copy(calibration_file, cache / "holo" / estimate.FILE)
    rows = {}
    for state in ("fresh cache", "warm cache"):
        # a job each: its files anew (the plate recorded each time), and a radiance's
        # scratch folder is used up by its run
        (folder / state.split()[0]).mkdir()
        job = make(folder / state.split()[0])
        p, v = planned(job)
        said = estimate.job(job, plan=p, view=v, cache_dir=cache)
        default = estimate.job(
            job, plan=p, view=v, cache_dir=cache, calibration=(estimate.DEFAULT, False)
        )
        load = os.getloadavg()[0]
        t = time.perf_counter()
        report = worker.run(job, cache_dir=str(cache)).report
        measured = time.perf_counter() - t
        parts = ", ".join(f"{k} {s:.1f}" for k, s in said.work)
        lit = report.radiance_seconds or 0.0
        print(
            f"  measured: in the worker {report.seconds:.1f} s (the radiance {lit:.1f} s), "
            f"its start and the hand-over {measured - report.seconds:.1f} s"
        )
        print(
            f"{name}, {state}: estimated {said.seconds:.1f} s ({said.words()}; work: "
            f"{parts}), measured {measured:.1f} s: ratio {said.seconds / measured:.2f}, "
            f"{'within' if within(said.seconds, measured) else 'NOT within'} the target; "
            f"by the default rates {default.seconds:.1f} s (ratio "
            f"{default.seconds / measured:.2f}); load {load:.1f}",
            flush=True,
        )
        rows[f"{name}, {state}"] = {
            "estimate [s]": round(said.seconds, 2),
            "of which set-up [s]": round(said.process + said.first, 2),
            "measured [s]": round(measured, 2),
            "estimate / measured": round(said.seconds / measured, 3),
            "within 25 % or 2 s": within(said.seconds, measured),
            "default rates' estimate [s]": round(default.seconds, 2),
            "in the worker [s]": round(report.seconds, 2),
            "radiance [s]": round(lit, 2),
            "load (1 min)": round(load, 1),
        }
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "--shot-scale", type=float, default=0.5, help="the shot's image size, of 1280x720 (0.5)"
    )
    p.add_argument(
        "--demo-resolution",
        type=int,
        nargs=2,
        default=(640, 360),
        metavar=("W", "H"),
        help="the demo's resolution (640 360)",
    )
    p.add_argument("--no-demo", action="store_true", help="skip the demo (it needs bpy)")
    p.add_argument(
        "--calibration", type=Path, default=None, help="a calibration file (default: measured now)"
    )
    args = p.parse_args()
    print(f"CPU: {results.cpu_name()}; load {os.getloadavg()[0]:.1f} (1 min) at the start")
    with tempfile.TemporaryDirectory(prefix="holo-estimates-") as tmp:
        tmp = Path(tmp)
        if args.calibration is None:
            t = time.perf_counter()
            args.calibration = calibration.calibrate(cache_dir=tmp / "calibrated", say=print)
            print(f"calibrated in {time.perf_counter() - t:.0f} s")
        cases = [
            ("tiny plate", tiny_plate),
            (f"the shot's plate at {args.shot_scale:g}", lambda f: shot_plate(f, args.shot_scale)),
        ]
        if not args.no_demo:
            w, h = args.demo_resolution
            cases.append(
                (f"the demo's camera pass at {w}x{h}", lambda f: demo_pass(f, args.demo_resolution))
            )
        figures = {}
        for name, make in cases:
            figures.update(run_case(name, make, args.calibration, tmp))
    met = sum(r["within 25 % or 2 s"] for r in figures.values())
    print(
        f"{met} of {len(figures)} estimates within the target; load at the end "
        f"{os.getloadavg()[0]:.1f}"
    )
    results.write("estimates", figures)


if __name__ == "__main__":
    main()
