"""The holographic pipeline for a scene: read on Blender's main thread, compute in a worker.

:func:`prepare` reads the scene into a typed job (:func:`holo_addon.export.job.read`);
:func:`run` reuses the frame's pass when it is up to date (or another frame's of the same
static shot), else hands the job to a worker process (:mod:`holo_core.worker`: no OpenCL
driver is ever loaded into Blender) that records (unless the plate's hologram is current)
and renders the holographic pass, and waits for it; :func:`apply` stores the result in the
scene. Nothing is written until every stage has finished, and each file is written
atomically, so a failed, killed or cancelled run leaves earlier holograms and passes as they
were.
"""

from __future__ import annotations

import json
import logging
from dataclasses import replace
from pathlib import Path

import bpy
import numpy as np

from holo_core import estimate, jobs, worker
from holo_core.io.image import exr_attribute
from holo_core.io.plate_paths import read_plate, store_of
from holo_core.io.view import copy_view, write_view
from holo_core.job import CameraRoute, PlateRoute, Result, pass_file
from holo_core.view import BACKGROUND_DEPTH, RenderResult

from ..export import bake
from ..export.job import Prepared, moving, output_dir, read
from ..export.scene import ExportError, border_pixels, render_size
from .options import scheduler, worker_options

log = logging.getLogger(__name__)
__all__ = [
    "Prepared",
    "apply",
    "cached_pass",
    "check_hologram",
    "clear_pass",
    "moving",
    "output_dir",
    "pass_file",
    "prepare",
    "release",
    "run",
    "start",
    "stored_key",
]


def prepare(scene, depsgraph, *, render=True, bake=False, preview=1) -> Prepared:
    """The scene read into a job (:func:`holo_addon.export.job.read`; ``preview``: the
    viewport's, at 1/``preview`` of the render's resolution). With ``bake``, emitters whose
    Base Color needs it are baked first (:mod:`holo_addon.export.bake`; never inside a
    render; Lighting: Albedo only)."""
    if bake and scene.holo.lighting != "SCENE":
        depsgraph = bake_emitters(scene) or depsgraph
    return read(scene, depsgraph, render=render, preview=preview)


def bake_emitters(scene):
    """Bake every emitter whose procedural Base Color has no current bake; returns the
    depsgraph evaluated afterwards, or None when nothing was baked."""
    todo = [
        o
        for o in scene.objects
        if o.type == "MESH"
        and o.holo.emitter != "NONE"
        and bake.needs_bake(o)
        and bake.current(o) is None
    ]
    for obj in todo:
        bake.bake(obj, scene)
        log.info("baked the Base Color of '%s' into image '%s'", obj.name, bake.image_name(obj))
    return bpy.context.evaluated_depsgraph_get() if todo else None


def start(prepared: Prepared, *, resident: bool = False) -> worker.Worker:
    """The job running in a worker process (see :class:`holo_core.worker.Worker`); with
    Lighting: Scene (and something to record), the scene is written for Cycles first and the
    worker has Cycles render the emitters' radiance before it records. ``resident``: in the
    process kept between a render's frames (the plate held in memory; :func:`release` at
    the render's end)."""
    job = prepared.lit()
    if isinstance(job.route, PlateRoute):  # a plate too large for memory records on Dask
        job = replace(job, route=replace(job.route, scheduler=scheduler()))
    options = worker_options()
    if isinstance(job.route, CameraRoute):  # a plate's is the worker's to say: it plans it
        # a new worker's start is counted: a render's later frames in its kept worker skip it
        said = estimate.job(job, device=options["device"], cache_dir=options["cache_dir"])
        log.info("holographic pass of frame %d: %s", job.output.frame, said.words())
    return worker.Worker(job, resident=resident, **options)


def release() -> None:
    """The render has ended: the worker process kept between its frames ends, and the plate
    it held is freed."""
    worker.release()


def run(
    prepared: Prepared, progress: jobs.Progress = None, on_log=None, *, resident: bool = False
) -> Result:
    """Run the job in a worker process and wait for it, unless its pass can be reused
    (:func:`cached_pass`). ``progress`` may raise :class:`holo_core.jobs.Cancelled` (the
    worker is killed); a failed worker raises :class:`holo_core.worker.WorkerError` with
    its reason. ``resident``: as :func:`start`'s."""
    cached = cached_pass(prepared)
    if cached is not None:
        return cached
    return start(prepared, resident=resident).wait(progress, on_log)


