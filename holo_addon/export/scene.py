"""Blender scene → plain data in metres for holo_core (runs on Blender's main thread).

Lengths are Blender units × ``unit_settings.scale_length``. Meshes are exported unindexed
(three vertices per triangle) so that per-corner colours and UVs survive. Colour comes from
the active colour attribute, else the material's image texture on Base Color, else its Base
Color (per triangle, by material slot), else white; all linear.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from holo_core.scene.camera import Camera
from holo_core.scene.mesh import Mesh
from holo_core.scene.plate import Plate, ViewingZone

from ..blender.materials import base_colour, principled, unhonoured
from . import bake


class ExportError(ValueError):
    """The scene cannot be recorded as it is; the message says what to change."""


class NoEmitters(ExportError):
    """No holographic emitter is left in the render (none marked, or none renders): a render
    then shows the raster alone."""


@dataclass(frozen=True, eq=False)
class SceneData:
    """What the pipeline needs, with no reference to Blender: emitter meshes in world metres
    (``points`` and ``triangles`` kinds), the plate, the camera; ``names``: the emitters'
    objects; ``view``: the render's whole frame as a pinhole (the camera of the emitters'
    radiance, before any crop); ``region``: the render region when it is not cropped (left,
    top, right, bottom) [px from the top-left] (the pass is cleared outside it), else None;
    ``unit``: metres per Blender unit; ``zone``: a plate's viewing zone resolved now (not yet
    kept on the plate), else None."""

    points: list
    triangles: list
    plate: Plate | None
    plate_name: str | None
    camera: Camera
    warnings: tuple = ()
    names: tuple = ()
    view: Camera | None = None
    region: tuple | None = None
    unit: float = 1.0
    zone: ViewingZone | None = None


def scale(scene) -> float:
    """Metres per Blender unit."""
    return float(scene.unit_settings.scale_length) or 1.0


def world_matrix(m, unit: float, *, normalise: bool) -> np.ndarray:
    a = np.array(m, np.float64).reshape(4, 4)
    a[:3, 3] *= unit
    if normalise:  # the nearest rotation (polar decomposition): no scale, float32 noise gone
        u, _, vt = np.linalg.svd(a[:3, :3])
        a[:3, :3] = u @ vt
        if np.linalg.det(a[:3, :3]) < 0:
            raise ExportError("a mirrored (negative-scale) camera or plate cannot be used")
    return a


def mesh_from_object(obj, depsgraph, unit: float, matrix=None, notes=None, *, lit=False) -> Mesh:
    """The evaluated mesh of ``obj`` (modifiers applied at the depsgraph's settings) as
    world-space triangles [m]; ``matrix``: an instance's world matrix instead of the object's.
    Material features the export cannot honour are added to ``notes`` (``lit``: the colours
    come from Cycles' radiance, which shows all but transparency)."""
    ev = obj if obj.is_evaluated else obj.evaluated_get(depsgraph)
    me = ev.to_mesh()
    try:
        vertices, loops, lv = _corners(obj, ev, me, unit, matrix)
        nt = len(loops) // 3
        mat_index = np.empty(nt, np.int64)
        me.loop_triangles.foreach_get("material_index", mat_index)
        colours, uvs, texture = _colours(ev, me, loops, lv, mat_index, None if lit else notes)
        if notes is not None:
            notes.extend(
                filter(None, (unhonoured(slot.material, lit=lit) for slot in ev.material_slots))
            )
    finally:
        ev.to_mesh_clear()
    return Mesh(
        vertices=vertices,
        triangles=np.arange(nt * 3).reshape(nt, 3),
        colours=colours,
        uvs=uvs,
        texture=texture,
    )


def _corners(obj, ev, me, unit: float, matrix=None):
    """(the triangles' corners (3T, 3) in world metres, each corner's loop (3T,), each loop's
    vertex) of the evaluated mesh ``me`` of ``ev``; ``matrix``: an instance's world matrix."""
    me.calc_loop_triangles()
    nt = len(me.loop_triangles)
    if nt == 0:
        raise ExportError(f"object '{obj.name}' has no faces to emit from")
    co = np.empty(len(me.vertices) * 3)
    me.vertices.foreach_get("co", co)
    loops = np.empty(nt * 3, np.int64)
    me.loop_triangles.foreach_get("loops", loops)
    lv = np.empty(len(me.loops), np.int64)
    me.loops.foreach_get("vertex_index", lv)
    m = np.array(ev.matrix_world if matrix is None else matrix, np.float64)
    world = co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]
    return world[lv[loops]] * unit, loops, lv


def corner_positions(obj, depsgraph, unit: float, matrix=None) -> np.ndarray:
    """Where the triangles' corners of ``obj`` are now, as :func:`mesh_from_object` exports
    them (world metres, the same order), without their colours."""
    ev = obj if obj.is_evaluated else obj.evaluated_get(depsgraph)
    me = ev.to_mesh()
    try:
        return _corners(obj, ev, me, unit, matrix)[0]
    finally:
        ev.to_mesh_clear()


def _colours(obj, me, loops, loop_vertex, mat_index, notes=None):
    """(per-corner colours or None, per-corner UVs or None, texture or None). Honoured: the
    active colour attribute, else a Base Color from other nodes (procedural textures, mixes)
    as baked by :mod:`holo_addon.export.bake`, else an Image Texture on the Principled BSDF's Base
    Color through the active UV map, else the Base Color (per material slot); a Base Color
    from nodes with no current bake is noted in ``notes`` and its default colour used."""
    attr = me.color_attributes.active_color
    if attr is not None and len(attr.data):
        data = np.empty(len(attr.data) * 4, np.float64)
        attr.data.foreach_get("color", data)  # linear
        data = data.reshape(-1, 4)[:, :3]
        per = data[loop_vertex[loops]] if attr.domain == "POINT" else data[loops]
        return per, None, None
    if bake.needs_bake(obj.original):
        baked = bake.current(obj.original)
        layer = me.uv_layers.get(bake.UV_NAME)
        if baked is not None and layer is not None:
            uv = np.empty(len(me.loops) * 2)
            layer.uv.foreach_get("vector", uv)
            return None, uv.reshape(-1, 2)[loops], _pixels(baked)
    image = _base_texture(obj)
    if image is not None and me.uv_layers.active is not None:
        uv = np.empty(len(me.loops) * 2)
        me.uv_layers.active.uv.foreach_get("vector", uv)
        return None, uv.reshape(-1, 2)[loops], _pixels(image)
    for slot in obj.material_slots:
        node = principled(slot.material)
        if node is not None and node.inputs["Base Color"].is_linked and notes is not None:
            src = node.inputs["Base Color"].links[0].from_node
            notes.append(
                f"material '{slot.material.name}': its Base Color comes from a "
                f"{src.bl_label} node and is not baked yet (Render Pass bakes it; a "
                f"render cannot): the holographic object uses the Base Color value"
            )
    base = np.array(
        [base_colour(slot.material) for slot in obj.material_slots] or [(1.0, 1.0, 1.0)], np.float64
    )
    return np.repeat(base[np.clip(mat_index, 0, len(base) - 1)], 3, axis=0), None, None


def _base_texture(obj):
    for slot in obj.material_slots:
        node = principled(slot.material)
        if node is None or not node.inputs["Base Color"].is_linked:
            continue
        src = node.inputs["Base Color"].links[0].from_node
        if src.type == "TEX_IMAGE" and src.image is not None:
            return src.image
    return None


def camera_from_object(scene, obj, unit: float, depsgraph=None, *, crop=True) -> Camera:
    """Blender's camera (lens, sensor, fit, shift, render size, pixel aspect, depth of field)
    as :class:`holo_core.scene.camera.Camera`; a focus object as ``depsgraph`` places it.
    With ``crop``, a render cropped to its region gets the region's camera.

    The lens and sensor scale with the scene, as in Cycles: its millimetres are thousandths
    of a Blender unit (the aperture is lens·1e-3 / (2·N) units), so a scene at any
    ``unit_settings.scale_length`` gets the same depth of field, and a camera of metres
    ``unit`` x the lens and sensor Blender shows (the field of view is their ratio)."""
    cam, r = obj.data, scene.render
    if cam.type != "PERSP":
        raise ExportError(f"camera '{obj.name}' must be perspective (it is {cam.type})")
    res = render_size(r)
    m = world_matrix(obj.matrix_world, unit, normalise=True)
    fstop = focus = None
    if cam.dof.use_dof:
        fstop = cam.dof.aperture_fstop
        if cam.dof.focus_object is not None:
            focus_object = cam.dof.focus_object
            if depsgraph is not None:
                focus_object = evaluated(focus_object.original, depsgraph)
            target = np.array(focus_object.matrix_world.translation) * unit
            focus = float(-(target - m[:3, 3]) @ m[:3, 2])  # along the view axis
        else:
            focus = cam.dof.focus_distance * unit
        if focus <= 0:
            raise ExportError("the camera's focus must lie in front of it (focus distance > 0)")
    camera = Camera(
        matrix_world=m,
        lens=cam.lens * unit,
        sensor_width=cam.sensor_width * unit,
        sensor_height=cam.sensor_height * unit,
        sensor_fit=cam.sensor_fit,
        shift_x=cam.shift_x,
        shift_y=cam.shift_y,
        resolution=res,
        pixel_aspect=(r.pixel_aspect_x, r.pixel_aspect_y),
        focus_distance=focus,
        fstop=fstop,
    )
    if crop and r.use_border and r.use_crop_to_border:  # the render is the region alone
        left, top, right, bottom = border_pixels(r)
        if right > left and bottom > top:
            camera = camera.cropped(left, top, right - left, bottom - top)
    return camera


def render_size(render) -> tuple[int, int]:
    """The rendered image's (width, height) [px]: the resolution at its percentage, in
    Blender's integer arithmetic (29 % of 100 px is 29 px, not int(100 * 0.29) = 28)."""
    pct = render.resolution_percentage
    return (max(1, render.resolution_x * pct // 100), max(1, render.resolution_y * pct // 100))


def render_region(render) -> tuple | None:
    """A render region that is not cropped (left, top, right, bottom) [px from the top-left]:
    Blender renders only inside it, so the pass is cleared outside; None without one."""
    return border_pixels(render) if render.use_border and not render.use_crop_to_border else None


def border_pixels(render) -> tuple[int, int, int, int]:
    """The render region (left, top, right, bottom) [px from the top-left corner], as Blender
    computes it: each edge is border × size in single precision, truncated, measured from the
    bottom (in double precision, a region set to exact pixels came out a pixel off: a
    128×108 crop gave a 129×107 pass)."""
    w, h = render_size(render)

    def edge(fraction, size):
        return int(np.float32(fraction) * np.float32(size))

    return (
        edge(render.border_min_x, w),
        h - edge(render.border_max_y, h),
        edge(render.border_max_x, w),
        h - edge(render.border_min_y, h),
    )


def export_scene(scene, depsgraph, *, lit=False) -> SceneData:
    """The scene's emitters and camera as ``depsgraph`` evaluates them (a render's depsgraph:
    the frame rendered, render modifier levels and visibility; the plate, where there is one:
    :func:`holo_addon.export.plates.with_plate`); a clear :class:`ExportError` when one is
    missing. ``lit``: the colours will come from Cycles' radiance
    (:mod:`holo_addon.export.radiance`), so only what that cannot show is noted."""
    unit = scale(scene)
    if scene.camera is None:
        raise ExportError("the scene has no camera")
    notes = []
    kinds, names = emitters(depsgraph, unit, notes, lit=lit)
    if not kinds["POINTS"] + kinds["TRIANGLES"]:
        left_out = "; ".join(n for n in notes if "left out" in n)
        raise NoEmitters(
            "no holographic emitters in the render: set Object ▸ Holo ▸ Emitter "
            "on a mesh that renders (not disabled in renders, in a collection "
            "the view layer includes)" + (f" ({left_out})" if left_out else "")
        )
    camera_object = evaluated(scene.camera, depsgraph)
    camera = camera_from_object(scene, camera_object, unit, depsgraph)
    view = replace(
        camera_from_object(scene, camera_object, unit, depsgraph, crop=False),
        fstop=None,
        focus_distance=None,
    )
    return SceneData(
        points=kinds["POINTS"],
        triangles=kinds["TRIANGLES"],
        plate=None,
        plate_name=None,
        camera=camera,
        warnings=tuple(dict.fromkeys(notes)),
        names=tuple(names),
        view=view,
        region=render_region(scene.render),
        unit=unit,
    )


def emitters(depsgraph, unit: float, notes: list, *, lit=False) -> tuple[dict, list]:
    """({'POINTS': [Mesh], 'TRIANGLES': [Mesh]}, the emitters' object names): every
    holographic emitter the render draws (see :func:`emitter_instances`).
    An emitter that cannot be exported (no faces, a missing image...) is left out with a note
    naming it, and the rest is recorded."""
    found, names = {"POINTS": [], "TRIANGLES": []}, []
    for inst, kind in emitter_instances(depsgraph):
        name = inst.object.original.name
        try:
            mesh = mesh_from_object(
                inst.object, depsgraph, unit, np.array(inst.matrix_world), notes, lit=lit
            )
        except ValueError as e:  # ExportError, and holo_core's InputError on its data
            notes.append(f"emitter '{name}' is left out of the hologram: {e}")
            continue
        found[kind].append(mesh)
        names.append(name)
    return found, names


def emitter_instances(depsgraph):
    """(instance, 'POINTS' or 'TRIANGLES') of every holographic emitter the render draws, as
    Blender decides it: instances (collection instances, instancing) included; objects
    disabled in renders or in collections the view layer excludes or does not render, left
    out."""
    shown = _rendered_collections(depsgraph.view_layer)
    for inst in depsgraph.object_instances:
        ev = inst.object
        holo = ev.original.holo
        if ev.type != "MESH" or holo.emitter == "NONE" or holo.is_plate:
            continue
        if _renders(inst.parent.original if inst.is_instance else ev.original, shown):
            yield inst, holo.emitter


def viewport_matches_render(scene) -> bool:
    """Whether the viewport evaluates every emitter as a render does (no modifier enabled in
    one and not the other, no subdivision or multiresolution level differing), so that a pass
    made from the viewport stands for the render's."""
    for obj in scene.objects:
        if obj.type != "MESH" or obj.holo.emitter == "NONE":
            continue
        for mod in obj.modifiers:
            if mod.show_viewport != mod.show_render:
                return False
            levels = getattr(mod, "levels", None), getattr(mod, "render_levels", None)
            if levels[1] is not None and levels[0] != levels[1]:
                return False
    return True


def _rendered_collections(view_layer) -> set:
    """Pointers of the collections the view layer renders: not excluded, not disabled in
    renders, and neither is any collection above them."""
    shown = set()

    def walk(lc, ok):
        ok = ok and not lc.exclude and not lc.collection.hide_render
        if ok:
            shown.add(lc.collection.as_pointer())
            for child in lc.children:
                walk(child, ok)

    walk(view_layer.layer_collection, True)
    return shown


def _renders(obj, shown: set) -> bool:
    return not obj.hide_render and any(c.as_pointer() in shown for c in obj.users_collection)


def camera_matrix(scene, depsgraph, unit: float) -> np.ndarray:
    """The scene camera's world matrix [m] (its scale removed) as ``depsgraph`` evaluates
    it."""
    return world_matrix(evaluated(scene.camera, depsgraph).matrix_world, unit, normalise=True)


def evaluated(obj, depsgraph):
    ev = obj.evaluated_get(depsgraph)
    return ev if ev is not None else obj


def _pixels(image) -> np.ndarray:
    """Image pixels (h, w, 3), row 0 at the top as :func:`holo_core.scene.mesh.texture_lookup`
    expects. Blender stores rows bottom-up; byte images are sRGB, float images linear."""
    w, h = image.size
    if not w or not h:
        raise ExportError(f"image '{image.name}' has no pixels (is the file missing?)")
    px = np.empty(w * h * image.channels, np.float32)
    image.pixels.foreach_get(px)
    px = px.reshape(h, w, image.channels)[::-1, :, :3].astype(np.float64)
    if not image.is_float and image.colorspace_settings.name == "sRGB":
        px = np.where(px <= 0.04045, px / 12.92, ((px + 0.055) / 1.055) ** 2.4)
    return px
