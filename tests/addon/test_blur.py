"""Depth of field and motion blur composited against Cycles' frame of the same scene with the
holographic object an ordinary one: a defocused holographic card spilling over the raster
behind it, a defocused raster card in front blurring over it, at f/1.2 and f/2.8 and at unit
scales 0.01, 1 and 100; the composite of an opaque scene opaque, its soft edges as Cycles'
and a transparent film's alpha as Cycles gives it, in Camera and Plate mode; and the card
moving during the shutter (bpy in-process)."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _flat_plane, _read_exr  # noqa: E402

SIZE = (320, 180)
ROWS = slice(60, 120)  # rows clear of every card's top and bottom
BEHIND = slice(200, 262)  # columns across the holographic card's right edge (col 231)
FRONT = slice(112, 178)  # columns across the red card's right edge (col 145)


def _cards(scene, fstop, unit=1.0):
    """Seen from 1 Blender unit before the origin, focused at the origin: a red card at 0.6
    (its right edge over the middle), the green holographic card at 2.5 (0.8 wide), a blue
    wall at 6; each shines its colour (an emission of strength 1, no light, no bounce), so
    Cycles' frame is the geometry and its blur alone. 320x180, 50 mm at ``fstop``,
    ``unit`` metres per Blender unit. Returns the green card."""
    from holo_addon.blender import compat
    from holo_addon.demo import point_at

    scene.unit_settings.scale_length = unit
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 64
    scene.cycles.max_bounces = 0
    scene.cycles.use_denoising = False
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.seed = 1
    scene.render.resolution_x, scene.render.resolution_y = SIZE
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.holo.lighting = "ALBEDO"
    compat.set_exr_output(scene, multilayer=False)
    bpy.ops.object.camera_add(location=(0, -1.0, 0))
    cam = bpy.context.object
    point_at(cam, (0, 10, 0))
    cam.data.lens = 50
    cam.data.dof.use_dof = True
    cam.data.dof.focus_distance = 1.0
    cam.data.dof.aperture_fstop = fstop
    scene.camera = cam
    _flat_plane("red", 1.0, (-0.52, -0.4, 0), (1, 0, 0))  # right edge at x = -0.02
    _flat_plane("blue", 40, (0, 5.0, 0), (0, 0, 1))
    green = _flat_plane("green", 0.8, (0, 1.5, 0), (0, 1, 0))
    for obj in scene.objects:
        if obj.type == "MESH":  # its emission alone: a black Base Color reflects nothing
            bsdf = obj.data.materials[0].node_tree.nodes["Principled BSDF"]
            bsdf.inputs["Base Color"].default_value = (
                (0, 0, 0, 1) if obj is not green else (0, 1, 0, 1)
            )
    bpy.context.view_layer.update()
    return green


def _render(scene, path):
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    image = _read_exr(path)
    return np.stack([image[c] for c in "RGBA"], -1)


def _profile(image, channel, cols):
    """The mean of ``channel`` over ROWS at ``cols``, from its level on the left (1) to its
    level on the right (0)."""
    p = image[ROWS, cols, channel].mean(0)
    left, right = p[:4].mean(), p[-4:].mean()
    return (p - right) / (left - right)


def _width(profile):
    """The 10-90 % width [px] of a falling edge profile."""
    x = np.arange(len(profile))
    return float(np.interp(-0.1, -profile, x) - np.interp(-0.9, -profile, x))


def _edges(image):
    """(the holographic card's edge over the wall, the red card's over the holographic
    card) as profiles."""
    return _profile(image, 1, BEHIND), _profile(image, 0, FRONT)


def _composite(scene, green, tmp_path, name):
    green.holo.emitter = "POINTS"
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    return _render(scene, tmp_path / f"{name}.exr")


def _compare(mine, theirs, label):
    """Each edge's 10-90 % width within 20 % of Cycles', and its profile nowhere more than
    0.08 of the step from Cycles' (a hard or stair-stepped edge is 0.3-0.5 off)."""
    out = []
    for what, a, b in zip(
        ("holographic over the wall", "red over holographic"), _edges(mine), _edges(theirs)
    ):
        wa, wb = _width(a), _width(b)
        off = float(np.abs(a - b).max())
        print(
            f"{label}: {what}: 10-90 % width {wa:.2f} px, Cycles' {wb:.2f} px "
            f"({wa / wb - 1:+.1%}); profile at most {off:.3f} off Cycles'"
        )
        out.append((what, wa, wb, off))
    for what, wa, wb, off in out:
        assert abs(wa / wb - 1) <= 0.2, f"{label}: {what}: width {wa:.2f} px, Cycles' {wb:.2f}"
        assert off <= 0.08, f"{label}: {what}: the profile is {off:.3f} off Cycles'"
    return out


