"""The emitters' colours from Blender's own light transport: what the worker needs to have
Cycles render the emitters' radiance from the camera (:mod:`holo_addon.render.cycles_radiance`)
and project it onto them (:func:`holo_core.scene.radiance.projected`), and a digest of what
that radiance depends on.

Why a render from the camera and not a bake: Cycles' render of the object is exactly what an
ordinary object would show from that camera (direct and indirect light, shadows falling on it,
textures, normal maps, and the view-dependent glossy highlights that a bake has only for its
own view); it needs no UV atlas; it runs in a Blender process of its own, so a render's frame
handler can have it (a bake inside a render would nest Cycles); and, cropped to the emitters'
region, it costs what the raster costs on those pixels. A plate recorded in this add-on is
recorded for the scene camera (it keeps the surfaces that camera sees), so the same radiance
serves it.
"""

from __future__ import annotations

import hashlib
import json
import sys
import tempfile
from pathlib import Path

import bpy
import numpy as np

from holo_core.job import Radiance
from holo_core.scene.camera import Camera

from ..blender import compat
from .scene import scale

SIMPLE = {"BOOLEAN", "INT", "FLOAT", "STRING", "ENUM"}
RAYS = (
    "visible_camera",
    "visible_diffuse",
    "visible_glossy",
    "visible_transmission",
    "visible_volume_scatter",
    "visible_shadow",
    "is_holdout",
    "is_shadow_catcher",
)
MARGIN = 2  # pixels around the emitters' projected box


def digest(scene, depsgraph) -> str:
    """What the emitters' radiance depends on, as ``depsgraph`` evaluates the scene: every
    object the render draws (its kind, placement, ray visibility, evaluated geometry and
    materials), every light's and the world's settings and nodes, and the scene's Cycles
    settings; the camera and the frame enter the pass's own key."""
    h = hashlib.sha256(b"radiance 1")
    _rna(h, scene.cycles)
    h.update(depsgraph.view_layer.name.encode())
    override = depsgraph.view_layer.material_override
    if override is not None:
        _material(h, override, set())
    world = scene.world
    _rna(h, world)
    if world is not None and world.node_tree is not None and compat.uses_nodes(world):
        _tree(h, world.node_tree, set())
    seen = set()
    for inst in depsgraph.object_instances:
        obj = inst.object
        if obj.type == "CAMERA":  # the view enters the pass's key (a plate's: its zone's)
            continue
        h.update(f"{obj.name}|{obj.type}|".encode())
        h.update(np.array(inst.matrix_world, np.float64).tobytes())
        h.update(repr([getattr(obj.original, n, None) for n in RAYS]).encode())
        data = obj.data
        if data is None:
            continue
        if obj.type == "LIGHT":
            _rna(h, data)
            if getattr(data, "node_tree", None) is not None:
                _tree(h, data.node_tree, seen)
        elif obj.type == "MESH":
            co = np.empty(len(data.vertices) * 3, np.float32)
            data.vertices.foreach_get("co", co)
            h.update(f"{len(data.polygons)}".encode() + co.tobytes())
        else:
            h.update(np.array(obj.bound_box, np.float64).tobytes())
        for slot in getattr(obj, "material_slots", ()):
            _material(h, slot.material, seen)
    return h.hexdigest()[:16]


def _rna(h, struct) -> None:
    """The writable plain settings of an RNA struct (numbers, flags, enums, strings)."""
    if struct is None:
        h.update(b"-")
        return
    for prop in struct.bl_rna.properties:
        if prop.type not in SIMPLE or prop.is_readonly or getattr(prop, "is_deprecated", False):
            continue
        value = getattr(struct, prop.identifier, None)
        if isinstance(value, set):
            value = sorted(value)
        elif hasattr(value, "__len__") and not isinstance(value, str):
            value = [tuple(v) if hasattr(v, "__len__") else v for v in value]
        h.update(f"{prop.identifier}={value!r};".encode())


def _material(h, material, seen: set) -> None:
    _rna(h, material)
    if material is not None and material.node_tree is not None and compat.uses_nodes(material):
        _tree(h, material.node_tree, seen)


def _tree(h, tree, seen: set) -> None:
    """A node tree's nodes (their settings and input values), links, node groups and
    images."""
    # by address: the trees of materials, lights and the world are embedded and share one name
    # ("Shader Nodetree"), and in 5.2 every light has one (5.0.1's have none)
    if tree.as_pointer() in seen:
        h.update(f"tree {tree.name_full}".encode())
        return
    seen.add(tree.as_pointer())
    for node in sorted(tree.nodes, key=lambda n: n.name):
        h.update(f"{node.bl_idname} {node.name} {node.mute}".encode())
        _rna(h, node)
        for socket in node.inputs:
            value = getattr(socket, "default_value", None)
            h.update(
                repr(
                    tuple(value)
                    if hasattr(value, "__len__") and not isinstance(value, str)
                    else value
                ).encode()
            )
        image = getattr(node, "image", None)
        if image is not None:
            h.update(
                f"{image.name_full}|{image.filepath}|{tuple(image.size)}|{image.source}|"
                f"{image.packed_file.size if image.packed_file else 0}".encode()
            )
        group = getattr(node, "node_tree", None)
        if group is not None:
            _tree(h, group, seen)
    for link in tree.links:
        h.update(
            f"{link.from_node.name}.{link.from_socket.identifier}>"
            f"{link.to_node.name}.{link.to_socket.identifier}".encode()
        )


