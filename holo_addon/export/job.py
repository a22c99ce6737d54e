"""Blender scene → :class:`holo_core.job.Job`, complete, in one visit (Blender's main thread,
or a render's).

:func:`read` reads the scene's settings, emitters, camera and plate (its viewing zone
resolved: the plate's own, else the camera's pupil with the plate's Zone Margin) and the
digests that name the hologram files and say whether a pass is up to date, and builds the
core's typed job. Nothing is written into Blender's data while reading: a zone the job
resolved is kept on the plate (:attr:`Prepared.zone`) once the job has succeeded.
"""

from __future__ import annotations

import hashlib
import logging
from collections.abc import Callable
from dataclasses import astuple, dataclass, field, replace
from functools import partial
from pathlib import Path

import bpy
import numpy as np

from holo_core import __version__
from holo_core.io.hologram import FORMAT_VERSION
from holo_core.io.plate_paths import plate_current
from holo_core.io.plate_set import MANIFEST, set_current
from holo_core.job import CameraRoute, Job, Output, PlateRoute, Radiance, SetRoute
from holo_core.scene.camera import Camera
from holo_core.scene.mesh import Mesh
from holo_core.scene.plate import ViewingZone

from . import quality, radiance, ranges
from .motion import with_motion
from .plates import beyond_zone, export_imported, plate_parts, scene_plate, with_plate, with_set
from .scene import ExportError, SceneData, export_scene

log = logging.getLogger(__name__)
EXPOSURE_STOPS = 64.0  # either way: the core takes an exposure up to 1e20, 66 stops


@dataclass(frozen=True)
class Settings:
    """``Scene.holo`` as plain values (lengths in metres)."""

    mode: str  # 'CAMERA' (camera hologram) or 'PLATE'
    samples: int
    memory_budget: float  # [bytes] a plate's recording, at most
    disk_budget: float  # [bytes] a plate's files, at most
    wavelength: float | None
    iterations: int  # looks of a plate (0: Auto, the plan's choice)
    supersample: int  # fine pixels a pixel (0: Auto)
    composition: str
    exposure: float  # linear factor (the scene stores stops)
    opacity_threshold: float
    seed: int
    lighting: str = "SCENE"  # 'SCENE' (Cycles' radiance) or 'ALBEDO' (the colour alone)
    lighting_samples: int = 8  # Cycles samples of the radiance (denoised)
    speckle: str = "EXACT"  # camera holograms: 'EXACT' (the looks' limit) or 'LOOKS'

    @classmethod
    def from_scene(cls, scene, unit: float) -> Settings:
        h = scene.holo
        gb = 2.0**30
        return cls(
            mode=h.mode,
            samples=h.samples,
            memory_budget=h.plate_memory * gb,
            disk_budget=h.plate_disk * gb,
            wavelength=h.wavelength * unit if h.wavelength > 0 else None,
            iterations=h.iterations,
            supersample=h.supersample,
            composition=h.composition,
            exposure=2.0**h.exposure,
            opacity_threshold=h.opacity_threshold,
            seed=h.seed,
            lighting=h.lighting,
            lighting_samples=h.lighting_samples,
            speckle=h.speckle,
        )

    def recording(self) -> tuple:
        """The settings a hologram depends on."""
        return (self.wavelength, self.iterations, self.seed, self.lighting)

    def camera_route(self) -> CameraRoute:
        return CameraRoute(
            samples=self.samples,
            speckle=self.speckle,
            supersample=self.supersample,
            exposure=self.exposure,
            seed=self.seed,
        )

    def set_route(self, parts, folder, record: bool, recording: str, outside: str) -> SetRoute:
        return SetRoute(
            parts=parts,
            folder=folder,
            looks=self.iterations,
            record=record,
            recording=recording,
            memory_budget=self.memory_budget,
            disk_budget=self.disk_budget,
            supersample=self.supersample,
            composition=self.composition,
            exposure=self.exposure,
            opacity_threshold=self.opacity_threshold,
            seed=self.seed,
            outside=outside,
        )

    def plate_route(self, plate, holograms, record: bool, recording: str = "") -> PlateRoute:
        return PlateRoute(
            plate=plate,
            holograms=holograms,
            record=record,
            recording=recording,
            memory_budget=self.memory_budget,
            disk_budget=self.disk_budget,
            wavelength=self.wavelength,
            supersample=self.supersample,
            composition=self.composition,
            exposure=self.exposure,
            opacity_threshold=self.opacity_threshold,
            seed=self.seed,
        )


