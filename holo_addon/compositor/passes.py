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
import time
from pathlib import Path

import bpy
from bpy.app.handlers import persistent

from holo_core import jobs

from ..blender import compat
from ..export.scene import NoEmitters, emitter_instances
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
    if BEFORE not in scene:  # what Remove Holo Compositing puts back
        scene[BEFORE] = {**compat.compositor_state(scene), "depth": {
            layer.name: int(layer.use_pass_z) for layer in scene.view_layers}}
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
DEPTHS = ("HoloDepth", "Depth")  # Blender's File Output names them .V; Blender's passes, .Z
BEFORE = "holo_compositor_before"  # on the scene: its compositing before the first setup


def remove(scene) -> bool:
    """Take the add-on's nodes out of the scene's compositor and put back what the user had:
    whatever fed the Depth Combine feeds the output again, every other node and link of the
    user's stays, a tree the add-on made is removed, and the view layers' Depth passes are as
    they were. Returns whether there was anything to remove."""
    tree = compat.existing_compositor_tree(scene)
    ours = [n for n in tree.nodes if n.name.startswith(NODE_PREFIX)] if tree is not None else []
    before = scene.get(BEFORE)
    if not ours and before is None:
        return False
    combine = tree.nodes.get(NODE_PREFIX + "Depth Combine") if tree is not None else None
    source = None
    if combine is not None and combine.inputs[2].is_linked:
        source = combine.inputs[2].links[0].from_socket
        if source.node.name.startswith(NODE_PREFIX):  # our Render Layers: the user had none
            source = None
    images = {n.image for n in ours if getattr(n, "image", None) is not None}
    for node in ours:
        tree.nodes.remove(node)
    if source is not None:
        tree.links.new(source, compat.output_socket(tree))
    if before is not None:
        state = before.to_dict()
        compat.restore_compositor(scene, state)
        for layer in scene.view_layers:
            layer.use_pass_z = bool(state.get("depth", {}).get(layer.name, layer.use_pass_z))
        del scene[BEFORE]
    for image in images:
        if image.users == 0:
            bpy.data.images.remove(image)
    return True


def layers_file(scene, frame: int) -> list[Path]:
    """The multilayer EXR files the File Output node may have written for ``frame``: with
    the frame's number (animations) or without (5.x stills)."""
    prefix = bpy.path.abspath(beside_render(scene))
    return [Path(f"{prefix}{frame:04d}.exr"), Path(f"{prefix}.exr")]


def name_depths_z(path: Path) -> bool:
    """Rename the depth layers' channels of the layers file ``path`` from ``.V`` (what
    Blender's File Output names a value) to ``.Z`` (what Blender's render passes and
    compositing programs call depth); rewritten atomically. Returns whether it renamed."""
    import OpenEXR

    from holo_core.io.image import atomic_path
    with OpenEXR.File(str(path), separate_channels=True) as f:
        parts, renamed = [], False
        for part in f.parts:
            header = {k: v for k, v in part.header.items() if k not in ("channels",
                                                                          "chunkCount")}
            channels = {}
            for name, c in part.channels.items():
                layer, _, channel = name.rpartition(".")
                new = f"{layer}.Z" if layer in DEPTHS and channel == "V" else name
                renamed |= new != name
                channels[new] = OpenEXR.Channel(new, c.pixels.copy(), c.xSampling,
                                                c.ySampling, c.pLinear)
            parts.append(OpenEXR.Part(header, channels, part.name()))
    if renamed:
        with atomic_path(path) as tmp:
            OpenEXR.File(parts).write(tmp)
    return renamed


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


def uses_pass(scene) -> bool:
    tree = compat.existing_compositor_tree(scene)
    return tree is not None and tree.nodes.get(NODE_PREFIX + "Pass") is not None


# The render being made (render_init to render_complete): what it has warned of once, and
# when its frame started (the layers file written since then is this frame's).
RENDER = {"warned": set(), "started": 0.0}


@persistent
def render_init(scene, *_):
    """A render begins (F12, ``-f``, ``-a``: once): the holographic layers follow the render
    output's path as it is now (``-o`` on a farm, or a path changed since the setup)."""
    RENDER.update(warned=set(), started=time.time())
    tree = compat.existing_compositor_tree(scene)
    node = tree.nodes.get(NODE_PREFIX + "File Output") if tree is not None else None
    if node is not None:
        compat.set_output_path(node, beside_render(scene))


@persistent
def render_pre(scene, *_):
    RENDER["started"] = time.time()


@persistent
def render_post(scene, *_):
    """A frame is composited: its holographic layers' depth channels named ``.Z``."""
    if not uses_pass(scene):
        return
    for path in layers_file(scene, scene.frame_current):
        try:
            if path.is_file() and path.stat().st_mtime >= RENDER["started"] - 1:
                name_depths_z(path)
        except (OSError, RuntimeError) as e:  # the library's read and write errors
            log.error("Holo: the holographic layers %s could not be renamed: %s", path, e)