def cached_pass(prepared: Prepared) -> Result | None:
    """The frame's pass when it need not be made: on disk and made from exactly this scene,
    these settings and this core (its ``pass_key``), or else another frame's pass of the
    same static shot (its ``shot_key``: everything but the frame number is the same), copied
    as this frame's, pixel for pixel; None when the pass must be made (or the hologram
    recorded)."""
    job = prepared.job
    if not job.output.render or (prepared.holograms and prepared.records):
        return None
    path = job.output.pass_path
    if stored_key(path) == job.output.pass_key:
        log.info("holographic pass of frame %d is up to date: %s", job.output.frame, path)
        return Result(pass_path=path, reused=path)
    shot = _same_shot(path, job.output.shot_key)
    if shot is None:
        return None
    copy_view(shot, path, pass_key=job.output.pass_key)
    log.info(
        "holographic pass of frame %d: the shot is static since %s (only the frame "
        "changed), its pass reused",
        job.output.frame,
        shot.name,
    )
    return Result(pass_path=path, reused=shot)


def _same_shot(path: Path, shot_key: str) -> Path | None:
    """Another frame's pass beside ``path`` made with ``shot_key`` (the nearest frame's), or
    None."""
    if not shot_key or not path.parent.is_dir():
        return None
    frame = int(path.stem.rsplit("_", 1)[-1])

    def distance(p):
        number = p.stem.rsplit("_", 1)[-1]
        return abs(int(number) - frame) if number.isdigit() else float("inf")

    for other in sorted(path.parent.glob("holo_pass_*.exr"), key=distance):
        if (
            other != path
            and distance(other) < float("inf")
            and _header(other).get("shot_key") == shot_key
            and other.with_suffix(".png").is_file()
        ):
            return other
    return None


def _header(path) -> dict:
    """The ``holo`` header a pass file was written with ({} when none, or unreadable)."""
    info = exr_attribute(path, "holo")
    try:
        header = json.loads(info) if info else {}
    except ValueError:
        return {}
    return header if isinstance(header, dict) else {}


def stored_key(path) -> str | None:
    """The ``pass_key`` a pass file was made with (None: no file, or none recorded)."""
    return _header(path).get("pass_key")


def clear_pass(scene, frame: int, folder: Path | None = None) -> Path:
    """Frame ``frame``'s pass with nothing in it (no emitter is left in the render): clear,
    at the background's depth, the render's size (its crop's, when cropped), so the frame
    composites the raster alone; in ``folder`` (default: the output folder)."""
    r = scene.render
    w, h = render_size(r)
    if r.use_border and r.use_crop_to_border:
        left, top, right, bottom = border_pixels(r)
        w, h = max(1, right - left), max(1, bottom - top)
    view = RenderResult(
        rgb=np.zeros((h, w, 3), np.float32),
        alpha=np.zeros((h, w), np.float32),
        depth=np.full((h, w), BACKGROUND_DEPTH, np.float32),
        info={"emitters": 0},
    )
    path = pass_file(output_dir(scene) if folder is None else folder, frame)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_view(view, path)
    return path


def apply(scene, prepared: Prepared, result: Result) -> None:
    """Store the result in the scene (main thread): the plate references its hologram and
    keeps the viewing zone its job resolved (so that the camera may move inside it without a
    new recording); the compositor reads the pass
    (:func:`holo_addon.compositor.tree.pass_made`)."""
    plate = scene.objects.get(prepared.plate_name) if prepared.plate_name else None
    if plate is not None:
        plate.holo.hologram = str(prepared.holograms[0])
        plate.holo.fingerprint = prepared.fingerprint
        if prepared.zone is not None:
            _keep_zone(plate, prepared.zone)


def _keep_zone(plate, zone) -> None:
    try:
        plate.holo.zone_centre = zone.centre
        plate.holo.zone_half = zone.half_extents
        plate.holo.zone_pupil = zone.pupil
        plate.holo.zone_pixel = zone.pixel
        plate.holo.zone_set = True
    except AttributeError:  # a context that may not write ID data (inside a render)
        log.warning(
            "plate '%s': its viewing zone is used for this frame but not kept (Fit "
            "Zone to Camera keeps it)",
            plate.name,
        )


def check_hologram(scene) -> Path:
    """The plate's hologram file, read and checked; a clear error when it is missing or
    corrupt."""
    plates = [o for o in scene.objects if o.holo.is_plate]
    if not plates or not plates[0].holo.hologram:
        raise ExportError("no hologram recorded yet: run Record Hologram first")
    path = Path(bpy.path.abspath(plates[0].holo.hologram))
    if not path.is_file() and not store_of(path).is_dir():
        raise ExportError(f"the hologram file {path} is missing: record it again")
    read_plate(path)  # HologramFileError names the file (or store) and the problem
    return path
