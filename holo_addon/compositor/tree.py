"""The holographic pass in Blender's compositor.

Emitters are holdouts in the raster (:func:`holo_addon.blender.objects.raster_visibility`):
Blender's render leaves a hole where a holographic object is the nearest surface, cut by its
own depth of field and motion blur, so a defocused raster object in front spills over the
hole and one behind is covered. The pass P (premultiplied, its alpha the pupil's blurred
coverage) fills that hole: with R the raster (premultiplied) and a its alpha,

    composite = R + k·P,   k = (1 − a) / max(P.alpha, MIN_COVERAGE),

per channel, alpha included. The hole is Blender's matte of the holographic object, so the
pass's colour fills it whole and a soft edge (anti-aliasing, depth of field, motion blur)
blends with what Blender's render sees beside and behind it, as Blender's own frame of the
object does; where a raster object covers part of the hole's rays, the pass shows that share
of its colour. Where the pass is too faint to fill the hole (its alpha below
``MIN_COVERAGE``), the rest shows the raster's own colour in that pixel, R·(1 + rest/a): an
opaque scene composites opaque wherever either covers the pixel. With Film ▸ Transparent the
hole cannot be told from the transparent world, so k = min(1, (1 − a)/P.alpha) and nothing
is filled: the pass as it is over the alpha Blender gives (:func:`follow_film` keeps the
blend to the film). A Depth output keeps the nearer of the two depths. A File Output node
writes the composite, the pass and both depths as a multilayer EXR beside each rendered frame
(:func:`beside_render`). The pass is read as an image sequence, so every frame composites its
own, from the .blend's current output folder (:func:`point_passes`).
"""

from __future__ import annotations

import os
from pathlib import Path

import bpy

from ..blender import compat
from ..blender.images import save_as_displayed
from ..blender.objects import raster_visibility
from ..render import pipeline

NODE_PREFIX = "Holo "
# The layers of the multilayer EXR written beside each rendered frame: the composite, the
# holographic pass alone and its depth, and the composite's depth (the nearer of the two).
LAYERS = (("Composite", "RGBA"), ("Holo", "RGBA"), ("HoloDepth", "FLOAT"), ("Depth", "FLOAT"))
DEPTHS = ("HoloDepth", "Depth")  # Blender's File Output names them .V; Blender's passes, .Z
BEFORE = "holo_compositor_before"  # on the scene: its compositing before the first setup
MAX_FRAME = 1048574  # Blender's last frame
RASTER = NODE_PREFIX + "Raster"  # what fed the compositor's output, split into channels
LEGACY = NODE_PREFIX + "Depth Combine"  # the tree of earlier versions (its input 2: the user's)
OPAQUE = ("Opaque", "Opaque Beside")  # the nodes whose input 0 is the film's opacity
MIN_COVERAGE = 1e-3  # an alpha below which a colour is too faint to fill a hole


def _output(node, *names):
    for name in names:
        if name in node.outputs and node.outputs[name].enabled:
            return node.outputs[name]
    raise ValueError(f"node '{node.name}' has no output {' or '.join(names)}")


def _source(tree):
    """The socket that fed the add-on's nodes from the user's compositing (None: nothing of
    the user's, Render Layers' image)."""
    for name, index in ((RASTER, 0), (LEGACY, 2)):
        node = tree.nodes.get(name)
        if node is not None:
            feed = node.inputs[index]
            source = feed.links[0].from_socket if feed.is_linked else None
            return None if source is None or source.node.name.startswith(NODE_PREFIX) else source
    feed = compat.output_socket(tree)
    return feed.links[0].from_socket if feed.is_linked else None