@dataclass(frozen=True, eq=False)
class Prepared:
    """A scene read for the worker: the core's ``job`` and what the add-on keeps beside it:
    the hologram's digest (``fingerprint``, its files' names), the plate's object name, the
    scene's ``warnings``, the viewing ``zone`` to keep on the plate once the job succeeds
    (None: nothing new), and with Lighting: Scene ``lighting``, which writes the scene for
    Cycles and returns the job's :class:`holo_core.job.Radiance` (called only when the
    worker runs, and only where something is recorded)."""

    job: Job
    fingerprint: str
    plate_name: str | None = None
    warnings: tuple = ()
    zone: ViewingZone | None = None
    lighting: Callable[[], Radiance | None] | None = field(default=None, repr=False)
    instead: str = ""  # why a Plate-mode frame is a camera hologram ("": it is not)

    @property
    def records(self) -> bool:
        """Whether the worker records (a camera hologram always does)."""
        route = self.job.route
        return isinstance(route, CameraRoute) or route.record

    @property
    def made_by(self) -> str:
        """Which route makes the frame's pass, in words for its log line."""
        if isinstance(self.job.route, SetRoute):
            return f"from plate '{self.plate_name}' (a set of {len(self.job.route.parts)} parts)"
        if isinstance(self.job.route, PlateRoute):
            return f"from plate '{self.plate_name}'"
        return f"as a camera hologram ({self.instead})" if self.instead else "as a camera hologram"

    @property
    def holograms(self) -> tuple:
        """The plate's hologram files (none for a camera hologram)."""
        route = self.job.route
        if isinstance(route, SetRoute):  # the set's manifest names its every file
            return (route.folder / MANIFEST,)
        return route.holograms if isinstance(route, PlateRoute) else ()

    def lit(self) -> Job:
        """The job with its radiance (the scene written for Cycles now), where it needs one."""
        if self.lighting is None or not self.records:
            return self.job
        return replace(self.job, radiance=self.lighting())


