"""The holographic pipeline for a scene: prepare on Blender's main thread, compute in a worker.

:func:`prepare` reads the scene into a :class:`Job` of plain data; :func:`start` hands it to a
worker process (:mod:`holo_core.worker`: no OpenCL driver is ever loaded into Blender) that
records (unless the plate's hologram is current) and renders the holographic pass; :func:`run`
waits for it; :func:`apply` stores the results in the scene. Nothing is written until every
stage has finished, and each file is written atomically, so a failed, killed or cancelled run
leaves earlier holograms and passes as they were.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Callable
from dataclasses import asdict, astuple, dataclass, field, replace
from functools import partial
from pathlib import Path

import bpy
import numpy as np

from holo_core import jobs, worker
from holo_core.io.hologram import read_hologram
from holo_core.io.image import exr_attribute
from holo_core.io.view import write_view
from holo_core.scene.camera import Camera, look_at
from holo_core.view import BACKGROUND_DEPTH, RenderResult

from ..export import bake, radiance
from ..export.scene import (
    ExportError,
    SceneData,
    border_pixels,
    export_imported,
    export_scene,
    plate_zone,
    render_size,
    scale,
    zone_around,
)
from .options import worker_options

log = logging.getLogger(__name__)
pass_file = worker.pass_file


@dataclass(frozen=True)
class Settings:
    """``Scene.holo`` as plain values (lengths in metres)."""

    mode: str                     # 'CAMERA' (camera hologram) or 'PLATE'
    samples: int
    max_resolution: int
    wavelength: float | None
    iterations: int
    supersample: int
    composition: str
    exposure: float               # linear factor (the scene stores stops)
    opacity_threshold: float
    seed: int
    lighting: str = "SCENE"       # 'SCENE' (Cycles' radiance) or 'ALBEDO' (the colour alone)
    lighting_samples: int = 8     # Cycles samples of the radiance (denoised)
    speckle: str = "EXACT"        # camera holograms: 'EXACT' (the looks' limit) or 'LOOKS'

    @classmethod
    def from_scene(cls, scene, unit: float) -> Settings:
        h = scene.holo
        return cls(mode=h.mode, samples=h.samples, max_resolution=h.max_resolution,
                   wavelength=h.wavelength * unit if h.wavelength > 0 else None,
                   iterations=h.iterations, supersample=h.supersample,
                   composition=h.composition, exposure=2.0 ** h.exposure,
                   opacity_threshold=h.opacity_threshold, seed=h.seed, lighting=h.lighting,
                   lighting_samples=h.lighting_samples,
                   speckle=h.speckle)

    def recording(self) -> tuple:
        """The settings a hologram depends on."""
        return (self.max_resolution, self.wavelength, self.iterations, self.seed,
                self.lighting)


@dataclass(frozen=True)
class Job:
    scene: SceneData
    settings: Settings
    output_dir: Path
    frame: int
    fingerprint: str
    current: bool                 # the plate's stored hologram matches the scene
    holograms: tuple              # paths of the iterations' hologram files
    render: bool = True           # also render the holographic pass
    pass_key: str = ""            # a digest of everything the frame's pass depends on
    border: tuple | None = None   # the render region (left, top, right, bottom) [px], uncropped
    depth_unit: float = 1.0       # metres per Blender unit: the pass's depth is in scene units
    # () -> the worker's ``radiance`` job (the scene written for Cycles), or None: Lighting:
    # Scene; called only when the worker runs
    radiance: Callable[[], dict | None] | None = field(default=None, repr=False)

    def payload(self) -> dict:
        """The job as :func:`holo_core.worker.run_job` takes it (without the radiance, which
        :func:`start` adds)."""
        return {"points": self.scene.points, "triangles": self.scene.triangles,
                "plate": self.scene.plate, "camera": self.scene.camera,
                "settings": asdict(self.settings), "holograms": self.holograms,
                "current": self.current, "render": self.render,
                "output_dir": self.output_dir, "frame": self.frame, "pass_key": self.pass_key,
                "border": self.border, "depth_unit": self.depth_unit}


@dataclass
class Outcome:
    holograms: tuple
    fingerprint: str
    recorded: bool
    pass_path: Path | None = None
    frame_path: Path | None = None
    info: dict = field(default_factory=dict)


def output_dir(scene) -> Path:
    """``Scene.holo.output_dir`` made absolute: relative to the .blend, or when it is not
    saved yet, to the render output's folder."""
    raw = scene.holo.output_dir or "//holo/"
    if raw.startswith("//") and not bpy.data.filepath:
        raise ExportError("save the .blend first, or set an absolute Output Folder in Render "
                          "Properties > Holo (the folder is relative to the .blend)")
    return Path(bpy.path.abspath(raw)).resolve()


