"""This machine's rates for the estimates (:mod:`holo_core.estimate`), measured once:
``python -m holo_core calibrate``.

Two reference jobs, a small plate of a sphere (recorded, written and viewed) and a camera
pass of it, each run as the add-on runs them, in worker processes:

1. in a new worker with a fresh cache (a temporary ``XDG_CACHE_HOME``, one a job):
   programs compiled, FFT plans measured;
2. in a new worker with that cache now warm;
3. twice in one worker (the second run: the work alone).

1 − 2 is the first time's set-up, 2 − 3 a worker's start, and 3 against the default rates'
prediction scales the plate's and the camera's rates (the stages' proportions stay the
defaults'). Cycles' radiance is not measured here (no Blender): its default stays. About a
minute on a 2-core CPU; the user's own caches are left as they were.
"""

from __future__ import annotations

import logging
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


def reference_scene() -> tuple[list[Mesh], Camera, Plate]:
    """A vertex-coloured sphere of 3 cm radius 0.35 m behind a 10 cm plate, a 50 mm f/2.8
    camera 0.3 m in front of it, the plate's zone fitted around its pupil."""
    n = 32
    th, ph = np.meshgrid(np.linspace(0, np.pi, n + 1), np.linspace(0, 2 * np.pi, 2 * n + 1),
                         indexing="ij")
    v = np.stack([np.sin(th) * np.cos(ph), np.cos(th), np.sin(th) * np.sin(ph)], -1)
    idx = np.arange(v.shape[0] * v.shape[1]).reshape(v.shape[:2])
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, :-1], idx[1:, 1:]
    tri = np.concatenate([np.stack([a, c, d], -1).reshape(-1, 3),
                          np.stack([a, d, b], -1).reshape(-1, 3)])
    v = v.reshape(-1, 3)
    sphere = Mesh(vertices=v * 0.03 + [0.0, 0.0, -0.35], triangles=tri,
                  colours=np.clip(0.55 + 0.45 * v, 0.05, 1.0))
    cam = Camera(matrix_world=look_at(np.array([0.0, 0.0, 0.3]), np.array([0.0, 0.0, -0.35]),
                                      up=(0, 1, 0)),
                 lens=50, sensor_width=36, resolution=RESOLUTION, fstop=2.8,
                 focus_distance=0.62)
    zone = ViewingZone.fit([cam.position], pupil=cam.aperture_diameter, margin=0.002,
                           pixel=cam.pixel_angle())
    plate = Plate(matrix_world=np.eye(4), width=0.1, height=0.1, zone=zone)
    return [sphere], cam, plate


def reference_jobs(folder: Path) -> dict[str, Job]:
    """The two reference jobs, writing under ``folder``."""
    meshes, cam, plate = reference_scene()
    route = PlateRoute(plate=plate, holograms=(folder / "look0.exr", folder / "look1.exr"))
    return {"plate": Job(camera=cam, route=route, triangles=tuple(meshes),
                         output=Output(folder=folder / "plate")),
            "camera": Job(camera=cam, route=CameraRoute(), triangles=tuple(meshes),
                          output=Output(folder=folder / "camera"))}


def _timed(job: Job, **options) -> float:
    t = time.perf_counter()
    worker.run(job, **options)
    return time.perf_counter() - t


def measure(*, device: str | None = None, say=log.info) -> estimate.Calibration:
    """The calibration of this machine (module docstring); ``say`` gets a line a step."""
    from .plate.plan import plan_view
    from .plate.recording import plate_plan
    with tempfile.TemporaryDirectory(prefix="holo-calibration-") as tmp:
        tmp = Path(tmp)
        jobs = reference_jobs(tmp / "out")
        # a cache for each: neither job's programs or FFT plans warm the other's
        opts = {k: {"device": device, "cache_dir": str(tmp / f"cache-{k}")} for k in jobs}
        cold = {k: _timed(j, **opts[k]) for k, j in jobs.items()}
        say(f"a new worker, a fresh cache: plate {cold['plate']:.1f} s, camera "
            f"{cold['camera']:.1f} s")
        warm = {k: _timed(j, **opts[k]) for k, j in jobs.items()}
        say(f"a new worker, the cache warm: plate {warm['plate']:.1f} s, camera "
            f"{warm['camera']:.1f} s")
        work = {}
        try:
            for k, j in jobs.items():
                _timed(j, resident=True, **opts[k])
                work[k] = _timed(j, resident=True, **opts[k])
                worker.release()
        finally:
            worker.release()
        say(f"the same worker again: plate {work['plate']:.1f} s, camera {work['camera']:.1f} s")
    j = jobs["plate"]
    p = plate_plan(list(j.triangles), plate=j.route.plate, camera=j.camera,
                   looks=len(j.route.holograms)).plan
    eye = j.route.plate.to_plate(np.asarray(j.camera.position)[None])[0]
    v = plan_view(p, position=eye, pixel_angle=j.camera.pixel_angle(),
                  pupil=j.camera.aperture_diameter, resolution=j.camera.resolution)
    ref = (estimate.DEFAULT, False)
    default_work = {k: sum(s for _, s in estimate.job(jobs[k], plan=p, view=v, warm=True,
                                                       calibration=ref).work) for k in jobs}
    # floors: a run faster than a tenth of the default's work is taken as noise
    scale = {k: max(work[k] / default_work[k], 0.1) for k in jobs}
    d = estimate.DEFAULT
    return replace(
        d, pairs_per_second=d.pairs_per_second / scale["plate"],
        emitter_seconds=d.emitter_seconds * scale["plate"],
        view_factor=d.view_factor * scale["plate"],
        write_bytes_per_second=d.write_bytes_per_second / scale["plate"],
        camera_pixel_seconds=d.camera_pixel_seconds * scale["camera"],
        camera_look_seconds=d.camera_look_seconds * scale["camera"],
        job_seconds=d.job_seconds * min(scale.values()),
        process_plate_seconds=max(0.0, warm["plate"] - work["plate"]),
        process_camera_seconds=max(0.0, warm["camera"] - work["camera"]),
        first_plate_seconds=max(0.0, cold["plate"] - warm["plate"]),
        first_camera_seconds=max(0.0, cold["camera"] - warm["camera"]))


def calibrate(*, device: str | None = None, cache_dir=None, say=log.info) -> Path:
    """Measure this machine (:func:`measure`) and keep it for the estimates: the file."""
    cal = measure(device=device, say=say)
    return estimate.save(cal, device=device, cache_dir=cache_dir)
