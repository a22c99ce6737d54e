"""The plate as a scene asset: its viewing zone (Fit Zone to Camera, Fit Zone to Shot: the
camera's pupil over the frame range, or over a move longer than the plate's Part Length a set
of parts along the camera's path), the planner (Plan Plate: what a plate will take and give
before any recording) and File ▸ Import ▸ Hologram.

The planner is pure arithmetic (:mod:`holo_core.plate.plan`, no OpenCL, nor the core's
physics): it runs in Blender's process, and its lines are shown in the plate's panel, the
verdict first. An imported hologram becomes a plate object placed where its metadata puts it,
linked to its file (kept, relative to the .blend, when the .blend is saved) and viewed as it
is: it is never recorded.
"""

from __future__ import annotations

import re
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import bpy
import numpy as np
from bpy_extras.io_utils import ImportHelper
from mathutils import Matrix

from holo_core import estimate, memory
from holo_core.acquired.framing import default_camera, stated_plane
from holo_core.io.hologram import HologramFileError, read_hologram
from holo_core.io.plate_set import parts_from_json, parts_to_json
from holo_core.plate.path import parts_along, plan_parts
from holo_core.plate.plan import plan, plan_view
from holo_core.plate.plan_summary import summary
from holo_core.plate.quality import choose
from holo_core.plate.zone_light import seen_area
from holo_core.scene.hologram import Hologram
from holo_core.scene.mesh import Mesh
from holo_core.scene.plate import ViewingZone, box_corners
from holo_core.validate import InputError
from holo_core.worker import environment

from ..blender.objects import raster_visibility
from ..compositor.session import session
from ..export import ranges
from ..export.plates import nearest_part, plate_from_object, plate_parts, zone_around
from ..export.scene import (
    ExportError,
    camera_from_object,
    corner_positions,
    emitter_instances,
    scale,
)
from ..render.options import device, runtime_paths, worker_options
from . import overlay


def plate_object(context):
    obj = context.object
    return obj if obj is not None and obj.type == "MESH" and obj.holo.is_plate else None


def _keep(obj, zone) -> None:
    """The zone on the plate's settings (what the next recording is for): one plate."""
    obj.holo.zone_centre, obj.holo.zone_half = zone.centre, zone.half_extents
    obj.holo.zone_pupil, obj.holo.zone_pixel = zone.pupil, zone.pixel
    obj.holo.zone_set = True
    obj.holo.parts = ""


def part_count(holo) -> int:
    """How many parts the plate's settings hold (0: one plate)."""
    try:
        return len(parts_from_json(holo.parts)) if holo.parts else 0
    except InputError:
        return 0