def read(scene, depsgraph, *, render=True, preview=1) -> Prepared:
    """The scene as ``depsgraph`` evaluates it, as one job (``render``: view it into the
    frame's pass; else a plate's recording alone). Raises :class:`ExportError` for a scene
    that cannot be recorded. With Lighting: Scene, what the emitters' radiance depends on
    (lights, world, every object the render draws, Cycles' settings) enters the hologram's
    and the pass's digests, so a changed light renders again and an unchanged scene is
    reused. ``preview`` > 1 (Camera mode): the viewport's preview, at 1/``preview`` of the
    render's resolution (the same frame), into the output folder's ``preview/``."""
    mode, instead = scene.holo.mode, ""
    out = output_dir(scene) / "preview" if preview > 1 else output_dir(scene)
    ranges.check(scene.holo, scene)  # before any work: a script may set what the panel cannot
    plate = scene_plate(scene, required=mode == "PLATE")
    if plate is not None:
        ranges.check(plate.holo, scene)
    imported = plate if mode == "PLATE" and plate.holo.imported else None
    parts = plate_parts(plate) if mode == "PLATE" and not imported else None
    lit = scene.holo.lighting == "SCENE" and not imported
    if imported:  # viewed as it is, never recorded: no emitters needed
        data = export_imported(scene, depsgraph, imported)
    else:
        data = export_scene(scene, depsgraph, lit=lit)
        if mode == "PLATE":  # a render's frame beyond the zone fails where the user says so
            at_camera = data
            strict = preview <= 1 and scene.holo.outside_zone == "FAIL"
            data = (
                with_set(data, plate, parts, strict=strict)
                if parts
                else with_plate(data, plate, depsgraph, strict=strict)
            )
            beyond = beyond_zone(data.plate, data.camera)
            if render and preview <= 1 and beyond and scene.holo.outside_zone == "CAMERA":
                # the plate cannot serve this frame whole: a camera hologram of it can
                data, mode, parts = at_camera, "CAMERA", None
                instead = (
                    f"the camera's pupil reaches {beyond:.3g} m beyond the viewing "
                    f"zone of plate '{plate.name}' (Outside Zone: Camera Hologram)"
                )
    if preview > 1:
        data = replace(
            data,
            camera=coarser(data.camera, preview),
            view=coarser(data.view, preview),
            region=None,
        )
    lighting = radiance.digest(scene, depsgraph) if lit else ""
    settings = replace(Settings.from_scene(scene, data.unit), mode=mode)
    # Iterations and Supersample at Auto take the plan's choice for this plate; a lower
    # setting of the user's is said with what it loses
    settings, said = quality.resolve(settings, data, None if imported else parts)
    data = replace(data, warnings=data.warnings + said)
    if mode == "CAMERA":  # recorded for this view at every render: no plate file
        fingerprint = digest(data, mode, settings.speckle, settings.samples, lighting, kinds=False)
        route = settings.camera_route()
    elif parts:
        # the set is a scene asset: its digest holds its parts and leaves the camera and the
        # part that holds it out
        fingerprint = digest(
            replace(data, plate=None),
            *settings.recording(),
            lighting,
            plate.holo.parts,
            camera=False,
        )
        folder = out / f"{bpy.path.clean_name(data.plate_name)}_set_{fingerprint}"
        route = settings.set_route(
            parts,
            folder,
            recording=fingerprint,
            record=not set_current(folder, fingerprint, len(parts)),
            outside="fail" if scene.holo.outside_zone == "FAIL" else "warn",
        )
        if settings.wavelength is not None:
            data = replace(
                data,
                warnings=data.warnings
                + (
                    "a plate set's parts are recorded at the planner's wavelength: the scene's "
                    "Wavelength is not used for them",
                ),
            )
    elif imported:
        paths = (Path(bpy.path.abspath(imported.holo.hologram)),)
        fingerprint = imported.holo.fingerprint or paths[0].name
        route = settings.plate_route(data.plate, paths, record=False)
    else:
        # a plate is a scene asset: its digest leaves the camera out (its zone is in it)
        fingerprint = digest(data, *settings.recording(), lighting, camera=False)
        paths = hologram_paths(out, data.plate_name, settings.iterations, fingerprint)
        # a file there under this name but of another recording is recorded again, never
        # rendered as this scene's
        route = settings.plate_route(
            data.plate,
            paths,
            recording=fingerprint,
            record=not all(plate_current(p, fingerprint) for p in paths),
        )
    frame, region, unit = scene.frame_current, data.region, data.unit
    animated = lit and getattr(scene.cycles, "use_animated_seed", False)
    kinds = mode != "CAMERA"  # a camera hologram renders points and triangles alike
    asset = (fingerprint,) if parts else ()  # a set's passes change with any of its parts
    output = Output(
        folder=out,
        frame=frame,
        render=render,
        depth_unit=unit,
        border=region,
        pass_key=digest(
            data, *astuple(settings), frame, region, unit, lighting, *asset, kinds=kinds
        ),
        shot_key=digest(
            data,
            *astuple(settings),
            region,
            unit,
            lighting,
            "shot",
            frame if animated else None,
            *asset,
            kinds=kinds,
        ),
    )
    job = Job(
        camera=data.camera,
        points=tuple(data.points),
        triangles=tuple(data.triangles),
        route=route,
        output=output,
    )
    light = (
        partial(
            radiance.request,
            scene,
            depsgraph.view_layer.name,
            data.view,
            data.points + data.triangles,
            data.names,
            samples=settings.lighting_samples,
        )
        if lit
        else None
    )
    return Prepared(
        job=job,
        fingerprint=fingerprint,
        plate_name=data.plate_name,
        warnings=data.warnings,
        zone=data.zone,
        lighting=light,
        instead=instead,
    )


