"""The viewport overlay of the plate's coverage (Plate mode): the lines of sight from the
scene camera through the plate's four corners, out to the farthest holographic object, and
the plate's outline; green when the plate covers every holographic object the camera looks at
through it, orange when it covers part (the rest is cut from the pass), red when none. The
plate's viewing zone is drawn as its box, in blue; a plate made a set of parts along the
camera's path (Fit Zone to Shot) draws each part's outline in violet and its zone in blue.

The objects are judged by their bounding boxes' corners, so the overlay is quick to update on
every change; recording checks the surfaces themselves
(:func:`holo_addon.export.plates.plate_coverage`).
Lines are computed when the scene changes (a depsgraph update, a frame change) and drawn from
that cache, in Blender units in world space.
"""

from __future__ import annotations

from dataclasses import dataclass

import bpy
import numpy as np
from bpy.app.handlers import persistent

from ..export.plates import plate_from_object, plate_parts, through_plate
from ..export.scene import ExportError, emitter_instances

COLOURS = {"ALL": (0.3, 0.9, 0.4, 0.9), "PART": (1.0, 0.6, 0.1, 0.9), "NONE": (1.0, 0.25, 0.2, 0.9)}
ZONE_COLOUR = (0.3, 0.75, 1.0, 0.9)
PART_COLOUR = (0.7, 0.45, 1.0, 0.9)
CORNERS = np.array([(-1, -1), (1, -1), (1, 1), (-1, 1)]) / 2  # around the plate, in its sizes


@dataclass(frozen=True)
class Coverage:
    """``lines`` (2K, 3) the segments' end points in world Blender units; ``state`` "ALL",
    "PART" or "NONE" (of the emitters' bounding-box corners in view behind the plate)."""

    lines: np.ndarray
    state: str
    zone: np.ndarray | None = None  # the viewing zone's box edges (24, 3), world units
    parts: np.ndarray | None = None  # a set's parts' outlines (8P, 3), world units


def coverage(scene, depsgraph) -> Coverage | None:
    """What the overlay draws for ``scene`` as ``depsgraph`` evaluates it; None outside Plate
    mode, or without one plate and a camera."""
    plates = [o for o in scene.objects if o.holo.is_plate]
    if scene.holo.mode != "PLATE" or len(plates) != 1 or scene.camera is None:
        return None
    try:
        plate = plate_from_object(plates[0].evaluated_get(depsgraph), 1.0)  # Blender units
    except ExportError:
        return None
    eye = np.array(scene.camera.evaluated_get(depsgraph).matrix_world.translation)
    m = plate.matrix_world
    corners = (CORNERS * (plate.width, plate.height)) @ m[:3, :2].T + m[:3, 3]
    outline = np.stack([corners, np.roll(corners, -1, 0)], 1).reshape(-1, 3)
    eye_z = plate.to_plate(eye[None])[0, 2]
    boxes = _emitter_boxes(depsgraph)
    unit = scene.unit_settings.scale_length or 1.0
    zone = zone_edges(plate, unit)
    try:
        parts = plate_parts(plates[0])
    except ExportError:
        parts = None
    edges = None
    if parts:  # the set replaces the plate object: its parts and their zones are drawn
        edges = part_edges(parts, unit)
        zone = np.concatenate([part_zone_edges(part, unit) for part in parts])
    if eye_z <= 0 or not len(boxes):  # a camera behind the plate sees nothing through it
        return Coverage(outline, "NONE" if eye_z <= 0 else "ALL", zone, edges)
    inside, _ = through_plate(plate, eye, boxes)
    state = "ALL" if inside.all() else "PART" if inside.any() else "NONE"
    depth = plate.to_plate(boxes)[:, 2]
    reach = (eye_z - min(depth.min(), -eye_z)) / eye_z  # to the farthest object, or as far again
    far = eye + reach * (corners - eye)
    sight = np.stack([np.broadcast_to(eye, far.shape), far], 1).reshape(-1, 3)
    end = np.stack([far, np.roll(far, -1, 0)], 1).reshape(-1, 3)
    return Coverage(np.concatenate([outline, sight, end]), state, zone, edges)


def part_edges(parts, unit: float) -> np.ndarray:
    """The outlines of a set's parts (PathPart, metres) as segments (8P, 3), world Blender
    units (``unit`` metres per Blender unit)."""
    lines = []
    for part in parts:
        p, m = part.plate, part.plate.matrix_world
        corners = ((CORNERS * (p.width, p.height)) @ m[:3, :2].T + m[:3, 3]) / unit
        lines.append(np.stack([corners, np.roll(corners, -1, 0)], 1).reshape(-1, 3))
    return np.concatenate(lines)