def hologram_paths(out: Path, plate_name: str, n: int, fingerprint: str) -> tuple:
    """The iterations' hologram files of the plate for the scene digest ``fingerprint``: one
    set per recorded state, never rewritten with another state's hologram (farm workers on
    different frames never share one), and a state seen before (a resolution switched back,
    a camera returned) is not recorded again."""
    stem = f"{bpy.path.clean_name(plate_name)}_hologram_{fingerprint}"
    return tuple(out / (f"{stem}.exr" if i == 0 else f"{stem}.{i}.exr") for i in range(n))


def prepare(scene, depsgraph, *, render=True, bake=False) -> Job:
    """Read the scene (main thread, or a render's). With ``bake``, emitters whose Base Color
    needs it are baked first (:mod:`holo_addon.export.bake`; never inside a render; Lighting:
    Albedo only). Raises :class:`scene_export.ExportError` for a scene that cannot be
    recorded. With Lighting: Scene, what the emitters' radiance depends on (lights, world,
    every object the render draws, Cycles' settings) enters the hologram's and the pass's
    digests, so a changed light renders again and an unchanged scene is reused."""
    unit = scale(scene)
    settings = Settings.from_scene(scene, unit)
    lit = settings.lighting == "SCENE"
    if bake and not lit:
        depsgraph = bake_emitters(scene) or depsgraph
    out = output_dir(scene)
    region, frame = render_region(scene), scene.frame_current
    imported = settings.mode == "PLATE" and imported_plate(scene)
    if imported:  # viewed as it is, never recorded: no emitters needed
        data = export_imported(scene, depsgraph, imported)
        lit = False
    else:
        data = export_scene(scene, depsgraph, plate=settings.mode != "CAMERA", lit=lit)
    lighting = radiance.digest(scene, depsgraph) if lit else ""
    view = data.view
    if settings.mode == "CAMERA":  # recorded for this view at every render: no plate file
        fingerprint, paths = data.fingerprint(settings.mode, settings.speckle, settings.samples,
                                       lighting), ()
    elif imported:
        paths = (Path(bpy.path.abspath(imported.holo.hologram)),)
        fingerprint = imported.holo.fingerprint or paths[0].name
    else:
        data = with_zone(data, scene.objects[data.plate_name], unit)
        view = zone_view(data)  # the radiance as the zone's centre sees it, not the camera
        # a plate is a scene asset: its digest leaves the camera out (its zone is in it)
        fingerprint = data.fingerprint(*settings.recording(), lighting, camera=False)
        paths = hologram_paths(out, data.plate_name, settings.iterations, fingerprint)
    light = partial(radiance.request, scene, depsgraph.view_layer.name, view,
                    data.points + data.triangles, data.names,
                    samples=settings.lighting_samples) if lit else None
    return Job(scene=data, settings=settings, output_dir=out, frame=frame,
               fingerprint=fingerprint, current=bool(paths) and all(p.is_file() for p in paths),
               holograms=paths, render=render, border=region, depth_unit=unit, radiance=light,
               pass_key=data.fingerprint(*astuple(settings), frame, region, unit, lighting))


def imported_plate(scene):
    """The scene's plate when it holds an imported hologram (File ▸ Import ▸ Hologram), else
    None."""
    plates = [o for o in scene.objects if o.holo.is_plate]
    return plates[0] if len(plates) == 1 and plates[0].holo.imported else None


def with_zone(data: SceneData, plate_object, unit: float) -> SceneData:
    """``data`` whose plate has its viewing zone: the plate's own, else (set now, and kept on
    the plate) the camera's pupil with the plate's Zone Margin around it."""
    if data.plate.zone is not None:
        return data
    zone = zone_around(data.plate, data.camera, plate_object.holo.zone_margin * unit)
    try:  # kept, so that the camera may move inside it without a new recording
        plate_object.holo.zone_centre = zone.centre
        plate_object.holo.zone_half = zone.half_extents
        plate_object.holo.zone_pupil = zone.pupil
        plate_object.holo.zone_set = True
        zone = plate_zone(plate_object)  # as kept (single precision): the next key's too
    except AttributeError:  # a context that may not write ID data (inside a render)
        log.warning("plate '%s': its viewing zone is used for this frame but not kept (Fit "
                    "Zone to Camera keeps it)", data.plate_name)
    return replace(data, plate=replace(data.plate, zone=zone))


def zone_view(data: SceneData) -> Camera:
    """A pinhole at the zone's centre looking at the emitters' centre, with the render
    camera's lens and frame: what a plate's radiance is rendered from."""
    plate = data.plate
    eye = plate.matrix_world[:3, :3] @ np.asarray(plate.zone.centre) + plate.matrix_world[:3, 3]
    every = np.concatenate([m.vertices for m in data.points + data.triangles])
    centre = (every.min(0) + every.max(0)) / 2
    return replace(data.view, matrix_world=look_at(eye, centre, up=plate.matrix_world[:3, 1]))


def render_region(scene) -> tuple | None:
    """A render region that is not cropped (left, top, right, bottom) [px from the top-left]:
    Blender renders only inside it, so the pass is cleared outside; None without one."""
    r = scene.render
    return border_pixels(r) if r.use_border and not r.use_crop_to_border else None