@pytest.mark.parametrize("fstop", [1.2, 2.8])
def test_defocused_edges_composite_as_cycles_blurs_them(empty_scene, tmp_path, fstop):
    """Focused at 1 unit: the holographic card (at 2.5) and the red card in front of it (at
    0.6) are both out of focus. Composited, the holographic card's edge spills over the blue
    wall behind it and the red card's edge blurs over the holographic card as in Cycles'
    frame of the same cards (widths within 20 %, profiles within 0.08 of the step)."""
    scene = empty_scene
    green = _cards(scene, fstop)
    cycles = _render(scene, tmp_path / "cycles.exr")
    _compare(_composite(scene, green, tmp_path, "holo"), cycles, f"f/{fstop}")


def test_any_unit_scale_gives_the_same_pass_and_depth_of_field(empty_scene, tmp_path):
    """The same cards at unit scales 0.01, 1 and 100 (Cycles' frame is the same at each):
    the pass has the same depth layers, aperture in Blender units and image (alpha within
    1e-3, depth in scene units within 1e-4 relative), and its edges match Cycles' at each
    scale. (At 0.01 the f/2.8 lens was taken in metres: a 100x wider blur, 64 layers.)"""
    import json

    from holo_addon.render import pipeline
    from holo_core.io.image import exr_attribute

    scene = empty_scene
    green = _cards(scene, 2.8)
    cycles = _render(scene, tmp_path / "cycles.exr")
    passes = {}
    for unit in (0.01, 1.0, 100.0):
        scene.unit_settings.scale_length = unit
        mine = _composite(scene, green, tmp_path, f"holo_{unit}")
        _compare(mine, cycles, f"scale {unit}")
        path = pipeline.pass_file(pipeline.output_dir(scene), 1)
        info = json.loads(exr_attribute(path, "holo"))
        passes[unit] = (_read_exr(path), info)
        print(
            f"scale {unit}: {info['layers']} layers, aperture {info['aperture_m'] / unit:.6g} "
            f"units, {info['pupil_samples']} pupil samples"
        )
    (ref, ref_info) = passes[1.0]
    for unit, (image, info) in passes.items():
        assert info["layers"] == ref_info["layers"], (unit, info["layers"])
        assert info["pupil_samples"] == ref_info["pupil_samples"], unit
        assert info["aperture_m"] / unit == pytest.approx(ref_info["aperture_m"], rel=1e-6)
        alpha = np.abs(image["ViewLayer.Combined.A"] - ref["ViewLayer.Combined.A"]).max()
        seen = ref["ViewLayer.Combined.A"] > 0.5
        depth = np.abs(image["ViewLayer.Depth.Z"][seen] / ref["ViewLayer.Depth.Z"][seen] - 1)
        assert alpha <= 1e-3, (unit, alpha)
        assert depth.max() <= 1e-4, (unit, depth.max())


def _ring(silhouette, width=2):
    """The pixels within ``width`` px of ``silhouette``'s edge, either side of it."""
    from scipy import ndimage

    return ndimage.binary_dilation(silhouette, iterations=width) & ~ndimage.binary_erosion(
        silhouette, iterations=width
    )


@pytest.mark.parametrize("mode", ["CAMERA", "PLATE"])
def test_an_opaque_scene_composites_opaque_with_edges_as_cycles_frame(empty_scene, tmp_path, mode):
    """The cards before the wall (an opaque scene), the holographic card through its camera
    hologram at f/2.8 or a plate's view at f/16 in a 96x54 frame (a plate's views are sharper
    than Cycles' f/2.8 blur: 2.4 % off on this ring, 4.6 % just outside the card): every pixel of
    the composite has alpha 1 (the pass's soft edge is narrower than Cycles' hole in places,
    which left 1,261 pixels below 0.99 in Camera mode), and over a 2-pixel ring around the
    card's silhouette in Cycles' frame of the same card the green differs from Cycles' by at
    most 2 % of the card's green on average."""
    from holo_addon.demo import point_at

    scene = empty_scene
    green = _cards(scene, 2.8 if mode == "CAMERA" else 16.0)
    if mode == "PLATE":  # half way to the card, covering its view; a small frame, a small plate
        scene.render.resolution_x, scene.render.resolution_y = 96, 54
        bpy.ops.mesh.primitive_plane_add(size=0.7, location=(0, 0.25, 0))
        plate = bpy.context.object
        point_at(plate, (0, 10, 0))  # its −Z away from the camera: +Z faces it
        plate.holo.is_plate = True
        scene.holo.mode, scene.holo.iterations = "PLATE", 1
    cycles = _render(scene, tmp_path / "cycles.exr")
    mine = _composite(scene, green, tmp_path, "holo")
    alpha = mine[..., 3]
    short = int((alpha < 0.99).sum())
    assert short == 0, (
        f"{short} pixels of an opaque scene's composite have alpha < 0.99 "
        f"(down to {alpha.min():.3f})"
    )
    card = cycles[..., 1] > 0.5
    ring = _ring(card)
    off = float(np.abs(mine[..., 1] - cycles[..., 1])[ring].mean())
    level = float(cycles[..., 1][card].mean())
    print(
        f"{mode}: ring of {ring.sum()} px: mean |green - Cycles'| {off:.4f}, "
        f"{off / level:.2%} of the card's {level:.3f}"
    )
    assert off <= 0.02 * level, f"the edge is {off / level:.2%} of the card's green off Cycles'"


