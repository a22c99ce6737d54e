"""This machine's rates for the estimates (:mod:`holo_core.estimate`), measured once:
``python -m holo_core calibrate``.

Two reference jobs, a small plate of a sphere (recorded, written and viewed) and a camera
pass of it, each run as the add-on runs them, in worker processes:

1. in a new worker with a fresh cache (a temporary ``XDG_CACHE_HOME``, one a job):
   programs compiled, FFT plans measured;
2. in a new worker with that cache now warm;
3. twice in one worker (the second run: the work alone).

1 − 2 is the first time's set-up (the camera pass's less its FFT plans, which the estimates
count from the lengths a job transforms), 2 − 3 a worker's start. Then the stages, each
timed on its own in a process with that warm cache (:func:`stage_rates`), on the small
reference and on one with twice its pixels a side and a five times wider zone: the emitters
found, the zone sum, the files, the view, a camera pass with Speckle: Exact and with 2 and
10 looks, each fitted as a fixed cost and a rate (:func:`_fit`); 3 less the camera pass's
stages is a job's own cost; and FFTW's measuring of a few lengths' plans
(:func:`plan_rate`). Everything is taken as on an idle machine: each time divided by the
load's slowdown as it began (:func:`holo_core.estimate.slowdown`), which the estimates
multiply back by the load of their time. Cycles' radiance is not measured here (no
Blender): its default stays. About a minute on a 2-core CPU; the user's own caches are
left as they were.
"""

from __future__ import annotations

import json
import logging
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from . import estimate, worker
from .job import CameraRoute, Job, Output, PlateRoute
from .scene.camera import Camera, look_at
from .scene.mesh import Mesh
from .scene.plate import Plate, ViewingZone

log = logging.getLogger(__name__)
RESOLUTION = (320, 180)  # the reference views: small, and large enough that work shows


def reference_scene(scale: float = 1.0, margin: float = 0.002) -> tuple[list[Mesh], Camera, Plate]:
    """A vertex-coloured sphere of 3 cm radius 0.35 m behind a 10 cm plate, a 50 mm f/2.8
    camera of RESOLUTION × ``scale`` pixels 0.3 m in front of it, the plate's zone fitted
    ``margin`` [m] around its pupil."""
    n = 32
    th, ph = np.meshgrid(
        np.linspace(0, np.pi, n + 1), np.linspace(0, 2 * np.pi, 2 * n + 1), indexing="ij"
    )
    v = np.stack([np.sin(th) * np.cos(ph), np.cos(th), np.sin(th) * np.sin(ph)], -1)
    idx = np.arange(v.shape[0] * v.shape[1]).reshape(v.shape[:2])
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, :-1], idx[1:, 1:]
    tri = np.concatenate(
        [np.stack([a, c, d], -1).reshape(-1, 3), np.stack([a, d, b], -1).reshape(-1, 3)]
    )
    v = v.reshape(-1, 3)
    sphere = Mesh(
        vertices=v * 0.03 + [0.0, 0.0, -0.35],
        triangles=tri,
        colours=np.clip(0.55 + 0.45 * v, 0.05, 1.0),
    )
    cam = Camera(
        matrix_world=look_at(np.array([0.0, 0.0, 0.3]), np.array([0.0, 0.0, -0.35]), up=(0, 1, 0)),
        lens=50,
        sensor_width=36,
        fstop=2.8,
        focus_distance=0.62,
        resolution=(round(RESOLUTION[0] * scale), round(RESOLUTION[1] * scale)),
    )
    zone = ViewingZone.fit(
        [cam.position], pupil=cam.aperture_diameter, margin=margin, pixel=cam.pixel_angle()
    )
    plate = Plate(matrix_world=np.eye(4), width=0.1, height=0.1, zone=zone)
    return [sphere], cam, plate


def reference_jobs(folder: Path) -> dict[str, Job]:
    """The two reference jobs, writing under ``folder``."""
    meshes, cam, plate = reference_scene()
    route = PlateRoute(plate=plate, holograms=(folder / "look0.exr", folder / "look1.exr"))
    return {
        "plate": Job(
            camera=cam, route=route, triangles=tuple(meshes), output=Output(folder=folder / "plate")
        ),
        "camera": Job(
            camera=cam,
            route=CameraRoute(),
            triangles=tuple(meshes),
            output=Output(folder=folder / "camera"),
        ),
    }


def _timed(job: Job, **options) -> float:
    """The job's seconds in a worker, as on an idle machine (the load's slowdown as it began
    taken out)."""
    k, t = estimate.slowdown(), time.perf_counter()
    worker.run(job, **options)
    return (time.perf_counter() - t) / k