class HOLO_OT_fit_zone(bpy.types.Operator):
    """Set the plate's viewing zone around the scene camera's pupil, the Zone Margin around it: the plate is recorded for views from there"""

    bl_idname = "holo.fit_zone"
    bl_label = "Fit Zone to Camera"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if plate_object(context) is None or context.scene.camera is None:
            cls.poll_message_set("Select the plate; the scene needs a camera")
            return False
        return True

    def execute(self, context):
        obj, unit = plate_object(context), scale(context.scene)
        try:
            plate = plate_from_object(obj, unit)
            camera = camera_from_object(context.scene, context.scene.camera, unit)
            zone = zone_around(plate, camera, obj.holo.zone_margin * unit)
        except (ExportError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        _keep(obj, zone)
        overlay.refresh(context)
        self.report({"INFO"}, f"plate '{obj.name}': viewing zone {zone.describe()}")
        return {"FINISHED"}


class HOLO_OT_fit_zone_to_shot(bpy.types.Operator):
    """Set the plate's viewing zone around the scene camera's pupil at every frame of the scene's range, the Zone Margin around it: the plate is recorded once and every frame of the shot renders from it"""

    bl_idname = "holo.fit_zone_to_shot"
    bl_label = "Fit Zone to Shot"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return HOLO_OT_fit_zone.poll(context)

    def execute(self, context):
        scene, obj, unit = context.scene, plate_object(context), scale(context.scene)
        try:
            parts, frames, distance = shot_parts(
                scene, obj, unit, context.evaluated_depsgraph_get()
            )
            if len(parts) == 1:  # one plate serves the move: the plate as the user placed it
                zone, frames = shot_zone(scene, obj, unit)
        except (ExportError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if len(parts) > 1:
            obj.holo.parts = parts_to_json(parts)
            obj.holo.zone_set = False
            length = parts[-1].stretch[1]
            self.report(
                {"INFO"},
                f"plate '{obj.name}': a set of {len(parts)} parts along "
                f"{length / unit:.3g} units of the camera's path over "
                f"frames {frames[0]}-{frames[-1]}, each facing its stretch "
                f"{distance / unit:.3g} units from the "
                f"objects: every frame renders from the part that holds its "
                f"camera",
            )
            overlay.refresh(context)
            return {"FINISHED"}
        _keep(obj, zone)
        self.report(
            {"INFO"},
            f"plate '{obj.name}': viewing zone {zone.describe()}, the "
            f"camera's pupil over frames {frames[0]}-{frames[-1]}",
        )
        return {"FINISHED"}


def shot_cameras(scene, unit):
    """(the frames of the scene's range, the scene camera at each, world metres); the
    timeline is put back where it was."""
    frames = list(range(scene.frame_start, scene.frame_end + 1, max(1, scene.frame_step)))
    current, cameras = scene.frame_current, []
    try:
        for frame in frames:
            scene.frame_set(frame)
            cameras.append(camera_from_object(scene, scene.camera, unit))
    finally:
        scene.frame_set(current)
    return frames, cameras


def emitter_box(depsgraph, unit) -> np.ndarray:
    """The holographic objects' box (2, 3) [m, world]: their triangles' corners, as the
    recording takes them."""
    every = np.concatenate(emitter_corners(depsgraph, unit))
    return np.array([every.min(0), every.max(0)])


def emitter_corners(depsgraph, unit) -> list[np.ndarray]:
    """Each holographic object's triangles' corners (3T, 3) [m, world], as the recording
    takes them."""
    corners = [
        corner_positions(inst.object, depsgraph, unit, inst.matrix_world)
        for inst, _ in emitter_instances(depsgraph)
    ]
    if not corners:
        raise ExportError("no holographic emitters to plan for")
    return corners


def corner_meshes(corners) -> list[Mesh]:
    """The objects' triangles (each a ``corners`` array, three rows a triangle) as meshes, for
    the planner's count of the surfaces a zone sees (a closed object's corners meet again:
    :func:`holo_core.scene.mesh.outward` merges them)."""
    return [Mesh(vertices=c, triangles=np.arange(len(c)).reshape(-1, 3)) for c in corners]


def shot_parts(scene, obj, unit, depsgraph):
    """(the parts of a plate serving the scene camera's path over the frame range
    (:func:`holo_core.plate.path.parts_along`): each part's Part Length of path, the Zone
    Margin around its pupils, the plates as far from the objects' centre as the plate object
    is; the frames; that distance [m]). One part: one plate serves the move."""
    frames, cameras = shot_cameras(scene, unit)
    box = emitter_box(depsgraph, unit)
    plate = plate_from_object(obj, unit)
    distance = float(np.linalg.norm(plate.matrix_world[:3, 3] - box.mean(0)))
    try:
        parts = parts_along(
            cameras,
            box,
            distance=distance,
            stretch=obj.holo.part_length * unit,
            margin=obj.holo.zone_margin * unit,
        )
    except InputError as e:
        raise ExportError(f"plate '{obj.name}': {_frames_named(str(e), frames)}") from None
    return parts, frames, distance


def _frames_named(text: str, frames) -> str:
    """The core's message, its frames (indices along the path) named by their numbers on the
    timeline."""

    def number(m):
        first = frames[min(int(m.group(2)), len(frames) - 1)]
        if m.group(4) is None:
            return f"{m.group(1)} {first}"
        return f"{m.group(1)} {first}-{frames[min(int(m.group(4)), len(frames) - 1)]}"

    return re.sub(r"\b(frames?) (\d+)(-(\d+))?", number, text)


def shot_zone(scene, obj, unit):
    """(the zone holding the scene camera's pupil at every frame of the scene's range with the
    plate's Zone Margin around it, the frames); the timeline is put back where it was."""
    frames = list(range(scene.frame_start, scene.frame_end + 1, max(1, scene.frame_step)))
    current, positions, camera = scene.frame_current, [], None
    try:
        for frame in frames:
            scene.frame_set(frame)
            plate = plate_from_object(obj, unit)
            camera = camera_from_object(scene, scene.camera, unit)
            positions.append(plate.to_plate(camera.position[None])[0])
    finally:
        scene.frame_set(current)
    if min(p[2] for p in positions) <= 0:
        raise ExportError(
            f"the camera passes behind plate '{obj.name}' during the shot: "
            f"viewers must stay on its +Z side"
        )
    zone = ViewingZone.fit(
        positions,
        camera.aperture_diameter or 0.0,
        obj.holo.zone_margin * unit,
        camera.pixel_angle(),
    )
    return zone, frames


def set_summary(context, obj, parts) -> list[str]:
    """The planner's lines for a plate set (:meth:`holo_core.plate.path.SetPlan.describe`):
    the verdict, the set, what the scene camera's frame reads, each part, and a budget it
    exceeds first where it does."""
    scene, unit, h = context.scene, scale(context.scene), context.scene.holo
    meshes = corner_meshes(emitter_corners(context.evaluated_depsgraph_get(), unit))
    every = np.concatenate([m.vertices for m in meshes])
    corners = box_corners(np.array([every.min(0), every.max(0)]))
    camera = camera_from_object(scene, scene.camera, unit)
    plans = plan_parts(parts, corners, meshes=meshes).plans
    choices = [
        choose(
            q,
            resolution=camera.resolution,
            looks=h.iterations,
            supersample=h.supersample,
            budget=budget(h),
            plans=plans,
        )
        for q in plans
    ]
    choice = min(choices, key=lambda c: c.planned.psnr)  # the part that needs the most
    p = plan_parts(parts, corners, looks=choice.looks, meshes=meshes)
    options = worker_options()  # the estimate of this machine for the worker's device and cache
    took = estimate.plate_set(p, device=options["device"], cache_dir=options["cache_dir"])
    k, beyond = nearest_part(parts, camera)
    here = (
        f"part {k + 1} holds the camera's pupil"
        if not beyond
        else f"the camera's pupil reaches {beyond:.3g} m beyond every part (part {k + 1} is "
        f"the nearest)"
    )
    widest = max(p.plans, key=lambda q: q.samples)
    lines = [
        f"verdict     a set of {len(parts)} parts along the camera's path; each frame "
        f"renders from the part that holds its camera ({here})",
        f"set         {p.describe(took)}",
        f"a view      reads one part, at most {widest.samples / 1e6:.3g} Mpx",
        *quality_lines(choice),
    ]
    for n, (part, q) in enumerate(zip(parts, p.plans), 1):
        lines.append(
            f"part {n:<6d} {part.plate.width / unit:.3g} x "
            f"{part.plate.height / unit:.3g} units, {q.samples / 1e6:.3g} Mpx, path "
            f"{part.stretch[0] / unit:.3g}-{part.stretch[1] / unit:.3g} units"
        )
    gb = 2.0**30
    if p.disk_bytes() > h.plate_disk * gb:
        lines.insert(
            1,
            f"refused     the set needs {memory.gib(p.disk_bytes())} on disk; the "
            f"Disk Budget is {h.plate_disk:g} GiB (a longer Part Length shares "
            f"more, a smaller aperture or coarser views need less)",
        )
    elif p.memory_bytes() > h.plate_memory * gb:
        lines.insert(
            1,
            f"refused     a part needs {memory.gib(p.memory_bytes())} of memory "
            f"while recorded; the Memory Budget is {h.plate_memory:g} GiB (a "
            f"shorter Part Length needs less)",
        )
    return lines


def quality_lines(choice) -> list[str]:
    """Plan Plate's lines on the looks and supersampling (:mod:`holo_core.plate.quality`):
    what the views use and why, and what a user's lower setting loses."""
    p = choice.planned
    if choice.user_looks or choice.user_supersample:
        lines = [
            f"quality     {choice.looks} looks at supersample {choice.supersample} "
            f"predict {choice.psnr:.1f} dB; Auto would choose {p.looks} looks at "
            f"supersample {p.supersample} ({p.psnr:.1f} dB)"
        ]
    else:
        lines = [f"quality     Auto chose {choice.describe()}"]
    if choice.capped():
        lines.append(f"budget      {choice.capped()}")
    warning = choice.warning()
    if warning:
        lines.append(f"warning     {warning}")
    return lines


def budget(h) -> tuple[float, float]:
    """The scene's Memory and Disk Budgets [bytes], which Auto's looks fit."""
    return h.plate_memory * 2.0**30, h.plate_disk * 2.0**30


def plan_summary(context) -> list[str]:
    """The planner's verdict and figures (:func:`holo_core.plate.plan_summary.summary`) for the
    selected plate, the holographic objects, the scene camera and the recording settings,
    in the plate's frame; the planner runs here, in Blender's process (pure arithmetic). A
    plate made a set of parts: :func:`set_summary`."""
    scene, obj, unit = context.scene, plate_object(context), scale(context.scene)
    ranges.check(scene.holo, scene)
    ranges.check(obj.holo, scene)
    if obj.holo.parts:
        return set_summary(context, obj, plate_parts(obj))
    plate = plate_from_object(obj, unit)
    camera = camera_from_object(scene, scene.camera, unit)
    # the triangles' corners, as the recording takes them: an object's bounding box turned
    # into the plate's frame is up to √3 times wider than the object, and a plate planned
    # from it overstates its samples and memory by as much (docs, Performance)
    meshes = [
        replace(m, vertices=plate.to_plate(m.vertices))
        for m in corner_meshes(emitter_corners(context.evaluated_depsgraph_get(), unit))
    ]
    local = np.concatenate([m.vertices for m in meshes])
    eye = plate.to_plate(camera.position[None])[0]
    zone = plate.zone or zone_around(plate, camera, obj.holo.zone_margin * unit)
    h = scene.holo
    p = plan(
        (plate.width, plate.height),
        [local.min(0), local.max(0)],
        zone=zone,
        pixel_angle=zone.pixel or camera.pixel_angle(),
        wavelength=h.wavelength * unit if h.wavelength > 0 else None,
        seen=seen_area(meshes, zone.centre),
    )
    choice = choose(
        p,
        resolution=camera.resolution,
        looks=h.iterations,
        supersample=h.supersample,
        budget=budget(h),
    )
    p = replace(p, looks=choice.looks)
    v = plan_view(
        p,
        position=eye,
        pixel_angle=camera.pixel_angle(),
        pupil=camera.aperture_diameter,
        resolution=camera.resolution,
    )
    lens = (
        f"{camera.lens:g} mm f/{camera.fstop:g}"
        if camera.fstop
        else f"a {camera.lens:g} mm pinhole"
    )
    options = worker_options()  # the estimate of this machine for the worker's device and cache
    lines = summary(
        p,
        v,
        lens=lens,
        resolution=camera.resolution,
        plate_size=(plate.width, plate.height),
        camera=eye,
        device=options["device"],
        cache_dir=options["cache_dir"],
    )
    lines[1:1] = quality_lines(choice)
    gb = 2.0**30
    try:  # as the recording's plan decides: tile by tile where the looks exceed the memory
        tiled = p.check_recording(memory=h.plate_memory * gb, disk=h.plate_disk * gb, tiled=None)
    except InputError as e:
        lines.insert(1, f"refused     {e}")
    else:
        if tiled:
            lines.insert(
                1,
                "tiles       the looks exceed the memory in one piece: they are "
                "recorded tile by tile, into a store beside each file",
            )
    return lines


class HOLO_OT_plan_plate(bpy.types.Operator):
    """State what the plate will take and give before recording it: whether its views are sharp, its samples, wavelength, disk, memory and time, and what the scene camera's view of it reads"""

    bl_idname = "holo.plan_plate"
    bl_label = "Plan Plate"

    @classmethod
    def poll(cls, context):
        return HOLO_OT_fit_zone.poll(context)

    def execute(self, context):
        obj = plate_object(context)
        try:
            lines = plan_summary(context)
        except (ExportError, ValueError) as e:
            session.plans[obj.name] = [str(e)]
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        session.plans[obj.name] = lines
        for line in lines:
            self.report({"WARNING"} if line.startswith("refused") else {"INFO"}, line)
        return {"FINISHED"}


def plan_lines(obj) -> list[str]:
    return session.plans.get(obj.name, [])


def _number(value) -> str:
    """A number as the command line reads it, exactly, in positional notation: argparse takes
    '-1.9e-08' for an option, never for a negative number (and NumPy 2's repr of its scalars
    is ``np.float64(...)``)."""
    return np.format_float_positional(float(value), unique=True, trim="-")


_PITCH_UNITS = [
    ("UM", "µm", "Micrometres (cameras, SLMs, scanned film)", 1e-6),
    ("NM", "nm", "Nanometres (electron and X-ray holograms)", 1e-9),
    ("MM", "mm", "Millimetres (antenna arrays)", 1e-3),
]
_WAVE_UNITS = [
    ("NM", "nm", "Nanometres (light, X-rays)", 1e-9),
    ("PM", "pm", "Picometres (electrons)", 1e-12),
    ("UM", "µm", "Micrometres (infrared)", 1e-6),
    ("KV", "kV", "An electron microscope's accelerating voltage", None),
]
_RADIUS_UNITS = [
    (
        "carrier",
        "Fraction of Carrier",
        (
            "A fraction of the carrier's frequency "
            "(1/3: weak phase objects, 0.5: holospy's "
            "for strong ones)"
        ),
    ),
    ("1/mm", "Cycles per mm", "Spatial frequency [1/mm]"),
    ("mrad", "mrad", "The scattering angle [mrad]"),
]


_PITCH_FACTOR = {key: factor for key, *_, factor in _PITCH_UNITS}
_WAVE_FACTOR = {key: factor for key, *_, factor in _WAVE_UNITS}


def _items(units):
    return [(key, name, text) for key, name, text, *_ in units]


class HOLO_OT_import_hologram(bpy.types.Operator, ImportHelper):
    """Import a hologram as a plate: a file recorded by Holo, placed where its metadata puts it, or an acquired one (a scan, a lab array, or a complex EXR of channels re and im) with its pitch, wavelength and distance: its carrier found, its object wave filtered out and placed at that distance"""

    bl_idname = "holo.import_hologram"
    bl_label = "Import Hologram"
    bl_options = {"REGISTER", "UNDO"}
    filename_ext = ".exr"
    filter_glob: bpy.props.StringProperty(
        default="*.exr;*.png;*.tif;*.tiff;*.npy;*.h5;*.hdf5;*.mat", options={"HIDDEN"}
    )
    pitch: bpy.props.FloatProperty(
        name="Pitch",
        default=3.45,
        min=1e-6,
        max=1e6,
        description="An acquired hologram's sample spacing, in the unit beside it",
    )
    pitch_unit: bpy.props.EnumProperty(name="Pitch Unit", items=_items(_PITCH_UNITS), default="UM")
    wavelength: bpy.props.FloatProperty(
        name="Wavelength",
        default=633.0,
        min=1e-6,
        max=1e7,
        description="An acquired hologram's wavelength, in the "
        "unit beside it (kV: electrons of that "
        "accelerating voltage)",
    )
    wavelength_unit: bpy.props.EnumProperty(
        name="Wavelength Unit", items=_items(_WAVE_UNITS), default="NM"
    )
    distance: bpy.props.FloatProperty(
        name="Distance",
        default=0.05,
        min=1e-9,
        soft_max=10.0,
        subtype="DISTANCE",
        unit="LENGTH",
        description="How far behind an acquired hologram its objects lie",
    )
    carrier: bpy.props.EnumProperty(
        name="Carrier",
        default="FIND",
        items=[
            (
                "FIND",
                "Find in Spectrum",
                (
                    "The +1 order's carrier found in the hologram's "
                    "spectrum (the file's reference angle, if it "
                    "states one)"
                ),
            ),
            ("GIVEN", "Reference Angle", "The reference's angle and azimuth given here"),
        ],
    )
    sideband: bpy.props.EnumProperty(
        name="Sideband",
        default="AUTO",
        items=[
            ("AUTO", "Auto", "The order that comes into focus at the distance"),
            ("LOWER", "Lower", "holospy's 'lower': the carrier with f_y > 0"),
            ("UPPER", "Upper", "holospy's 'upper': the carrier with f_y < 0"),
        ],
    )
    reference_angle: bpy.props.FloatProperty(
        name="Reference Angle",
        default=0.05,
        min=0.0,
        max=1.5,
        subtype="ANGLE",
        description="The off-axis reference's angle to the hologram's normal",
    )
    reference_azimuth: bpy.props.FloatProperty(
        name="Azimuth",
        default=0.0,
        subtype="ANGLE",
        description="The reference's direction in the hologram's plane, from +x to +y",
    )
    radius: bpy.props.FloatProperty(
        name="Filter Radius",
        default=1 / 3,
        min=1e-6,
        description="The sideband filter's radius, in its unit",
    )
    radius_unit: bpy.props.EnumProperty(name="Radius Unit", items=_RADIUS_UNITS, default="carrier")
    edge: bpy.props.EnumProperty(
        name="Filter Edge",
        default="HARD",
        items=[
            ("HARD", "Hard", "A hard-edged aperture"),
            ("TANH", "Smooth (tanh)", "holospy's smooth edge"),
            ("COSINE", "Raised Cosine", "A raised-cosine (Tukey) edge"),
        ],
    )
    edge_width: bpy.props.FloatProperty(
        name="Edge Width",
        default=0.05,
        min=1e-3,
        max=1.0,
        description="The edge's width, a fraction of the radius",
    )
    window: bpy.props.EnumProperty(
        name="Apodisation",
        default="NONE",
        items=[
            (k.upper(), k.capitalize(), f"A {k} window across the filter")
            for k in ("none", "hann", "hamming", "blackman", "gaussian", "butterworth")
        ],
    )
    add_camera: bpy.props.BoolProperty(
        name="Add Camera",
        default=True,
        description="Add a camera that frames the plate, focused "
        "at the distance, as the scene's camera",
    )

    def draw(self, context):
        layout = self.layout
        for prop, unit in (("pitch", "pitch_unit"), ("wavelength", "wavelength_unit")):
            row = layout.row(align=True)
            row.prop(self, prop)
            row.prop(self, unit, text="")
        layout.prop(self, "distance")
        layout.prop(self, "carrier")
        if self.carrier == "GIVEN":
            layout.prop(self, "reference_angle")
            layout.prop(self, "reference_azimuth")
        else:
            layout.prop(self, "sideband")
        row = layout.row(align=True)
        row.prop(self, "radius")
        row.prop(self, "radius_unit", text="")
        layout.prop(self, "edge")
        if self.edge != "HARD":
            layout.prop(self, "edge_width")
        layout.prop(self, "window")
        layout.prop(self, "add_camera")

    def import_options(self, context) -> list[str]:
        """The dialog's optics and filter as ``python -m holo_core import`` options, lengths
        in metres (the scene's unit applied to the distance)."""
        if self.wavelength_unit == "KV":
            wavelength = f"{_number(self.wavelength)}kV"
        else:
            wavelength = f"{_number(self.wavelength * _WAVE_FACTOR[self.wavelength_unit])}m"
        options = [
            "--pitch",
            f"{_number(self.pitch * _PITCH_FACTOR[self.pitch_unit])}m",
            "--wavelength",
            wavelength,
            "--distance",
            f"{_number(self.distance * scale(context.scene))}m",
            "--radius",
            _number(self.radius),
            "--radius-unit",
            self.radius_unit,
            "--edge",
            self.edge.lower(),
            "--edge-width",
            _number(self.edge_width),
            "--window",
            self.window.lower(),
        ]
        if self.carrier == "GIVEN":
            return options + [
                "--reference-angle",
                _number(self.reference_angle),
                "--reference-azimuth",
                _number(self.reference_azimuth),
            ]
        return options + ["--sideband", self.sideband.lower()]

    def execute(self, context):
        path = Path(self.filepath)
        try:
            hologram, written, lines = imported(path, self.import_options(context))
        except (HologramFileError, ValueError, OSError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        for line in lines:
            self.report({"INFO"}, line)
        obj = add_plate(context, hologram, written or path)
        if self.add_camera and stated_plane(hologram) is not None:
            add_camera(context, hologram)
        self.report({"INFO"}, f"plate '{obj.name}' from {path}: {hologram!r}")
        return {"FINISHED"}


def imported(path: Path, options: list[str]):
    """(the hologram of ``path``, the Holo file written for it or None, the lines to report):
    a Holo hologram file as it is; else an acquired one (a scan, a lab array, a complex EXR of
    channels re and im) through ``python -m holo_core import`` with ``options`` in a child
    process (the sideband filter and the carrier's search use the core's OpenCL stages, which
    never run in Blender's process), written beside it as ``<name>_holo.exr``."""
    try:
        return read_hologram(path), None, []
    except HologramFileError as e:
        if "without hologram metadata" not in str(e) and path.suffix.lower() == ".exr":
            raise
    out = path.with_name(f"{path.stem}_holo.exr")
    command = [
        sys.executable,
        "-m",
        "holo_core",
        "import",
        str(path),
        "-o",
        str(out),
        "--no-view",
        *options,
    ]
    r = subprocess.run(
        command,
        capture_output=True,
        text=True,
        timeout=1800,
        check=False,
        env=environment(runtime_paths(), device() or None),
    )
    if r.returncode != 0:
        raise HologramFileError((r.stderr.strip().splitlines() or [f"{path}: import failed"])[-1])
    lines = [line for line in r.stdout.strip().splitlines() if line.strip()]
    return read_hologram(out), out, lines[:-1]


def add_camera(context, hologram: Hologram):
    """A camera that frames the plate and is focused on its objects' plane
    (:func:`holo_core.acquired.framing.default_camera`), as the scene's camera; the render's
    size is the camera's."""
    camera = default_camera(hologram)
    unit = scale(context.scene)
    data = bpy.data.cameras.new("Hologram Camera")
    # Blender's millimetres are thousandths of a scene unit, as camera_from_object reads them
    data.lens, data.sensor_width = camera.lens / unit, camera.sensor_width / unit
    data.sensor_fit = "AUTO"
    data.dof.use_dof = True
    data.dof.focus_distance = camera.focus_distance / unit
    data.dof.aperture_fstop = camera.fstop
    data.clip_end = max(data.clip_end, 4 * camera.focus_distance / unit)
    obj = bpy.data.objects.new("Hologram Camera", data)
    context.collection.objects.link(obj)
    m = np.array(camera.matrix_world, np.float64)
    m[:3, 3] /= unit
    obj.matrix_world = Matrix(m.tolist())
    scene = context.scene
    scene.camera = obj
    scene.render.resolution_x, scene.render.resolution_y = camera.resolution
    scene.render.resolution_percentage = 100
    return obj


def add_plate(context, hologram: Hologram, path: Path):
    """A plane of the hologram's size at its plate's pose (Blender units), marked as the
    scene's plate, linked to ``path`` and never recorded; the scene turns to Plate mode."""
    unit = scale(context.scene)
    w, h = hologram.size
    mesh = bpy.data.meshes.new(path.stem)
    mesh.from_pydata(
        [
            (-w / 2 / unit, -h / 2 / unit, 0),
            (w / 2 / unit, -h / 2 / unit, 0),
            (w / 2 / unit, h / 2 / unit, 0),
            (-w / 2 / unit, h / 2 / unit, 0),
        ],
        [],
        [(0, 1, 2, 3)],
    )
    obj = bpy.data.objects.new(path.stem, mesh)
    context.collection.objects.link(obj)
    m = np.array(hologram.plate, np.float64)
    m[:3, 3] /= unit
    obj.matrix_world = Matrix(m.tolist())
    for other in context.scene.objects:
        if other is not obj and other.holo.is_plate:
            other.holo.is_plate = False  # one plate per scene: the imported one
    obj.holo.is_plate = True
    obj.holo.imported = True
    raster_visibility(obj)  # the window its objects are seen through: a hole the pass fills
    obj.holo.hologram = bpy.path.relpath(str(path)) if bpy.data.filepath else str(path)
    if hologram.zone is not None:
        obj.holo.zone_centre, obj.holo.zone_half = hologram.zone.centre, hologram.zone.half_extents
        obj.holo.zone_pupil, obj.holo.zone_pixel = hologram.zone.pupil, hologram.zone.pixel
        obj.holo.zone_set = True
    context.scene.holo.mode = "PLATE"
    return obj


def _menu(menu, _context):
    menu.layout.operator(HOLO_OT_import_hologram.bl_idname, text="Hologram (.exr, scan, lab array)")


CLASSES = (HOLO_OT_fit_zone, HOLO_OT_fit_zone_to_shot, HOLO_OT_plan_plate, HOLO_OT_import_hologram)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.TOPBAR_MT_file_import.append(_menu)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(_menu)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