def test_a_transparent_film_keeps_cycles_alpha(empty_scene, tmp_path):
    """Film ▸ Transparent, no wall: the composite's alpha is Cycles' alpha of the same card
    (mean difference at most 0.01), and the world 4 px or more from the card stays clear
    (alpha below 0.01): the hole is not filled where the world is transparent. The
    compositing was set up while the film was opaque: the render follows the film as it is."""
    scene = empty_scene
    green = _cards(scene, 2.8)
    bpy.data.objects["blue"].hide_render = True
    scene.render.film_transparent = True
    cycles = _render(scene, tmp_path / "cycles.exr")
    scene.render.film_transparent = False
    green.holo.emitter = "POINTS"
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    scene.render.film_transparent = True
    mine = _render(scene, tmp_path / "holo.exr")
    off = float(np.abs(mine[..., 3] - cycles[..., 3]).mean())
    from scipy import ndimage

    world = ~ndimage.binary_dilation(cycles[..., 3] > 0.01, iterations=4)
    filled = int((mine[..., 3][world] >= 0.01).sum())
    print(
        f"transparent film: mean |alpha - Cycles'| {off:.4f}; {filled} of {world.sum()} "
        f"world pixels with alpha >= 0.01"
    )
    assert off <= 0.01, f"the composite's alpha is {off:.4f} off Cycles' on average"
    assert filled == 0, f"{filled} pixels of the transparent world were filled"


def move(obj, speed):
    """``obj`` moving along x at ``speed`` units a frame, exactly (a driver on the frame: no
    easing), through x = 0 at frame 2."""
    curve = obj.driver_add("location", 0)
    curve.driver.type = "SCRIPTED"
    curve.driver.expression = f"(frame - 2) * {speed}"  # a simple expression: no Python


def test_a_moving_card_is_blurred_as_cycles_blurs_it(empty_scene, tmp_path, worker_frames):
    """The holographic card moves 0.1 units a frame (18 px) across a pinhole's view, Cycles'
    motion blur on (shutter 0.5 frame, centred): composited, both its edges fade over the
    wall as Cycles' frame of the ordinary card does (10-90 % widths within 20 %, profiles
    within 0.08 of the step). The render's own frame handler, which collects the sub-frames
    Blender evaluates for the raster's blur, makes the same pass as Render Pass (bit for
    bit), in one worker."""
    from holo_addon.render import pipeline

    scene = empty_scene
    green = _cards(scene, 2.8)
    scene.camera.data.dof.use_dof = False
    bpy.data.objects["red"].hide_render = True
    move(green, 0.1)
    scene.render.use_motion_blur = True
    scene.frame_set(2)
    cycles = _render(scene, tmp_path / "cycles.exr")
    mine = _composite(scene, green, tmp_path, "holo")
    path = pipeline.pass_file(pipeline.output_dir(scene), 2)
    made = _read_exr(path)
    widths = []
    for side, cols, sign in (("right", slice(205, 258), 1), ("left", slice(62, 115), -1)):
        a, b = (
            _profile(
                im[:, ::sign],
                1,
                cols if sign > 0 else slice(SIZE[0] - cols.stop, SIZE[0] - cols.start),
            )
            for im in (mine, cycles)
        )
        wa, wb, off = _width(a), _width(b), float(np.abs(a - b).max())
        print(
            f"moving card, {side} edge: 10-90 % width {wa:.2f} px, Cycles' {wb:.2f} px "
            f"({wa / wb - 1:+.1%}); profile at most {off:.3f} off Cycles'"
        )
        widths.append((side, wa, wb, off))
    for side, wa, wb, off in widths:
        assert wb > 5, f"{side}: Cycles' edge is {wb:.2f} px: no motion blur to compare"
        assert abs(wa / wb - 1) <= 0.2, f"{side} edge: width {wa:.2f} px, Cycles' {wb:.2f}"
        assert off <= 0.08, f"{side} edge: the profile is {off:.3f} off Cycles'"
    path.unlink()
    workers = worker_frames[:]
    _render(scene, tmp_path / "again.exr")
    again = _read_exr(path)
    assert worker_frames == workers + [2], worker_frames
    assert all(np.array_equal(made[k], again[k]) for k in made), "the render's pass differs"
