"""The holographic pass in Blender's compositor, and the pass rendered before each frame.

The tree: Render Layers (Image, Depth) and an Image node showing the holographic pass
(Combined, Depth) meet in a Depth Combine that keeps, per pixel, the nearer of the two and
blends the holographic image over by its alpha.
"""

from __future__ import annotations

import logging
from pathlib import Path

import bpy
from bpy.app.handlers import persistent

from . import compat, pipeline

log = logging.getLogger(__name__)
NODE_PREFIX = "Holo "


def _node(tree, idname, name):
    node = tree.nodes.get(name)
    if node is None or node.bl_idname != idname:
        node = tree.nodes.new(idname)
        node.name = node.label = name
    return node


def _output(node, *names):
    for name in names:
        if name in node.outputs and node.outputs[name].enabled:
            return node.outputs[name]
    raise ValueError(f"node '{node.name}' has no output {' or '.join(names)}")


def setup(scene, pass_path: Path):
    """Build (or rebuild) the Depth Combine of the holographic pass at ``pass_path`` with the
    render; enables the view layer's Depth pass. The pass must exist (its sockets come from
    the file)."""
    if not Path(pass_path).is_file():
        raise FileNotFoundError(f"no holographic pass at {pass_path}: render the pass first")
    for layer in scene.view_layers:
        layer.use_pass_z = True
    tree = compat.compositor_tree(scene)
    layers = _node(tree, "CompositorNodeRLayers", NODE_PREFIX + "Render Layers")
    layers.scene = scene
    layers.location = (-400, 200)
    image = bpy.data.images.load(str(pass_path), check_existing=True)
    image.reload()
    holo = _node(tree, "CompositorNodeImage", NODE_PREFIX + "Pass")
    holo.image = image
    holo.location = (-400, -200)
    old = tree.nodes.get(NODE_PREFIX + "Depth Combine")
    if old is not None:
        tree.nodes.remove(old)
    combine = compat.depth_combine(tree)
    combine.name = combine.label = NODE_PREFIX + "Depth Combine"
    tree.links.new(_output(holo, "Combined", "Image"), combine.inputs[0])
    tree.links.new(_output(holo, "Depth", "Z"), combine.inputs[1])
    tree.links.new(_output(layers, "Image"), combine.inputs[2])
    tree.links.new(_output(layers, "Depth", "Z"), combine.inputs[3])
    tree.links.new(combine.outputs[0], compat.output_socket(tree))
    return combine


def uses_pass(scene) -> bool:
    tree = (scene.compositing_node_group if compat.compositor_is_group(scene)
            else scene.node_tree)
    return tree is not None and tree.nodes.get(NODE_PREFIX + "Pass") is not None


@persistent
def render_pre(scene, *_):
    """Before Blender renders a frame (F12, ``-f``, ``-a``): the holographic pass of that
    frame, recording again only when the scene changed."""
    if not (scene.holo.pass_on_render and uses_pass(scene)):
        return
    if scene.holo.get("skip_pass_once"):
        del scene.holo["skip_pass_once"]
        return
    depsgraph = bpy.context.evaluated_depsgraph_get()
    job = pipeline.prepare(scene, depsgraph)
    outcome = pipeline.run(job)
    pipeline.apply(scene, job, outcome)
    log.info("holographic pass for frame %d: %s", job.frame, outcome.frame_path)


def register():
    bpy.app.handlers.render_pre.append(render_pre)


def unregister():
    if render_pre in bpy.app.handlers.render_pre:
        bpy.app.handlers.render_pre.remove(render_pre)