def part_zone_edges(part, unit: float) -> np.ndarray:
    """A part's viewing zone (metres, its plate's frame) as its box's 12 edges (24, 3), world
    Blender units."""
    corners = part.plate.zone.corners()
    edges = [(a, b) for a in range(8) for b in range(a + 1, 8) if (a ^ b).bit_count() == 1]
    m = part.plate.matrix_world
    world = (corners @ m[:3, :3].T + m[:3, 3]) / unit
    return world[np.array(edges).ravel()]


def zone_edges(plate, unit: float) -> np.ndarray | None:
    """The plate's viewing zone (metres, the plate's frame) as the 12 edges of its box, in
    world Blender units (``plate`` in Blender units; ``unit`` metres per Blender unit)."""
    if plate.zone is None:
        return None
    corners = plate.zone.corners() / unit  # x, y, z each over (-1, 1): index 4x + 2y + z
    edges = [(a, b) for a in range(8) for b in range(a + 1, 8) if (a ^ b).bit_count() == 1]
    m = plate.matrix_world
    world = corners @ m[:3, :3].T + m[:3, 3]
    return world[np.array(edges).ravel()]


def _emitter_boxes(depsgraph) -> np.ndarray:
    """The bounding-box corners (N, 3) of every holographic emitter the render draws, world
    units."""
    boxes = []
    for inst, _ in emitter_instances(depsgraph):
        m = np.array(inst.matrix_world)
        boxes.append(np.array(inst.object.bound_box) @ m[:3, :3].T + m[:3, 3])
    return np.concatenate(boxes) if boxes else np.empty((0, 3))


_cache: dict = {}  # scene name → Coverage or None


@persistent
def _update(scene, depsgraph=None):
    if depsgraph is not None and depsgraph.mode == "VIEWPORT":
        _cache[scene.name] = coverage(scene, depsgraph) if scene.holo.show_coverage else None


def refresh(context) -> None:
    """The overlay turned on or off (Scene.holo.show_coverage)."""
    if _handle:
        _update(context.scene, context.evaluated_depsgraph_get())


@persistent
def _forget(*_):
    _cache.clear()


def _draw():
    context = bpy.context
    found = _cache.get(context.scene.name)
    if found is None or not (
        context.scene.holo.show_coverage and context.space_data.overlay.show_overlays
    ):
        return
    import gpu
    from gpu_extras.batch import batch_for_shader

    shader = gpu.shader.from_builtin("POLYLINE_UNIFORM_COLOR")
    batch = batch_for_shader(shader, "LINES", {"pos": found.lines.tolist()})
    shader.uniform_float("viewportSize", [float(n) for n in gpu.state.viewport_get()[2:]])
    shader.uniform_float("lineWidth", 2.0)
    shader.uniform_float("color", COLOURS[found.state])
    gpu.state.blend_set("ALPHA")
    batch.draw(shader)
    if found.zone is not None:
        shader.uniform_float("color", ZONE_COLOUR)
        batch_for_shader(shader, "LINES", {"pos": found.zone.tolist()}).draw(shader)
    if found.parts is not None:
        shader.uniform_float("color", PART_COLOUR)
        batch_for_shader(shader, "LINES", {"pos": found.parts.tolist()}).draw(shader)
    gpu.state.blend_set("NONE")


def _toggle(panel, context):
    """In the viewport's Overlays popover, under Guides."""
    panel.layout.prop(context.scene.holo, "show_coverage", text="Holo Plate Coverage")


def attach(handlers, draw, kind: str, drawn: list) -> bool:
    """In the interface (a background Blender draws nothing): the app ``handlers`` ((name,
    function), ...) and ``draw`` in every 3D view's window region at ``kind`` (POST_VIEW,
    POST_PIXEL), its handle kept in ``drawn``. Returns whether it attached them."""
    if bpy.app.background:
        return False
    for name, fn in handlers:
        getattr(bpy.app.handlers, name).append(fn)
    drawn.append(bpy.types.SpaceView3D.draw_handler_add(draw, (), "WINDOW", kind))
    return True


def detach(handlers, drawn: list) -> bool:
    """Undo :func:`attach`; returns whether there was anything attached."""
    if not drawn:
        return False
    bpy.types.SpaceView3D.draw_handler_remove(drawn.pop(), "WINDOW")
    for name, fn in handlers:
        found = getattr(bpy.app.handlers, name)
        if fn in found:
            found.remove(fn)
    return True


HANDLERS = (
    ("depsgraph_update_post", _update),
    ("frame_change_post", _update),
    ("load_post", _forget),
)
_handle = []


def register():
    if attach(HANDLERS, _draw, "POST_VIEW", _handle):
        bpy.types.VIEW3D_PT_overlay_guides.append(_toggle)


def unregister():
    if detach(HANDLERS, _handle):
        bpy.types.VIEW3D_PT_overlay_guides.remove(_toggle)
    _cache.clear()
