"""Emitter colours from Blender's own shading: where a material's Base Color comes from a node
the export cannot read (a procedural texture, a mix, a colour ramp...), Cycles bakes it.

The bake is Cycles' Diffuse colour (the albedo: no light, no shadow) into a float image on a
UV map of the add-on's own (``Holo Bake``: each face in its own cell of a grid, so nothing
overlaps), which modifiers carry to the evaluated mesh; the export then reads it as an image
texture. The image is packed into the .blend, so farm machines render with it, and it is made
again when the materials or the faces change (a digest kept on the object). Baking runs from
the operators on Blender's main thread; a render cannot bake (Cycles would nest), so a render
whose bake is missing or stale warns and uses the Base Color value.
"""

from __future__ import annotations

import hashlib
import math

import bpy
import numpy as np

from ..blender.materials import principled
from ..blender.objects import seen_by_every_ray

UV_NAME = "Holo Bake"
SIZE = 1024  # texels along the atlas side
MARGIN = 0.08  # of a cell, left free around each face (the bake's margin bleeds into it)
BAKE_SAMPLES = 4  # the albedo has no noise: a few samples only average across each texel


def image_name(obj) -> str:
    return f"{UV_NAME} {obj.name}"


def needs_bake(obj) -> bool:
    """Whether a material's Base Color comes from a node other than an Image Texture."""
    return any(_procedural(slot.material) for slot in obj.material_slots)


def _procedural(material) -> bool:
    node = principled(material)
    if node is None or not node.inputs["Base Color"].is_linked:
        return False
    return node.inputs["Base Color"].links[0].from_node.type != "TEX_IMAGE"


def digest(obj) -> str:
    """What the bake depends on: the mesh's faces and vertices, and every material's nodes,
    values and links. (A bake is made at the frame it runs on: a Base Color that changes with
    deformation or over time is baked as it is then.)"""
    co = np.empty(len(obj.data.vertices) * 3, np.float32)
    obj.data.vertices.foreach_get("co", co)
    h = hashlib.sha256(f"{len(obj.data.polygons)}".encode() + co.tobytes())
    for slot in obj.material_slots:
        tree = slot.material.node_tree if slot.material is not None else None
        for node in tree.nodes if tree is not None else ():
            h.update(f"{node.bl_idname} {node.name}".encode())
            for socket in node.inputs:
                value = getattr(socket, "default_value", None)
                h.update(
                    repr(
                        tuple(value)
                        if hasattr(value, "__len__") and not isinstance(value, str)
                        else value
                    ).encode()
                )
            for key in (
                "noise_dimensions",
                "gradient_type",
                "voronoi_dimensions",
                "feature",
                "distance",
                "interpolation",
                "blend_type",
                "operation",
            ):
                h.update(repr(getattr(node, key, None)).encode())
        for link in tree.links if tree is not None else ():
            h.update(
                f"{link.from_node.name}.{link.from_socket.identifier}>"
                f"{link.to_node.name}.{link.to_socket.identifier}".encode()
            )
    return h.hexdigest()[:16]


def current(obj) -> bpy.types.Image | None:
    """The object's bake when it matches its materials and faces, else None."""
    image = bpy.data.images.get(image_name(obj))
    if image is None or obj.data.uv_layers.get(UV_NAME) is None:
        return None
    return image if obj.get("holo_bake") == digest(obj) else None


def bake(obj, scene, size: int = SIZE) -> bpy.types.Image:
    """Bake ``obj``'s Base Color (every material slot) into its image; returns the image."""
    mesh = obj.data
    uv = mesh.uv_layers.get(UV_NAME) or mesh.uv_layers.new(name=UV_NAME, do_init=False)
    _atlas(mesh, uv)
    image = bpy.data.images.get(image_name(obj))
    if image is None or tuple(image.size) != (size, size):
        if image is not None:
            bpy.data.images.remove(image)
        image = bpy.data.images.new(image_name(obj), size, size, float_buffer=True)
    targets = []
    for slot in obj.material_slots:  # the bake writes into each material's active image node
        tree = slot.material.node_tree if slot.material is not None else None
        if tree is not None and all(t.id_data != tree for t in targets):
            node = tree.nodes.new("ShaderNodeTexImage")
            node.image = image
            tree.nodes.active = node
            targets.append(node)
    engine, selected = scene.render.engine, obj.select_get()
    scene.render.engine = "CYCLES"
    samples, scene.cycles.samples = scene.cycles.samples, BAKE_SAMPLES
    try:
        obj.select_set(True)
        # an emitter is a holdout in the raster, which the bake must not see
        with (
            seen_by_every_ray(obj),
            bpy.context.temp_override(
                scene=scene,
                object=obj,
                active_object=obj,
                selected_objects=[obj],
                selected_editable_objects=[obj],
            ),
        ):
            bpy.ops.object.bake(
                type="DIFFUSE", pass_filter={"COLOR"}, margin=4, use_clear=True, uv_layer=UV_NAME
            )
        # packed (and kept by a fake user) while the nodes still use it: an image nobody uses
        # loses its baked buffer, and is not saved with the .blend
        image.pack()
        image.use_fake_user = True
    finally:
        scene.cycles.samples = samples
        scene.render.engine = engine
        obj.select_set(selected)
        for node in targets:
            node.id_data.nodes.remove(node)
    obj["holo_bake"] = digest(obj)
    return image


def _atlas(mesh, uv) -> None:
    """Each face in its own cell of a square grid, projected onto its plane and scaled to fit
    inside the cell's margin."""
    n = len(mesh.polygons)
    side = math.ceil(math.sqrt(max(n, 1)))
    cell = 1.0 / side
    co = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    out = np.zeros((len(mesh.loops), 2))
    for i, poly in enumerate(mesh.polygons):
        loops = list(poly.loop_indices)
        p = co[[mesh.loops[k].vertex_index for k in loops]]
        normal = np.array(poly.normal)
        u = p[1] - p[0] if len(p) > 1 else np.array([1.0, 0, 0])
        u = u - normal * (u @ normal)
        u /= np.linalg.norm(u) or 1.0
        v = np.cross(normal, u)
        flat = np.stack([(p - p[0]) @ u, (p - p[0]) @ v], 1)
        lo, span = flat.min(0), max(float(np.ptp(flat, 0).max()), 1e-12)
        inner = cell * (1 - 2 * MARGIN)
        origin = np.array([i % side, i // side]) * cell + cell * MARGIN
        out[loops] = origin + (flat - lo) / span * inner
    uv.uv.foreach_set("vector", out.ravel())
