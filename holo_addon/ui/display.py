"""The holographic display as a scene asset: its panel's lines (the display, its scale and
its diffraction angle) and Export Display Frame (the current frame's patterns, layout and
focal stack, as Render Animation writes each frame's).
"""

from __future__ import annotations

import math

import bpy

from holo_core import jobs
from holo_core.worker import WorkerError

from ..compositor import handlers
from ..export.display import display_from_object, scene_display
from ..export.scene import ExportError, NoEmitters

USER_ERRORS = (ExportError, NoEmitters, ValueError, OSError, WorkerError)


def display_object(context):
    obj = context.object
    return obj if obj is not None and obj.type == "MESH" and obj.holo.is_display else None


def lines(obj) -> list[str]:
    """What the display is, in the panel: its size, its volume as the scene sees it, and
    the angle its samples diffract the shortest wavelength to."""
    try:
        spec = display_from_object(obj)
    except ExportError as e:
        return [str(e)]
    w, h = spec.size
    lam = min(laser.wavelength for laser in spec.lasers)
    angle = math.degrees(math.asin(min(1.0, spec.sin_diffraction(lam))))
    return [
        f"{spec.resolution[0]} x {spec.resolution[1]} at {spec.pitch * 1e6:.3g} µm: "
        f"{w * 1e3:.3g} x {h * 1e3:.3g} mm, {spec.bit_depth}-bit",
        f"scene: {w / spec.scale:.3g} x {h / spec.scale:.3g} m, "
        f"{spec.behind / spec.scale:.3g} m behind, {spec.front / spec.scale:.3g} m in front",
        f"diffraction: ±{angle:.3g}° at {lam * 1e9:.4g} nm; eye box "
        f"{spec.eye_box * 1e3:.3g} mm at {spec.eye_distance * 1e3:.4g} mm",
    ]


def draw_display(layout, context, obj) -> None:
    d = obj.holo.display
    layout.prop(d, "preset")
    if d.preset == "CUSTOM":
        layout.prop(d, "resolution")
        layout.prop(d, "pitch")
        layout.prop(d, "bit_depth")
    layout.prop(d, "pattern_format")
    layout.prop(d, "phase_range")
    layout.prop(d, "inverted")
    col = layout.column(heading="Lasers")
    for i, name in enumerate(("Red", "Green", "Blue")):
        row = col.row(align=True)
        row.prop(d, "colours", index=i, text=name)
        row.prop(d, "wavelengths", index=i, text="nm")
        row.prop(d, "powers", index=i, text="mW")
    col = layout.column(heading="Volume")
    col.prop(d, "scene_scale")
    col.prop(d, "behind")
    col.prop(d, "front")
    col = layout.column(heading="Eye Box")
    col.prop(d, "eye_distance")
    col.prop(d, "eye_box")
    col.prop(d, "pupil")
    col = layout.column(heading="Phase Tables")
    for name in ("table_red", "table_green", "table_blue"):
        col.prop(d, name)
    layout.prop(d, "phases")
    layout.prop(d, "method")
    if d.method != "double-phase":
        layout.prop(d, "iterations")
    layout.prop(d, "slices")
    col = layout.column(align=True)
    for line in lines(obj):
        col.label(text=line)
    layout.operator(HOLO_OT_export_display.bl_idname, icon="RENDER_STILL")


class HOLO_OT_export_display(bpy.types.Operator):
    """Write the current frame's patterns (one per laser, as the SLM's driver takes them), their layout and the focal stack the display will show, with each slice's PSNR and SSIM against the unencoded wave's; the stack's contact sheet opens in the Image Editor"""

    bl_idname = "holo.export_display"
    bl_label = "Export Display Frame"

    @classmethod
    def poll(cls, context):
        if context.scene is None or scene_display(context.scene) is None:
            cls.poll_message_set("Mark a plane as a Holographic Display (Object ▸ Holo)")
            return False
        return True

    def execute(self, context):
        scene = context.scene
        obj = scene_display(scene)
        try:
            result = handlers.display_frame(
                scene, context.evaluated_depsgraph_get(), obj, progress=lambda _f: None
            )
        except jobs.Cancelled:
            self.report({"WARNING"}, "the display frame was cancelled: nothing was written")
            return {"CANCELLED"}
        except USER_ERRORS as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, handlers.display.summary(obj.name, result))
        return {"FINISHED"}


CLASSES = (HOLO_OT_export_display,)
register, unregister = bpy.utils.register_classes_factory(CLASSES)