def setup(scene, folder: Path):
    """Add the holographic pass (the frame's ``holo_pass_NNNN.exr`` in ``folder``) to the
    scene's compositor as the module docstring says; enables the view layer's Depth pass and
    makes every emitter a holdout in the raster. The user's own nodes and links stay:
    whatever fed the compositor's output now feeds the composite. The add-on's nodes sit in a
    frame named "Holo: holographic pass"; running this again rebuilds only them. Before the
    current frame has a pass, a clear one is written, from which the node takes its sockets
    (the render makes the real one)."""
    first = pipeline.pass_file(folder, scene.frame_current)
    if not first.is_file():
        pipeline.clear_pass(scene, scene.frame_current)
    if BEFORE not in scene:  # what Remove Holo Compositing puts back
        scene[BEFORE] = {
            **compat.compositor_state(scene),
            "depth": {layer.name: int(layer.use_pass_z) for layer in scene.view_layers},
        }
    for layer in scene.view_layers:
        layer.use_pass_z = True
    for obj in scene.objects:
        if obj.type == "MESH" and (obj.holo.emitter != "NONE" or obj.holo.is_plate):
            raster_visibility(obj)
    tree = compat.compositor_tree(scene)
    source = _source(tree)
    for node in [n for n in tree.nodes if n.name.startswith(NODE_PREFIX)]:
        tree.nodes.remove(node)
    frame = tree.nodes.new("NodeFrame")
    frame.name, frame.label = NODE_PREFIX + "Frame", "Holo: holographic pass"

    def new(idname, name, at, **settings):
        node = tree.nodes.new(idname)
        node.name = node.label = NODE_PREFIX + name
        node.parent, node.location = frame, at
        for key, value in settings.items():
            setattr(node, key, value)
        return node

    def math(name, operation, at, *inputs, clamp=False):
        node = compat.math_node(tree, operation, clamp=clamp)
        node.name = node.label = NODE_PREFIX + name
        node.parent, node.location = frame, at
        for socket, value in zip(node.inputs, inputs):
            if isinstance(value, float):
                socket.default_value = value
            else:
                tree.links.new(value, socket)
        return node.outputs[0]

    layers = new("CompositorNodeRLayers", "Render Layers", (-700, 300), scene=scene)
    holo = new(
        "CompositorNodeImage",
        "Pass",
        (-700, -200),
        image=pass_image(first),
        frame_start=1,
        frame_offset=0,
        frame_duration=MAX_FRAME,  # file = frame
        use_auto_refresh=True,
    )
    raster = new("CompositorNodeSeparateColor", "Raster", (-450, 300))
    split = new("CompositorNodeSeparateColor", "Split", (-450, -200))
    tree.links.new(source or _output(layers, "Image"), raster.inputs[0])
    tree.links.new(_output(holo, "Combined", "Image"), split.inputs[0])
    clear = math("Clear", "SUBTRACT", (-250, 100), 1.0, raster.outputs[3])
    share = math("Share", "DIVIDE", (-100, 100), clear, split.outputs[3], clamp=True)
    coverage = math("Coverage", "MAXIMUM", (-250, -50), split.outputs[3], MIN_COVERAGE)
    matte = math("Matte", "DIVIDE", (-100, -50), clear, coverage)
    share = math(
        "Opaque",
        "MULTIPLY_ADD",
        (-100, 0),
        opacity(scene),
        math("Fill", "SUBTRACT", (-100, -100), matte, share),
        share,
    )
    # the hole's share the pass is too faint to fill (its coverage below MIN_COVERAGE) shows
    # the raster's own colour in the pixel: R scaled by 1 + rest / a
    left = math(
        "Rest",
        "SUBTRACT",
        (-250, -200),
        clear,
        math("Filled", "MULTIPLY", (-400, -300), share, split.outputs[3]),
    )
    beside = math(
        "Beside",
        "DIVIDE",
        (-100, -200),
        left,
        math("Seen", "MAXIMUM", (-250, -300), raster.outputs[3], MIN_COVERAGE),
    )
    scale = math("Opaque Beside", "MULTIPLY_ADD", (-100, -300), opacity(scene), beside, 1.0)
    combine = new("CompositorNodeCombineColor", "Composite", (250, 100))
    for c in range(4):
        seen = math(
            "Raster " + "RGBA"[c], "MULTIPLY", (50, 200 - 100 * c), scale, raster.outputs[c]
        )
        tree.links.new(
            math("RGBA"[c], "MULTIPLY_ADD", (150, 250 - 100 * c), share, split.outputs[c], seen),
            combine.inputs[c],
        )
    depth = math(
        "Depth", "MINIMUM", (50, -250), _output(layers, "Depth", "Z"), _output(holo, "Depth", "Z")
    )
    tree.links.new(combine.outputs[0], compat.output_socket(tree))
    files = compat.multilayer_output(
        tree, NODE_PREFIX + "File Output", beside_render(scene), LAYERS
    )
    files.parent, files.location = frame, (450, -250)
    for socket, layer in zip(
        (
            combine.outputs[0],
            _output(holo, "Combined", "Image"),
            _output(holo, "Depth", "Z"),
            depth,
        ),
        files.inputs,
    ):
        tree.links.new(socket, layer)
    return combine


def opacity(scene) -> float:
    """1 where Blender's raster is opaque but for its holes (the world drawn), 0 where its
    alpha is the film's (Film ▸ Transparent): which share of the hole the pass fills."""
    return 0.0 if scene.render.film_transparent else 1.0


def follow_film(scene) -> None:
    """The blend follows the film as it is now (Film ▸ Transparent turned on or off since the
    setup)."""
    tree = compat.existing_compositor_tree(scene)
    for name in OPAQUE:
        node = tree.nodes.get(NODE_PREFIX + name) if tree is not None else None
        if node is not None:
            node.inputs[0].default_value = opacity(scene)


def pass_image(path: Path):
    """The image sequence of holographic passes whose frame file is ``path``."""
    image = bpy.data.images.load(str(path), check_existing=True)
    image.source = "SEQUENCE"
    image.reload()
    return image


def passes_images():
    """The image sequences of holographic passes in the file."""
    return [
        image
        for image in bpy.data.images
        if image.source == "SEQUENCE" and Path(image.filepath).name.startswith("holo_pass_")
    ]


