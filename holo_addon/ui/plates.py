"""The plate as a scene asset: its viewing zone (Fit Zone to Camera), the planner (Plan Plate:
what a plate will take and give before any recording) and File ▸ Import ▸ Hologram.

The planner runs ``python -m holo_core plan`` in a child process, as the worker runs (no
OpenCL, nor the core's physics, in Blender's process), and its lines are shown in the
plate's panel. An imported hologram becomes a plate object placed where its metadata puts it,
linked to its file (kept, relative to the .blend, when the .blend is saved) and viewed as it
is: it is never recorded.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import bpy
import numpy as np
from bpy_extras.io_utils import ImportHelper
from mathutils import Matrix

from holo_core.acquired import import_acquired
from holo_core.io.hologram import HologramFileError, read_hologram, write_hologram
from holo_core.io.image import read_exr
from holo_core.scene.hologram import Hologram
from holo_core.worker import environment

from ..compositor.session import session
from ..export.plates import plate_from_object, zone_around
from ..export.scene import ExportError, camera_from_object, emitter_instances, scale
from ..render.options import device, runtime_paths


def plate_object(context):
    obj = context.object
    return obj if obj is not None and obj.type == "MESH" and obj.holo.is_plate else None


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
        obj.holo.zone_centre, obj.holo.zone_half = zone.centre, zone.half_extents
        obj.holo.zone_pupil, obj.holo.zone_pixel = zone.pupil, zone.pixel
        obj.holo.zone_set = True
        self.report({"INFO"}, f"plate '{obj.name}': viewing zone {zone.describe()}")
        return {"FINISHED"}


def plan_command(context) -> list[str]:
    """``python -m holo_core plan`` for the selected plate, the holographic objects, the
    scene camera and Max Hologram Size, all in the plate's frame."""
    scene, obj, unit = context.scene, plate_object(context), scale(context.scene)
    plate = plate_from_object(obj, unit)
    camera = camera_from_object(scene, scene.camera, unit)
    corners = []
    for inst, _ in emitter_instances(context.evaluated_depsgraph_get()):
        m = np.array(inst.matrix_world)
        corners.append(np.array(inst.object.bound_box) @ m[:3, :3].T + m[:3, 3])
    if not corners:
        raise ExportError("no holographic emitters to plan for")
    local = plate.to_plate(np.concatenate(corners) * unit)
    eye = plate.to_plate(camera.position[None])[0]
    look = plate.to_plate((camera.position - camera.rotation[:, 2])[None])[0]
    zone = plate.zone or zone_around(plate, camera, obj.holo.zone_margin * unit)
    command = [sys.executable, "-m", "holo_core", "plan",
               "--bounds", *map(_number, local.min(0)), *map(_number, local.max(0)),
               "--plate-size", _number(plate.width), _number(plate.height),
               "--camera", *map(_number, eye), "--look-at", *map(_number, look),
               "--lens", _number(camera.lens), "--sensor-width", _number(camera.sensor_width),
               "--resolution", *map(str, camera.resolution),
               "--zone", *map(_number, zone.centre), *map(_number, zone.half_extents)]
    command += ["--fstop", _number(camera.fstop), "--focus-distance",
                _number(camera.focus_distance)] if camera.fstop else ["--pinhole"]
    return command


def _number(value) -> str:
    """A number as the command line reads it, exactly, in positional notation: argparse takes
    '-1.9e-08' for an option, never for a negative number (and NumPy 2's repr of its scalars
    is ``np.float64(...)``)."""
    return np.format_float_positional(float(value), unique=True, trim="-")


class HOLO_OT_plan_plate(bpy.types.Operator):
    """State what the plate will take and give before recording it: its samples, wavelength, memory and time, and what the scene camera's view of it resolves"""

    bl_idname = "holo.plan_plate"
    bl_label = "Plan Plate"

    @classmethod
    def poll(cls, context):
        return HOLO_OT_fit_zone.poll(context)

    def execute(self, context):
        obj = plate_object(context)
        try:
            command = plan_command(context)
        except (ExportError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        r = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False,
                           env=environment(runtime_paths(), device() or None))
        lines = (r.stdout if r.returncode == 0 else r.stderr).strip().splitlines()
        session.plans[obj.name] = lines
        for line in lines:
            self.report({"INFO"} if r.returncode == 0 else {"ERROR"}, line)
        return {"FINISHED"} if r.returncode == 0 else {"CANCELLED"}


def plan_lines(obj) -> list[str]:
    return session.plans.get(obj.name, [])


