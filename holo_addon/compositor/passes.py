"""The holographic pass in Blender's compositor, and the pass each rendered frame makes.

The tree: the user's composite (or Render Layers' Image) and an Image node reading the
frame's holographic pass (Combined, Depth) meet in a Depth Combine that keeps, per pixel, the
nearer of the two and blends the holographic image over by its alpha; a File Output node
writes the composite, the pass and both depths as a multilayer EXR beside each rendered frame
(:func:`beside_render`). A render makes its frame's pass from its own depsgraph
(:func:`render_frame`); a failure never leaves a stale pass in the frame (:func:`failed`).
"""

from __future__ import annotations

import logging
import os
import sys
from pathlib import Path

import bpy
from bpy.app.handlers import persistent

from holo_core import jobs

from ..blender import compat
from ..render import pipeline

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


def setup(scene, folder: Path):
    """Add the Depth Combine of the holographic pass (the frame's ``holo_pass_NNNN.exr`` in
    ``folder``, read as an image sequence so that every frame composites its own pass) to the
    scene's compositor; enables the view layer's Depth pass. The user's own nodes and links
    stay: whatever fed the compositor's output now feeds the Depth Combine, whose result goes
    to the output and to the multilayer EXR beside the render. The add-on's nodes sit in a
    frame named "Holo: holographic pass"; running this again rebuilds only them. The current
    frame's pass must exist (its sockets come from the file)."""
    first = pipeline.pass_file(folder, scene.frame_current)
    if not first.is_file():
        raise FileNotFoundError(f"no holographic pass at {first}: render the pass first")
    for layer in scene.view_layers:
        layer.use_pass_z = True
    tree = compat.compositor_tree(scene)
    group = _node(tree, "NodeFrame", NODE_PREFIX + "Frame")
    group.label = "Holo: holographic pass"
    out_socket = compat.output_socket(tree)
    old = tree.nodes.get(NODE_PREFIX + "Depth Combine")
    feed = old.inputs[2] if old is not None else out_socket
    source = feed.links[0].from_socket if feed.is_linked else None
    if old is not None:
        tree.nodes.remove(old)
    layers = _node(tree, "CompositorNodeRLayers", NODE_PREFIX + "Render Layers")
    layers.scene = scene
    image = bpy.data.images.load(str(first), check_existing=True)
    image.source = "SEQUENCE"
    image.reload()
    holo = _node(tree, "CompositorNodeImage", NODE_PREFIX + "Pass")
    holo.image = image
    holo.frame_start, holo.frame_offset = 1, 0
    holo.frame_duration = MAX_FRAME  # file number = the frame being rendered
    holo.use_auto_refresh = True
    combine = compat.depth_combine(tree)
    combine.name = combine.label = NODE_PREFIX + "Depth Combine"
    for node, at in ((layers, (-400, 200)), (holo, (-400, -200)), (combine, (-100, 0))):
        node.parent, node.location = group, at
    tree.links.new(_output(holo, "Combined", "Image"), combine.inputs[0])
    tree.links.new(_output(holo, "Depth", "Z"), combine.inputs[1])
    tree.links.new(source or _output(layers, "Image"), combine.inputs[2])
    tree.links.new(_output(layers, "Depth", "Z"), combine.inputs[3])
    tree.links.new(combine.outputs[0], out_socket)
    files = compat.multilayer_output(tree, NODE_PREFIX + "File Output", beside_render(scene),
                                     LAYERS)
    files.parent, files.location = group, (200, -250)
    for socket, layer in zip((combine.outputs[0], _output(holo, "Combined", "Image"),
                              _output(holo, "Depth", "Z"), combine.outputs[1]), files.inputs):
        tree.links.new(socket, layer)
    return combine


# The layers of the multilayer EXR written beside each rendered frame: the composite, the
# holographic pass alone and its depth, and the composite's depth (the nearer of the two).
LAYERS = (("Composite", "RGBA"), ("Holo", "RGBA"), ("HoloDepth", "FLOAT"), ("Depth", "FLOAT"))


def beside_render(scene) -> str:
    """Where the frame's holographic layers go: the render output's folder, under the output's
    file name prefixed by ``holo_`` (its ``#`` frame digits and image extension dropped:
    Blender adds the frame), e.g. ``//out/shot_####`` → ``//out/holo_shot_0001.exr``."""
    folder, name = os.path.split(scene.render.filepath)
    stem, ext = os.path.splitext(name)
    if ext.lower() in bpy.path.extensions_image:
        name = stem
    return os.path.join(folder or "//", "holo_" + name.replace("#", ""))


MAX_FRAME = 1048574  # Blender's last frame


def _tree(scene):
    return scene.compositing_node_group if compat.compositor_is_group(scene) else scene.node_tree


def uses_pass(scene) -> bool:
    tree = _tree(scene)
    return tree is not None and tree.nodes.get(NODE_PREFIX + "Pass") is not None