def point_passes(scene, frame: int | None = None, *, rendering=False) -> Path | None:
    """The compositor's image sequences of holographic passes read the .blend's own output
    folder as it is now (after *Save As* into another folder, or another Output Folder), so
    a frame never composites a pass of another folder or file; a pass rewritten is read
    again. ``rendering``: a render is about to composite the frame, which gets a clear pass
    where it has none yet (an Image node whose file is missing shows grey, and keeps failing
    for the rest of the render). Returns the frame's pass file (None where the folder is not
    known: an unsaved .blend with a relative folder)."""
    frame = scene.frame_current if frame is None else frame
    try:
        path = pipeline.pass_file(pipeline.output_dir(scene), frame)
    except ValueError:
        return None
    try:
        if rendering and not path.is_file():
            pipeline.clear_pass(scene, frame)  # OSError: a folder that cannot be written
    finally:  # the images follow the folder even then: never another folder's pass
        read_passes_from(path)
    return path


def read_passes_from(path: Path) -> None:
    """The compositor's image sequences of holographic passes read ``path`` (a frame's pass
    file; the sequence finds the other frames beside it), read again."""
    for image in passes_images():
        if Path(bpy.path.abspath(image.filepath)) != path:
            image.filepath = str(path)
        image.reload()


def pass_made(scene, result) -> Path | None:
    """A pass was made or found up to date (an operator's, a render's): the compositor reads
    it, and its PNG preview is written through the scene's view transform as it is now (the
    worker, which has no colour management, wrote plain sRGB). Returns its file (None: no
    pass)."""
    path = result.pass_path
    if path is None:
        return None
    point_passes(scene)
    save_as_displayed(scene, path, path.with_suffix(".png"))
    return path


def remove(scene) -> bool:
    """Take the add-on's nodes out of the scene's compositor and put back what the user had:
    whatever fed the composite feeds the output again, every other node and link of the
    user's stays, a tree the add-on made is removed, and the view layers' Depth passes are as
    they were. Returns whether there was anything to remove."""
    tree = compat.existing_compositor_tree(scene)
    ours = [n for n in tree.nodes if n.name.startswith(NODE_PREFIX)] if tree is not None else []
    before = scene.get(BEFORE)
    if not ours and before is None:
        return False
    source = _source(tree) if ours else None
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


def uses_pass(scene) -> bool:
    tree = compat.existing_compositor_tree(scene)
    return tree is not None and tree.nodes.get(NODE_PREFIX + "Pass") is not None


def layers_file(scene, frame: int) -> list[Path]:
    """The multilayer EXR files the File Output node may have written for ``frame``: with
    the frame's number (animations) or without (5.x stills)."""
    prefix = bpy.path.abspath(beside_render(scene))
    return [Path(f"{prefix}{frame:04d}.exr"), Path(f"{prefix}.exr")]


def follow_render_output(scene) -> None:
    """The holographic layers follow the render output's path as it is now (``-o`` on a
    farm, or a path changed since the setup)."""
    tree = compat.existing_compositor_tree(scene)
    node = tree.nodes.get(NODE_PREFIX + "File Output") if tree is not None else None
    if node is not None:
        compat.set_output_path(node, beside_render(scene))


def name_depths_z(path: Path) -> bool:
    """Rename the depth layers' channels of the layers file ``path`` from ``.V`` (what
    Blender's File Output names a value) to ``.Z`` (what Blender's render passes and
    compositing programs call depth); rewritten atomically. Returns whether it renamed."""
    import OpenEXR

    from holo_core.io.image import atomic_path

    with OpenEXR.File(str(path), separate_channels=True) as f:
        parts, renamed = [], False
        for part in f.parts:
            header = {k: v for k, v in part.header.items() if k not in ("channels", "chunkCount")}
            channels = {}
            for name, c in part.channels.items():
                layer, _, channel = name.rpartition(".")
                new = f"{layer}.Z" if layer in DEPTHS and channel == "V" else name
                renamed |= new != name
                channels[new] = OpenEXR.Channel(
                    new, c.pixels.copy(), c.xSampling, c.ySampling, c.pLinear
                )
            parts.append(OpenEXR.Part(header, channels, part.name()))
    if renamed:
        with atomic_path(path) as tmp:
            OpenEXR.File(parts).write(tmp)
    return renamed


def holes(path: Path) -> int:
    """The pixels of the layers file ``path`` whose composite's alpha is below 0.99."""
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        for part in f.parts:
            alpha = part.channels.get("Composite.A")
            if alpha is not None:
                return int((alpha.pixels < 0.99).sum())
    return 0


def beside_render(scene) -> str:
    """Where the frame's holographic layers go: the render output's folder, under the output's
    file name prefixed by ``holo_`` (its ``#`` frame digits and image extension dropped:
    Blender adds the frame), e.g. ``//out/shot_####`` → ``//out/holo_shot_0001.exr``."""
    folder, name = os.path.split(scene.render.filepath)
    stem, ext = os.path.splitext(name)
    if ext.lower() in bpy.path.extensions_image:
        name = stem
    return os.path.join(folder or "//", "holo_" + name.replace("#", ""))