def bake_emitters(scene):
    """Bake every emitter whose procedural Base Color has no current bake; returns the
    depsgraph evaluated afterwards, or None when nothing was baked."""
    todo = [o for o in scene.objects if o.type == "MESH" and o.holo.emitter != "NONE"
            and bake.needs_bake(o) and bake.current(o) is None]
    for obj in todo:
        bake.bake(obj, scene)
        log.info("baked the Base Color of '%s' into image '%s'", obj.name, bake.image_name(obj))
    return bpy.context.evaluated_depsgraph_get() if todo else None


def start(job: Job) -> worker.Worker:
    """The job running in a worker process (see :class:`holo_core.worker.Worker`); with
    Lighting: Scene (and a hologram to record), the scene is written for Cycles first and the
    worker has Cycles render the emitters' radiance before it records."""
    payload = job.payload()
    if job.radiance is not None and not job.current:
        payload["radiance"] = job.radiance()
    return worker.Worker(payload, **worker_options())


def outcome(job: Job, result: dict) -> Outcome:
    return Outcome(holograms=job.holograms, fingerprint=job.fingerprint,
                   recorded=result["recorded"], pass_path=result["pass_path"],
                   frame_path=result["frame_path"], info=result["info"])


def run(job: Job, progress: jobs.Progress = None, on_log=None) -> Outcome:
    """Run the job in a worker process and wait for it. ``progress`` may raise
    :class:`holo_core.jobs.Cancelled` (the worker is killed); a failed worker raises
    :class:`holo_core.worker.WorkerError` with its reason."""
    cached = cached_pass(job)
    if cached is not None:
        return cached
    return outcome(job, start(job).wait(progress, on_log))


def cached_pass(job: Job) -> Outcome | None:
    """The frame's pass when it is on disk and was made from exactly this scene, these
    settings and this core (its ``pass_key``), and the hologram needs no recording."""
    path = pass_file(job.output_dir, job.frame)
    if not job.render or (job.holograms and not job.current):
        return None
    if stored_key(path) != job.pass_key:
        return None
    log.info("holographic pass of frame %d is up to date: %s", job.frame, path)
    return Outcome(holograms=job.holograms, fingerprint=job.fingerprint, recorded=False,
                   pass_path=path, frame_path=path, info={"cached": True})


def stored_key(path) -> str | None:
    """The ``pass_key`` a pass file was made with (None: no file, or none recorded)."""
    info = exr_attribute(path, "holo")
    try:
        return json.loads(info).get("pass_key") if info else None
    except (ValueError, AttributeError):
        return None


def clear_pass(scene, frame: int) -> Path:
    """Frame ``frame``'s pass with nothing in it (no emitter is left in the render): clear,
    at the background's depth, the render's size (its crop's, when cropped), so the frame
    composites the raster alone."""
    r = scene.render
    w, h = render_size(r)
    if r.use_border and r.use_crop_to_border:
        left, top, right, bottom = border_pixels(r)
        w, h = max(1, right - left), max(1, bottom - top)
    view = RenderResult(rgb=np.zeros((h, w, 3), np.float32), alpha=np.zeros((h, w), np.float32),
                        depth=np.full((h, w), BACKGROUND_DEPTH, np.float32),
                        info={"emitters": 0})
    path = pass_file(output_dir(scene), frame)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_view(view, path)
    return path


def reload_passes(path: Path) -> None:
    """The compositor's image sequences of holographic passes read ``path``'s folder again."""
    for image in bpy.data.images:
        name = Path(image.filepath).name if image.filepath else ""
        if image.source == "SEQUENCE" and name.startswith("holo_pass_"):
            if Path(bpy.path.abspath(image.filepath)).parent != path.parent:
                image.filepath = str(path)
            image.reload()


def apply(scene, job: Job, outcome: Outcome) -> None:
    """Store the outcome in the scene (main thread): the plate references its hologram, and
    the image sequences of holographic passes read this frame's file from the output folder
    (which may have changed since compositing was set up)."""
    plate = scene.objects.get(job.scene.plate_name) if job.scene.plate_name else None
    if plate is not None:
        plate.holo.hologram = str(outcome.holograms[0])
        plate.holo.fingerprint = outcome.fingerprint
    if outcome.pass_path is not None:
        reload_passes(outcome.pass_path)


def check_hologram(scene) -> Path:
    """The plate's hologram file, read and checked; a clear error when it is missing or
    corrupt."""
    plates = [o for o in scene.objects if o.holo.is_plate]
    if not plates or not plates[0].holo.hologram:
        raise ExportError("no hologram recorded yet: run Record Hologram first")
    path = Path(bpy.path.abspath(plates[0].holo.hologram))
    if not path.is_file():
        raise ExportError(f"the hologram file {path} is missing: record it again")
    read_hologram(path)  # HologramFileError names the file and the problem
    return path