class HOLO_OT_import_hologram(bpy.types.Operator, ImportHelper):
    """Import a hologram as a plate: a file recorded by Holo, placed where its metadata puts it, or an acquired one (an intensity scan, or a complex EXR of channels re and im) with the pitch, wavelength and distance given here"""

    bl_idname = "holo.import_hologram"
    bl_label = "Import Hologram"
    bl_options = {"REGISTER", "UNDO"}
    filename_ext = ".exr"
    filter_glob: bpy.props.StringProperty(default="*.exr;*.png;*.tif;*.tiff",
                                          options={"HIDDEN"})
    pitch: bpy.props.FloatProperty(name="Pitch [µm]", default=8.0, min=1e-3, max=1e4,
                                   description="An acquired hologram's sample spacing")
    wavelength: bpy.props.FloatProperty(name="Wavelength [nm]", default=633.0, min=1.0,
                                        max=1e7, description="An acquired hologram's "
                                                             "wavelength")
    distance: bpy.props.FloatProperty(name="Distance [m]", default=0.1, min=1e-6,
                                      description="How far behind an acquired hologram its "
                                                  "objects lie")
    reference_angle: bpy.props.FloatProperty(name="Reference Angle", default=0.0, min=0.0,
                                             max=1.5, subtype="ANGLE",
                                             description="An acquired intensity hologram's "
                                                         "off-axis reference angle")

    def execute(self, context):
        path = Path(self.filepath)
        try:
            hologram, acquired = imported(path, pitch=self.pitch * 1e-6,
                                          wavelength=self.wavelength * 1e-9,
                                          distance=self.distance,
                                          reference_angle=self.reference_angle)
        except (HologramFileError, ValueError, OSError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if acquired:  # a Holo file beside it, of the scan and what was said of it here
            path = write_hologram(path.with_name(f"{path.stem}_holo.exr"), hologram)
        obj = add_plate(context, hologram, path)
        self.report({"INFO"}, f"plate '{obj.name}' from {path}: {hologram!r}")
        return {"FINISHED"}


def imported(path: Path, *, pitch, wavelength, distance, reference_angle=0.0):
    """(the hologram of ``path``, whether it was acquired): a Holo hologram file as it is;
    else an acquired one (a complex EXR of channels re, im; else an intensity scan), its
    objects a plate-sized box ``distance`` [m] behind it."""
    try:
        return read_hologram(path), False
    except HologramFileError as e:
        if "without hologram metadata" not in str(e) and path.suffix.lower() == ".exr":
            raise
    channels = read_exr(path, what="hologram")[1] if path.suffix.lower() == ".exr" else {}
    if {"re", "im"} <= set(channels):
        wave = (channels["re"] + 1j * channels["im"]).astype(np.complex64)[None]
        h = Hologram(object_wave=wave, encoding="complex", wavelengths=(wavelength,),
                     pitch=pitch)
    else:
        h = import_acquired(path, pitch=pitch, wavelength=wavelength,
                            reference_angle=reference_angle)
    w, ht = h.size
    bounds = np.array([[-w / 2, -ht / 2, -distance], [w / 2, ht / 2, -distance]])
    return Hologram(**{**{k: getattr(h, k) for k in h.__dataclass_fields__},
                       "bounds": bounds}), True


def add_plate(context, hologram: Hologram, path: Path):
    """A plane of the hologram's size at its plate's pose (Blender units), marked as the
    scene's plate, linked to ``path`` and never recorded; the scene turns to Plate mode."""
    unit = scale(context.scene)
    w, h = hologram.size
    mesh = bpy.data.meshes.new(path.stem)
    mesh.from_pydata([(-w / 2 / unit, -h / 2 / unit, 0), (w / 2 / unit, -h / 2 / unit, 0),
                      (w / 2 / unit, h / 2 / unit, 0), (-w / 2 / unit, h / 2 / unit, 0)], [],
                     [(0, 1, 2, 3)])
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
    obj.holo.hologram = bpy.path.relpath(str(path)) if bpy.data.filepath else str(path)
    if hologram.zone is not None:
        obj.holo.zone_centre, obj.holo.zone_half = hologram.zone.centre, hologram.zone.half_extents
        obj.holo.zone_pupil, obj.holo.zone_pixel = hologram.zone.pupil, hologram.zone.pixel
        obj.holo.zone_set = True
    context.scene.holo.mode = "PLATE"
    return obj


def _menu(menu, _context):
    menu.layout.operator(HOLO_OT_import_hologram.bl_idname, text="Hologram (.exr)")


CLASSES = (HOLO_OT_fit_zone, HOLO_OT_plan_plate, HOLO_OT_import_hologram)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.TOPBAR_MT_file_import.append(_menu)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(_menu)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
