"""Panels in the Properties editor: Render ▸ Holo (settings and actions), Object ▸ Holo."""

from __future__ import annotations

import bpy

from ..compositor.session import session
from ..compositor.tree import uses_pass
from . import display, live, plates, preview


class HOLO_PT_scene(bpy.types.Panel):
    bl_label = "Holo"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"

    def draw(self, context):
        h = context.scene.holo
        layout = self.layout
        layout.use_property_split = True
        layout.prop(h, "output_dir")
        layout.prop(h, "mode")
        layout.prop(h, "lighting")
        if h.lighting == "SCENE":
            layout.prop(h, "lighting_samples")
        col = layout.column(heading="Recording")
        if h.mode == "CAMERA":
            col.prop(h, "speckle")
            if h.speckle == "LOOKS":
                col.prop(h, "samples")
        else:
            col.prop(h, "plate_memory")
            col.prop(h, "plate_disk")
            col.prop(h, "outside_zone")
            col.prop(h, "wavelength")
            col.prop(h, "iterations")
        col.prop(h, "seed")
        col = layout.column(heading="Image")
        col.prop(h, "supersample")
        col.prop(h, "exposure")
        if h.mode == "PLATE":
            col.prop(h, "composition")
            col.prop(h, "opacity_threshold")
            layout.prop(h, "show_coverage")
            draw_live(layout, context)
        if h.mode == "CAMERA":
            layout.prop(h, "preview")
            shown = preview.state()
            if h.preview and shown.latency is not None:
                layout.label(
                    text=f"Preview: {shown.latency:.1f} s from the change to the picture",
                    icon="HIDE_OFF",
                )
        layout.prop(h, "pass_on_render")
        running, warnings = session.running, session.warnings
        if running.frame is not None:  # a render is making its pass
            box = layout.box()
            box.label(text=f"Pass of frame {running.frame}: {running.fraction:.0%}", icon="TIME")
            box.operator("holo.cancel_pass", icon="CANCEL")
        if warnings["texts"]:  # of the latest pass a render made
            box = layout.box()
            box.label(text=f"Pass of frame {warnings['frame']}:", icon="ERROR")
            for text in warnings["texts"][-3:]:
                box.label(text=text)
        col = layout.column(align=True)
        if h.mode == "PLATE":  # camera holograms are recorded with each pass
            col.operator("holo.record_hologram", icon="REC")
        col.operator("holo.render_pass", icon="RENDER_STILL")
        col.operator("holo.setup_compositing", icon="NODE_COMPOSITING")
        if uses_pass(context.scene):
            col.operator("holo.remove_compositing", icon="X")
        col.operator("holo.render", icon="RENDER_RESULT")


class HOLO_PT_object(bpy.types.Panel):
    bl_label = "Holo"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        return context.object is not None and context.object.type == "MESH"

    def draw(self, context):
        """The emitter; the plate's controls in Plate mode only (a plate marked in Plate mode
        says, in Camera mode, that it waits for Plate mode)."""
        h = context.object.holo
        layout = self.layout
        layout.use_property_split = True
        if not h.is_plate:
            layout.prop(h, "is_display")
            if h.is_display:
                display.draw_display(layout, context, context.object)
                return
        if context.scene.holo.mode == "PLATE":
            layout.prop(h, "is_plate")
            if h.is_plate:
                draw_plate(layout, context, h)
                return
        elif h.is_plate:
            layout.label(text="Hologram plate (used in Plate mode)")
            return
        layout.prop(h, "emitter")


def draw_live(layout, context) -> None:
    """Live Plate View, its resolution and what it does now."""
    h = context.scene.holo
    row = layout.row(heading="Viewport")
    row.prop(h, "live_plate")
    if h.live_plate:
        layout.prop(h, "live_pixels")
        said = live.words(context.scene)
        if said:
            layout.label(text=said, icon="HIDE_OFF")


def draw_plate(layout, context, h) -> None:
    """The plate's hologram, its viewing zone and the planner's lines."""
    imported = " (imported: viewed as it is)" if h.imported else ""
    layout.label(text=f"Hologram: {h.hologram or 'not recorded yet'}{imported}")
    draw_live(layout, context)
    if h.imported:
        return
    layout.prop(h, "zone_margin")
    layout.prop(h, "part_length")
    if h.parts:
        layout.label(
            text=f"A set of {plates.part_count(h)} parts along the camera's path "
            f"(Fit Zone to Shot): each frame renders from the part that holds "
            f"its camera"
        )
    elif h.zone_set:
        (x, y, z), (hx, hy, hz) = h.zone_centre, h.zone_half
        layout.label(
            text=f"Viewing zone: ({x:.3g}, {y:.3g}, {z:.3g}) m "
            f"±({hx:.3g}, {hy:.3g}, {hz:.3g}) m, plate's frame"
        )
    else:
        layout.label(text="Viewing zone: set around the camera when recorded")
    row = layout.row(align=True)
    row.operator("holo.fit_zone", icon="CAMERA_DATA")
    row.operator("holo.fit_zone_to_shot", icon="RENDER_ANIMATION")
    row.operator("holo.plan_plate", icon="INFO")
    col = layout.column(align=True)
    for line in plates.plan_lines(context.object):
        col.label(text=line)


CLASSES = (HOLO_PT_scene, HOLO_PT_object)

register, unregister = bpy.utils.register_classes_factory(CLASSES)