def _stages(meshes, cam, plate, folder: Path) -> tuple[dict, dict]:
    """(work, seconds) of each stage of a plate of ``meshes`` recorded, written and viewed
    from ``cam``, and camera passes of 2 and 10 looks: the second of two runs (the first
    builds the programs and plans the FFTs; its camera pass of 2 looks is enough for that)."""
    from .camera.render import render_camera
    from .io.hologram import write_hologram
    from .plate.plan import plan_view
    from .plate.recording import plate_plan, prepare_plate
    from .plate.view import render_view

    planned = plate_plan(meshes, plate=plate, camera=cam, looks=2)
    p = planned.plan
    eye = plate.to_plate(np.asarray(cam.position)[None])[0]
    v = plan_view(
        p,
        position=eye,
        pixel_angle=cam.pixel_angle(),
        pupil=cam.aperture_diameter,
        resolution=cam.resolution,
    )

    def timed(f, *args, **kw):  # as on an idle machine: the load's slowdown taken out
        k, t = estimate.slowdown(), time.perf_counter()
        out = f(*args, **kw)
        d.append((time.perf_counter() - t) / k)
        return out

    def write(holos):
        for k, h in enumerate(holos):
            write_hologram(folder / f"look{k}.exr", h)

    for run in range(2):
        d = []
        holos = timed(prepare_plate, planned)
        holos = timed(holos.record)
        timed(write, holos)
        timed(render_view, holos, cam)
        timed(render_camera, meshes, cam, via="incoherent")  # Speckle: Exact
        for samples in (2, 10) if run else (2,):  # the first builds and plans: one is enough
            timed(render_camera, meshes, cam, samples=samples)
    fine = cam.resolution[0] * cam.resolution[1] * 2**2  # the default supersampling
    names = ("emitters", "zone sum", "files", "view", "exact", "camera 2", "camera 10")
    work = dict(zip(names, (p.emitters, p.pairs(), p.disk_bytes(), v.seconds, fine, fine, fine)))
    seconds = dict(zip(names, d))
    # the emitters' own: the triangles' share is the estimate's constant (TRIANGLE_SECONDS)
    seconds["emitters"] = max(seconds["emitters"] - p.triangles * estimate.TRIANGLE_SECONDS, 0.0)
    return work, seconds


def _fit(small, large, default_rate) -> tuple[float, float]:
    """(seconds a unit, fixed seconds) through two (work, seconds). Where the larger took
    less than twice the smaller's time, both are mostly fixed cost and their difference
    mostly noise: the rate is then the larger's time over its work (an upper bound: its
    fixed cost counted as work), which a job of much more work than the references reads
    truly (bench/estimates.py's shot writes 12 times the larger reference's bytes); the
    default's rate where the larger did not take longer at all."""
    (u0, t0), (u1, t1) = small, large
    if not (u1 > u0 and t1 > t0):
        rate = default_rate
    elif t1 < 2 * t0:
        rate = t1 / u1
    else:
        rate = (t1 - t0) / (u1 - u0)
    return rate, max(t0 - rate * u0, 0.0)


PLAN_LENGTHS = (480, 1080, 1440, 2500, 3645)  # FFT lengths few and many ways to factor


def plan_rate(lengths=PLAN_LENGTHS) -> float:
    """:attr:`~holo_core.estimate.Calibration.fft_plan_seconds`: FFTW's measuring of a
    column pass's and a row pass's problem of each of ``lengths``, from no wisdom, per
    problem and τ(L)^1.5 (:func:`holo_core.estimate.fft_plans`). It forgets this process's
    wisdom: the last step of a process."""
    import pyfftw

    seconds = units = 0.0
    for n in lengths:
        for shape, axis in (((n, 16), 0), ((16, n), 1)):
            pyfftw.forget_wisdom()
            a = pyfftw.empty_aligned(shape, np.complex64)
            t = time.perf_counter()
            pyfftw.FFTW(a, a, axes=(axis,), flags=("FFTW_MEASURE",), threads=1)
            seconds += time.perf_counter() - t
            units += estimate.divisors(n) ** 1.5
    return seconds / units