@persistent
def render_frame(scene, depsgraph=None):
    """``frame_change_post``: when Blender has evaluated a frame for rendering (F12, ``-f``,
    ``-a``; its depsgraph is then the render's, in RENDER mode), the holographic pass of that
    frame from that depsgraph: the frame being rendered whatever the timeline shows, render
    modifier levels and render visibility. The hologram is recorded again only when the scene
    changed. A failed pass never leaves a stale pass in the composite (see :func:`failed`)."""
    if depsgraph is None or depsgraph.mode != "RENDER":
        return
    if scene.frame_subframe:  # a motion-blur step: the frame's pass is made at its centre
        return
    WARNINGS.update(frame=scene.frame_current, texts=[])
    names = [inst.object.original.name for inst, _ in emitter_instances(depsgraph)]
    if not uses_pass(scene):
        if names:  # never a silent vanish: the camera sees emitters through the pass only
            _warn_once("setup", f"Holo: the holographic objects ({_listed(names)}) are not "
                                f"in this render: the compositor has no holographic pass "
                                f"(Render ▸ Holo ▸ Set Up Compositing, or Render with "
                                f"Hologram)")
        return
    if names and scene.render.use_motion_blur:
        _warn_once("blur", "Holo: motion blur is on: the holographic objects are rendered at "
                           "each frame's time, without blur (the raster is blurred)")
    if not scene.holo.pass_on_render:
        _check_stale(scene, depsgraph)
        return
    if scene.holo.get("skip_pass_once"):
        del scene.holo["skip_pass_once"]
        return
    RUNNING.update(frame=scene.frame_current, fraction=0.0, cancel=False)
    try:
        try:
            job = pipeline.prepare(scene, depsgraph)
        except NoEmitters:  # none left: the frame is the raster alone
            path = pipeline.clear_pass(scene, scene.frame_current)
            pipeline.reload_passes(path)
            log.info("Holo: no holographic emitters in frame %d: it renders the raster "
                     "alone (Render ▸ Holo ▸ Remove Holo Compositing takes the pass out)",
                     scene.frame_current)
            return
        for warning in job.warnings:
            _log(logging.WARNING, warning)
        result = pipeline.run(job, _progress, _log)
        pipeline.apply(scene, job, result)
    except jobs.Cancelled:
        failed(scene, f"Holo: the holographic pass of frame {scene.frame_current} was "
                      f"cancelled")
        return
    except Exception as e:  # noqa: BLE001 -- any failure must stop the frame, not pass by
        failed(scene, f"Holo: the holographic pass of frame {scene.frame_current} failed: {e}")
        return
    finally:
        RUNNING["frame"] = None
    log.info("holographic pass for frame %d: %s", job.job.output.frame, result.pass_path)


def _listed(names, most=3) -> str:
    names = list(dict.fromkeys(names))
    more = f" and {len(names) - most} more" if len(names) > most else ""
    return ", ".join(f"'{n}'" for n in names[:most]) + more


def _warn_once(key: str, text: str) -> None:
    """A warning given once per render (an animation included)."""
    if key not in RENDER["warned"]:
        RENDER["warned"].add(key)
        warn(text)


def warn(text: str) -> None:
    """A warning of a render's pass: in the log (a farm's output), in Render ▸ Holo, and in
    the interface in Blender's reports (status bar, Info log)."""
    _log(logging.WARNING, text)
    if not bpy.app.background:
        bpy.app.timers.register(lambda: _show_warning(text), first_interval=0.0)


def _show_warning(message):
    try:
        bpy.ops.holo.report(message=message, level="WARNING")
    except RuntimeError as e:
        log.debug("report: %s", e)


def _age(seconds: float) -> str:
    seconds = max(0.0, seconds)
    for unit, size in (("days", 86400), ("h", 3600), ("min", 60)):
        if seconds >= size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.0f} s"


def _check_stale(scene, depsgraph) -> None:
    """Pass on Every Render is off: the frame composites the pass on disk as it is; a warning
    when it was made from another state of the scene (with its age) or is missing."""
    frame = scene.frame_current
    try:
        path = pipeline.pass_file(pipeline.output_dir(scene), frame)
        try:
            key = pipeline.prepare(scene, depsgraph).job.output.pass_key
        except NoEmitters:
            key = None
    except Exception as e:  # noqa: BLE001 -- the scene cannot be read: say so, render on
        warn(f"Holo: the holographic pass of frame {frame} could not be checked: {e}")
        return
    if not path.is_file():
        if key is not None:
            warn(f"Holo: frame {frame} has no holographic pass (Pass on Every Render is off): "
                 f"its holographic objects are missing")
        return
    if key is None or pipeline.stored_key(path) != key:
        age = _age(time.time() - path.stat().st_mtime)
        warn(f"Holo: the holographic pass of frame {frame} is stale: made {age} ago from "
             f"another state of the scene, it is composited as it is (Pass on Every Render "
             f"is off; Render Pass makes it again)")


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


def _handlers():
    h = bpy.app.handlers
    return ((h.frame_change_post, render_frame), (h.load_post, _new_file),
            (h.render_init, render_init), (h.render_pre, render_pre),
            (h.render_post, render_post))


def register():
    for handlers, fn in _handlers():
        handlers.append(fn)
    if not bpy.app.background:
        bpy.app.timers.register(_show_progress, persistent=True)


def unregister():
    for handlers, fn in _handlers():
        if fn in handlers:
            handlers.remove(fn)
    if bpy.app.timers.is_registered(_show_progress):
        bpy.app.timers.unregister(_show_progress)