@persistent
def render_frame(scene, depsgraph=None):
    """``frame_change_post``: when Blender has evaluated a frame for rendering (F12, ``-f``,
    ``-a``; its depsgraph is then the render's, in RENDER mode), the holographic pass of that
    frame from that depsgraph: the frame being rendered whatever the timeline shows, render
    modifier levels and render visibility. The hologram is recorded again only when the scene
    changed. A failed pass never leaves a stale pass in the composite (see :func:`failed`)."""
    if depsgraph is None or depsgraph.mode != "RENDER":
        return
    if not (scene.holo.pass_on_render and uses_pass(scene)):
        return
    if scene.holo.get("skip_pass_once"):
        del scene.holo["skip_pass_once"]
        return
    RUNNING.update(frame=scene.frame_current, fraction=0.0, cancel=False)
    WARNINGS.update(frame=scene.frame_current, texts=[])
    try:
        job = pipeline.prepare(scene, depsgraph)
        for warning in job.scene.warnings:
            _log(logging.WARNING, warning)
        outcome = pipeline.run(job, _progress, _log)
        pipeline.apply(scene, job, outcome)
    except jobs.Cancelled:
        failed(scene, f"Holo: the holographic pass of frame {scene.frame_current} was "
                      f"cancelled")
        return
    except Exception as e:  # noqa: BLE001 -- any failure must stop the frame, not pass by
        failed(scene, f"Holo: the holographic pass of frame {scene.frame_current} failed: {e}")
        return
    finally:
        RUNNING["frame"] = None
    log.info("holographic pass for frame %d: %s", job.frame, outcome.frame_path)


# The pass a render is making (it runs in the render's thread): its progress for the status
# bar and the panel, and the Cancel Pass button's request.
RUNNING = {"frame": None, "fraction": 0.0, "cancel": False}


# The warnings of the latest pass a render made (the scene's and the worker's, as they
# arise): in the log, which a farm's output shows, and in Render ▸ Holo.
WARNINGS = {"frame": None, "texts": []}


def _log(level, text):
    log.log(level, text)
    if level >= logging.WARNING:
        WARNINGS["texts"].append(text)


def _progress(fraction):
    RUNNING["fraction"] = fraction
    if RUNNING["cancel"]:
        raise jobs.Cancelled()


_shown = [None]


def _show_progress():
    """A timer on the interface's thread: the render's pass progress in the status bar."""
    frame = RUNNING["frame"]
    text = None if frame is None else (f"Holo: holographic pass of frame {frame}: "
                                       f"{RUNNING['fraction']:.0%} (Render Properties ▸ Holo "
                                       f"▸ Cancel Pass)")
    if text != _shown[0]:
        _shown[0] = text
        for window in bpy.context.window_manager.windows:
            try:
                with bpy.context.temp_override(window=window):
                    window.workspace.status_text_set(text)
                for area in window.screen.areas:
                    if area.type == "PROPERTIES":
                        area.tag_redraw()
            except Exception as e:  # noqa: BLE001 -- a timer that raises is unregistered
                log.debug("status text: %s", e)
    return 0.25


EXIT_ON_FAILURE = None  # None: in background renders (blender -b ... -a), as farms need


def failed(scene, message: str) -> None:
    """A failed pass. In a background render the process exits with status 1 before the frame
    is rendered, so ``blender -b ... -a`` fails and no frame with a stale pass is written. In
    the interface (a handler cannot cancel Blender's render) the frame's earlier pass, now
    stale, is set aside as ``holo_pass_NNNN.stale.exr`` (kept, but out of the image sequence),
    so the composite shows the raster alone, and the error goes to Blender's reports and a
    popup. (Muting the node would not do: the render has already evaluated its copy of the
    compositor.)"""
    log.error(message)
    exit_now = bpy.app.background if EXIT_ON_FAILURE is None else EXIT_ON_FAILURE
    if exit_now:
        sys.stderr.write(message + "\n")
        sys.stderr.flush()
        os._exit(1)
    try:
        stale = pipeline.pass_file(pipeline.output_dir(scene), scene.frame_current)
        if stale.is_file():
            os.replace(stale, stale.with_suffix(".stale.exr"))
    except (OSError, ValueError) as e:
        log.error("the stale pass could not be set aside: %s", e)
    if not bpy.app.background:
        bpy.app.timers.register(lambda: _show_error(message), first_interval=0.0)


def _show_error(message):
    """On the interface's thread: the error in Blender's reports (status bar, Info log) and a
    popup."""
    try:
        bpy.ops.holo.report(message=message)
    except RuntimeError:  # what Python sees of an error report, once it is reported
        pass

    def draw(menu, _context):
        menu.layout.label(text=message)
    bpy.context.window_manager.popup_menu(draw, title="Holo", icon="ERROR")


@persistent
def _new_file(*_):
    WARNINGS.update(frame=None, texts=[])


def register():
    bpy.app.handlers.frame_change_post.append(render_frame)
    bpy.app.handlers.load_post.append(_new_file)
    if not bpy.app.background:
        bpy.app.timers.register(_show_progress, persistent=True)


def unregister():
    for handlers, fn in ((bpy.app.handlers.frame_change_post, render_frame),
                         (bpy.app.handlers.load_post, _new_file)):
        if fn in handlers:
            handlers.remove(fn)
    if bpy.app.timers.is_registered(_show_progress):
        bpy.app.timers.unregister(_show_progress)