def digest(data: SceneData, *settings, camera=True, kinds=True) -> str:
    """A digest of everything the hologram depends on: each emitter's kind, evaluated
    geometry and colours (vertex colours, texture and UVs, material colours), the plate
    and its viewing zone, the camera (its pose, lens and focus; ``camera=False`` leaves
    it out, for a plate recorded for its zone), ``settings`` and the core's version and
    file format. ``kinds=False``: the emitters' kinds left out (a camera hologram renders
    points and triangles alike)."""
    h = hashlib.sha256(f"holo {__version__} format {FORMAT_VERSION}".encode())
    meshes = [
        (kind, mesh_digest(m))
        for kind, group in (("points", data.points), ("triangles", data.triangles))
        for m in group
    ]
    for kind, mesh in meshes if kinds else sorted(("", d) for _, d in meshes):
        h.update(kind.encode() + mesh + b"|")
    plate = (
        ()
        if data.plate is None
        else (data.plate.matrix_world, (data.plate.width, data.plate.height))
    )
    zone = data.plate.zone if data.plate is not None else None
    if zone is not None:
        plate += (zone.centre, zone.half_extents, zone.pupil)
    for a in (*plate, *((data.camera.matrix_world,) if camera else ())):
        h.update(np.asarray(a, np.float64).tobytes())
    lens = (
        (
            data.camera.lens,
            data.camera.sensor_width,
            data.camera.sensor_height,
            data.camera.sensor_fit,
            data.camera.shift_x,
            data.camera.shift_y,
            data.camera.resolution,
            data.camera.pixel_aspect,
            data.camera.fstop,
            data.camera.focus_distance,
        )
        if camera
        else ("no camera",)
    )
    h.update(repr(lens + settings).encode())
    return h.hexdigest()[:16]


def mesh_digest(mesh: Mesh) -> bytes:
    """A mesh's geometry, colours and motion across the shutter, digested."""
    h = hashlib.sha256()
    for a in (
        mesh.vertices,
        mesh.colours,
        mesh.uvs,
        mesh.texture,
        *(() if mesh.motion is None else (mesh.motion,)),
    ):
        h.update(
            b"-"
            if a is None
            else np.ascontiguousarray(a, np.float64).tobytes() + repr(a.shape).encode()
        )
    return h.digest()


def moving(prepared: Prepared, samples, opening: float, closing: float) -> Prepared:
    """``prepared`` with its emitters blurred across the shutter from ``opening`` to
    ``closing`` [frames] (Camera mode; ``samples``: :class:`holo_addon.export.motion.Sample`
    of the shutter's times): their meshes carry their motion, and the digests of the pass
    and of its static shot change with it. Itself where nothing moves."""
    job = prepared.job
    if not isinstance(job.route, CameraRoute) or len(samples) < 2:
        return prepared
    blurred = with_motion(job, samples, opening, closing)
    moved = [m for m in blurred.points + blurred.triangles if m.motion is not None]
    if not moved:
        return prepared

    def rekeyed(key: str) -> str:
        h = hashlib.sha256(key.encode())
        for mesh in moved:
            h.update(mesh_digest(mesh))
        return h.hexdigest()[:16]

    output = replace(
        job.output, pass_key=rekeyed(job.output.pass_key), shot_key=rekeyed(job.output.shot_key)
    )
    return replace(
        prepared, job=replace(blurred, output=output), fingerprint=rekeyed(prepared.fingerprint)
    )


def coarser(camera: Camera, factor: int) -> Camera:
    """``camera``'s frame at 1/``factor`` of its resolution (the same field of view)."""
    w, h = camera.resolution
    return replace(camera, resolution=(max(1, round(w / factor)), max(1, round(h / factor))))


def output_dir(scene) -> Path:
    """``Scene.holo.output_dir`` made absolute: relative to the .blend, or when it is not
    saved yet, to the render output's folder."""
    raw = scene.holo.output_dir or "//holo/"
    if raw.startswith("//") and not bpy.data.filepath:
        raise ExportError(
            "save the .blend first, or set an absolute Output Folder in Render "
            "Properties > Holo (the folder is relative to the .blend)"
        )
    return Path(bpy.path.abspath(raw)).resolve()


def hologram_paths(out: Path, plate_name: str, n: int, fingerprint: str) -> tuple:
    """The iterations' hologram files of the plate for the scene digest ``fingerprint``: one
    set per recorded state, never rewritten with another state's hologram (farm workers on
    different frames never share one), and a state seen before (a resolution switched back,
    a camera returned) is not recorded again."""
    stem = f"{bpy.path.clean_name(plate_name)}_hologram_{fingerprint}"
    return tuple(out / (f"{stem}.exr" if i == 0 else f"{stem}.{i}.exr") for i in range(n))