def stage_rates(*, say=log.info) -> dict:
    """This process's rates of the plate's stages and the camera pass, each fitted through a
    small and a larger reference (:func:`reference_scene`: the larger has twice the pixels a
    side and a five times wider zone): a dict of :class:`~holo_core.estimate.Calibration`'s
    fields."""
    d = estimate.DEFAULT
    with tempfile.TemporaryDirectory(prefix="holo-calibration-") as tmp:
        small = _stages(*reference_scene(), Path(tmp))
        large = _stages(*reference_scene(2.0, 0.01), Path(tmp))
    for (work, secs), size in ((small, "small"), (large, "larger")):
        say(f"{size}: " + ", ".join(f"{k} {secs[k]:.2f} s" for k in secs))
    fits = {
        k: _fit((small[0][k], small[1][k]), (large[0][k], large[1][k]), default)
        for k, default in (
            ("emitters", d.emitter_seconds),
            ("zone sum", 1 / d.pairs_per_second),
            ("files", 1 / d.write_bytes_per_second),
            ("view", d.view_factor),
            ("exact", d.exact_pixel_seconds),
        )
    }
    # the camera pass: a look's fine pixels from 2 against 10 looks (the larger: more of
    # them), then the pass's own rate and fixed cost from the two sizes' passes of 2 looks
    work, secs = large
    k = estimate.slowdown()  # as on an idle machine, as every stage
    planned = plan_rate() / k
    look = max(secs["camera 10"] - secs["camera 2"], 0.0) / 8 / work["camera 2"]
    once = [(w["camera 2"], t["camera 2"] - 2 * look * w["camera 2"]) for w, t in (small, large)]
    fits["camera 2"] = _fit(*once, d.camera_pixel_seconds)
    return {
        "emitter_seconds": fits["emitters"][0],
        "emitters_fixed": fits["emitters"][1],
        "pairs_per_second": 1 / fits["zone sum"][0],
        "zone_sum_fixed": fits["zone sum"][1],
        "write_bytes_per_second": 1 / fits["files"][0],
        "view_factor": fits["view"][0],
        "view_fixed": fits["view"][1],
        "camera_pixel_seconds": fits["camera 2"][0],
        "camera_look_seconds": look,
        "camera_fixed": fits["camera 2"][1],
        "exact_pixel_seconds": fits["exact"][0],
        "exact_fixed": fits["exact"][1],
        "fft_plan_seconds": planned,
    }


def measure(*, device: str | None = None, say=log.info) -> estimate.Calibration:
    """The calibration of this machine (module docstring), as on an idle machine (each time
    measured divided by the load's :func:`~holo_core.estimate.slowdown` as it began); ``say``
    gets a line a step."""
    with tempfile.TemporaryDirectory(prefix="holo-calibration-") as tmp:
        tmp = Path(tmp)
        jobs = reference_jobs(tmp / "out")
        # a cache for each: neither job's programs or FFT plans warm the other's
        opts = {k: {"device": device, "cache_dir": str(tmp / f"cache-{k}")} for k in jobs}
        cold = {k: _timed(j, **opts[k]) for k, j in jobs.items()}
        say("as on an idle machine (each time over the load's slowdown as it began):")
        say(
            f"a new worker, a fresh cache: plate {cold['plate']:.1f} s, camera "
            f"{cold['camera']:.1f} s"
        )
        warm = {k: _timed(j, **opts[k]) for k, j in jobs.items()}
        say(
            f"a new worker, the cache warm: plate {warm['plate']:.1f} s, camera "
            f"{warm['camera']:.1f} s"
        )
        work = {}
        try:
            for k, j in jobs.items():
                _timed(j, resident=True, **opts[k])
                work[k] = _timed(j, resident=True, **opts[k])
                worker.release()
        finally:
            worker.release()
        say(f"the same worker again: plate {work['plate']:.1f} s, camera {work['camera']:.1f} s")
        # the stages' rates in a process of its own, on the plate's warm cache (the user's
        # caches are not this calibration's to fill)
        out = subprocess.run(
            [
                sys.executable,
                "-c",
                "import json; from holo_core.calibration import "
                "stage_rates; print(json.dumps(stage_rates(say=print)))",
            ],
            env=worker.environment(**opts["plate"]),
            capture_output=True,
            text=True,
            check=True,
        )
        lines = out.stdout.strip().splitlines()
        for line in lines[:-1]:
            say(line)
        rates = json.loads(lines[-1])
    cam = jobs["camera"]
    fine = cam.camera.resolution[0] * cam.camera.resolution[1] * cam.route.supersample**2
    passed = rates["exact_fixed"] + fine * rates["exact_pixel_seconds"]  # Speckle: Exact
    d = estimate.DEFAULT
    measured = replace(
        d,
        **rates,
        job_seconds=max(work["camera"] - passed, 0.05),
        process_plate_seconds=max(0.0, warm["plate"] - work["plate"]),
        process_camera_seconds=max(0.0, warm["camera"] - work["camera"]),
        first_plate_seconds=max(0.0, cold["plate"] - warm["plate"]),
        first_camera_seconds=0.0,
    )
    # the camera pass's FFT plans are counted apart, from the lengths a job transforms
    plans = estimate.fft_plans(estimate.camera_lengths(jobs["camera"]), measured)
    measured = replace(
        measured, first_camera_seconds=max(0.0, cold["camera"] - warm["camera"] - plans)
    )
    return measured  # Cycles' radiance is not measured here: the default's (idle) rates stay


def calibrate(*, device: str | None = None, cache_dir=None, say=log.info) -> Path:
    """Measure this machine (:func:`measure`) and keep it for the estimates: the file."""
    cal = measure(device=device, say=say)
    return estimate.save(cal, device=device, cache_dir=cache_dir)
