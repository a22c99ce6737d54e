"""Blender 4.x / 5.x differences, in one place (facts.md §2).

5.0 made the compositor a node-group data-block with a Group Output instead of the Composite
node, turned Depth Combine's options into input sockets and multilayer EXR output into a
media type; 4.2-4.5 call EEVEE ``BLENDER_EEVEE_NEXT``. ``gpu_extras``' ``draw_texture_2d``
takes scene-linear textures into the viewport's sRGB target only where it has
``is_scene_linear_with_rec709_srgb_target``.
"""

from __future__ import annotations

import inspect
import os
from contextlib import contextmanager

import bpy

TREE_NAME = "Holo Compositing"


def compositor_is_group(scene) -> bool:
    return hasattr(scene, "compositing_node_group")


def compositor_tree(scene):
    """The scene's compositing node tree, created when missing."""
    if compositor_is_group(scene):
        tree = scene.compositing_node_group
        if tree is None:
            tree = bpy.data.node_groups.new(TREE_NAME, "CompositorNodeTree")
            scene.compositing_node_group = tree
        return tree
    scene.use_nodes = True
    return scene.node_tree


def output_socket(tree):
    """The input socket whose image becomes the render result."""
    if hasattr(bpy.types, "CompositorNodeComposite"):
        node = next((n for n in tree.nodes if n.bl_idname == "CompositorNodeComposite"), None)
        node = node or tree.nodes.new("CompositorNodeComposite")
        return node.inputs[0]
    if not any(
        s.in_out == "OUTPUT"
        for s in tree.interface.items_tree
        if getattr(s, "item_type", "SOCKET") == "SOCKET"
    ):
        tree.interface.new_socket(name="Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    node = next((n for n in tree.nodes if n.bl_idname == "NodeGroupOutput"), None)
    node = node or tree.nodes.new("NodeGroupOutput")
    return node.inputs[0]


def math_node(tree, operation: str, *, clamp=False):
    """A compositor Math node (4.x ``CompositorNodeMath``, 5.x the shader nodes' Math)."""
    idname = "CompositorNodeMath" if hasattr(bpy.types, "CompositorNodeMath") else "ShaderNodeMath"
    node = tree.nodes.new(idname)
    node.operation, node.use_clamp = operation, clamp
    return node


def multilayer_output(tree, name: str, path: str, layers):
    """A File Output node named ``name`` writing ``layers`` ((layer name, "RGBA" or "FLOAT"),
    ...; inputs in that order) as one 32-bit multilayer EXR per frame at ``path``, a folder
    and a file-name prefix to which Blender adds the frame number."""
    old = tree.nodes.get(name)
    if old is not None:
        tree.nodes.remove(old)
    node = tree.nodes.new("CompositorNodeOutputFile")
    node.name = node.label = name
    if hasattr(node, "file_output_items"):
        node.format.media_type = "MULTI_LAYER_IMAGE"
        node.file_output_items.clear()
        for layer, kind in layers:
            node.file_output_items.new(kind, layer)
    else:
        node.format.file_format = "OPEN_EXR_MULTILAYER"
        node.layer_slots.clear()
        for layer, _ in layers:
            node.layer_slots.new(layer)
    set_output_path(node, path)
    node.format.color_depth = "32"
    node.format.exr_codec = "ZIP"  # lossless; 5.0's default is uncompressed
    return node


def set_output_path(node, path: str) -> None:
    """A File Output node's folder and file-name prefix (``path``; Blender adds the frame)."""
    if hasattr(node, "file_output_items"):
        folder, node.file_name = os.path.split(path)
        node.directory = folder + os.sep
    else:
        node.base_path = path


def existing_compositor_tree(scene):
    """The scene's compositing node tree when it has one in use, else None (nothing made)."""
    if compositor_is_group(scene):
        return scene.compositing_node_group
    return scene.node_tree if scene.use_nodes else None


def compositor_state(scene) -> dict:
    """What :func:`restore_compositor` puts back: whether the scene had a compositing tree
    (5.x: a node group of the user's) or used its nodes (4.x)."""
    if compositor_is_group(scene):
        tree = scene.compositing_node_group
        return {"tree": tree.name if tree is not None else ""}
    return {"use_nodes": int(bool(scene.use_nodes))}


def restore_compositor(scene, state) -> None:
    """The scene's compositing as :func:`compositor_state` found it: a tree the add-on made
    is taken off the scene (and removed when nothing else uses it); 4.x nodes off again if
    they were."""
    if compositor_is_group(scene):
        tree = scene.compositing_node_group
        if not state.get("tree") and tree is not None:
            scene.compositing_node_group = None
            if tree.users == 0:
                bpy.data.node_groups.remove(tree)
    else:
        scene.use_nodes = bool(state.get("use_nodes", 1))


def set_exr_output(scene, *, multilayer: bool):
    """Render output as float EXR (32-bit; multilayer keeps every pass, Depth included)."""
    s = scene.render.image_settings
    if hasattr(s, "media_type"):
        s.media_type = "MULTI_LAYER_IMAGE" if multilayer else "IMAGE"
        if not multilayer:
            s.file_format = "OPEN_EXR"
    else:
        s.file_format = "OPEN_EXR_MULTILAYER" if multilayer else "OPEN_EXR"
    s.color_depth = "32"


@contextmanager
def png_output(scene):
    """The scene's render output as 8-bit RGBA PNG for a while (Image.save_render writes in
    it), then as it was."""
    s = scene.render.image_settings
    names = [n for n in ("media_type", "file_format", "color_mode", "color_depth") if hasattr(s, n)]
    kept = {n: getattr(s, n) for n in names}
    try:
        set_png_output(scene)
        s.color_mode = "RGBA"
        yield s
    finally:
        for name in names:  # the media type first: it decides which formats are allowed
            setattr(s, name, kept[name])


def set_png_output(scene):
    s = scene.render.image_settings
    if hasattr(s, "media_type"):
        s.media_type = "IMAGE"
    s.file_format = "PNG"
    s.color_depth = "8"


def uses_nodes(material) -> bool:
    """5.x materials always use their node tree (``use_nodes`` is deprecated)."""
    return bpy.app.version >= (5, 0, 0) or material.use_nodes


def enable_nodes(material) -> None:
    if bpy.app.version < (5, 0, 0):
        material.use_nodes = True


LINEAR_TEXTURE = "is_scene_linear_with_rec709_srgb_target"


def draws_linear_textures() -> bool:
    """Whether ``draw_texture_2d`` converts a scene-linear texture for the viewport (else
    the texture must hold display values)."""
    from gpu_extras.presets import draw_texture_2d

    return LINEAR_TEXTURE in inspect.signature(draw_texture_2d).parameters


def draw_linear_texture(draw, texture, position, width, height, *, linear: bool) -> None:
    """``draw`` (``draw_texture_2d``) of ``texture``, told it is scene linear where it can
    be (``linear``: :func:`draws_linear_textures`)."""
    if linear:
        draw(texture, position, width, height, **{LINEAR_TEXTURE: True})
    else:
        draw(texture, position, width, height)