def region(camera: Camera, meshes) -> tuple[int, int, int, int] | None:
    """The pixels (left, top, right, bottom) [px from the top-left corner of ``camera``'s
    image] that the emitters ``meshes`` (world metres) cover, with a margin; the whole image
    when one lies behind the camera, None when none is in view."""
    w, h = camera.resolution
    points = np.concatenate([m.vertices for m in meshes]) if meshes else np.zeros((0, 3))
    if not len(points):
        return None
    xy, depth = camera.project(points)
    if not (depth > 0).all():
        return 0, 0, w, h
    left, top = np.floor(xy.min(0)).astype(int) - MARGIN
    right, bottom = np.ceil(xy.max(0)).astype(int) + MARGIN
    left, top, right, bottom = max(left, 0), max(top, 0), min(right, w), min(bottom, h)
    if right <= left or bottom <= top:
        return None
    return int(left), int(top), int(right), int(bottom)


def border(box, size) -> tuple[float, float, float, float]:
    """Blender's render region (min x, max x, min y, max y; y from the bottom) whose pixels are
    ``box`` (left, top, right, bottom) of an image of ``size`` (w, h): Blender truncates
    border × size, so each edge is set half a pixel inside."""
    (left, top, right, bottom), (w, h) = box, size
    return (
        min((left + 0.5) / w, 1.0),
        min((right + 0.5) / w, 1.0),
        min((h - bottom + 0.5) / h, 1.0),
        min((h - top + 0.5) / h, 1.0),
    )


def request(
    scene,
    view_layer: str,
    camera: Camera,
    meshes,
    emitter_names,
    *,
    samples: int = 8,
    own_lens: bool = False,
) -> Radiance | None:
    """The job's :class:`holo_core.job.Radiance` (see :func:`holo_core.runner.lit_emitters`):
    the scene written to a scratch folder as it is now (unsaved changes included), the
    command that renders its view layer ``view_layer`` with Cycles, and the camera of the
    cropped image.
    ``camera``: the render's camera uncropped, as a pinhole; ``meshes``: the emitters (world
    metres), ``emitter_names`` their objects; ``samples``: Cycles' samples (denoised);
    ``own_lens``: Cycles renders with ``camera``'s lens and frame, not the scene camera's (a
    holographic display's eye box). None when no emitter is in view."""
    box = region(camera, meshes)
    if box is None:
        return None
    folder = Path(tempfile.mkdtemp(prefix="holo-radiance-"))
    blend = folder / "scene.blend"
    write_scene(scene, blend)
    image = folder / "radiance.exr"
    args = {
        "blend": str(blend),
        "scene": scene.name,
        "view_layer": view_layer,
        "frame": scene.frame_current,
        "emitters": sorted(set(emitter_names)),
        "border": border(box, camera.resolution),
        "image": str(image),
        "samples": samples,
        "compat": compat.__file__,
        "view": view_matrix(camera, scale(scene)),
        "lens": {
            "lens": camera.lens,
            "sensor_width": camera.sensor_width,
            "sensor_height": camera.sensor_height,
            "sensor_fit": camera.sensor_fit,
            "resolution": list(camera.resolution),
        }
        if own_lens
        else None,
    }
    script = str(Path(__file__).resolve().parents[1] / "render" / "cycles_radiance.py")
    if bpy.app.binary_path:  # Blender: a background Blender without the user's add-ons
        command = [
            bpy.app.binary_path,
            "-b",
            "--factory-startup",
            "-noaudio",
            str(blend),
            "--python",
            script,
            "--",
            json.dumps(args),
        ]
    else:  # the bpy module: a Python that imports it
        command = [sys.executable, "-I", script, "--", json.dumps(args)]  # bpy's own path
    left, top, right, bottom = box
    return Radiance(
        command=tuple(command),
        image=image,
        folder=folder,
        camera=camera.cropped(left, top, right - left, bottom - top),
    )


def view_matrix(camera: Camera, unit: float) -> list:
    """The pose Cycles renders the radiance from, in Blender units (``unit``: metres per
    unit): the camera the emitters are projected from, which for a plate is its zone's centre
    (not the scene's camera)."""
    m = np.array(camera.matrix_world, np.float64)
    m[:3, 3] /= unit
    return m.tolist()


def write_scene(scene, path: Path) -> None:
    """``scene`` and everything it uses, as they are in memory, into the .blend ``path``
    (external files by absolute path; packed ones stay packed)."""
    bpy.data.libraries.write(str(path), {scene}, path_remap="ABSOLUTE", compress=False)
