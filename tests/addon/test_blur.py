"""Depth of field and motion blur composited against Cycles' frame of the same scene with the
holographic object an ordinary one: a defocused holographic card spilling over the raster
behind it, a defocused raster card in front blurring over it, at f/1.2 and f/2.8 and at unit
scales 0.01, 1 and 100; and the card moving during the shutter (bpy in-process)."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _flat_plane, _read_exr  # noqa: E402

SIZE = (320, 180)
ROWS = slice(60, 120)           # rows clear of every card's top and bottom
BEHIND = slice(200, 262)        # columns across the holographic card's right edge (col 231)
FRONT = slice(112, 178)         # columns across the red card's right edge (col 145)


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
    _flat_plane("red", 1.0, (-0.52, -0.4, 0), (1, 0, 0))   # right edge at x = -0.02
    _flat_plane("blue", 40, (0, 5.0, 0), (0, 0, 1))
    green = _flat_plane("green", 0.8, (0, 1.5, 0), (0, 1, 0))
    for obj in scene.objects:
        if obj.type == "MESH":  # its emission alone: a black Base Color reflects nothing
            bsdf = obj.data.materials[0].node_tree.nodes["Principled BSDF"]
            bsdf.inputs["Base Color"].default_value = (0, 0, 0, 1) if obj is not green else \
                (0, 1, 0, 1)
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
    for what, a, b in zip(("holographic over the wall", "red over holographic"),
                          _edges(mine), _edges(theirs)):
        wa, wb = _width(a), _width(b)
        off = float(np.abs(a - b).max())
        print(f"{label}: {what}: 10-90 % width {wa:.2f} px, Cycles' {wb:.2f} px "
              f"({wa / wb - 1:+.1%}); profile at most {off:.3f} off Cycles'")
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
        print(f"scale {unit}: {info['layers']} layers, aperture {info['aperture_m'] / unit:.6g} "
              f"units, {info['pupil_samples']} pupil samples")
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
        a, b = (_profile(im[:, ::sign], 1, cols if sign > 0 else
                         slice(SIZE[0] - cols.stop, SIZE[0] - cols.start)) for im in (mine, cycles))
        wa, wb, off = _width(a), _width(b), float(np.abs(a - b).max())
        print(f"moving card, {side} edge: 10-90 % width {wa:.2f} px, Cycles' {wb:.2f} px "
              f"({wa / wb - 1:+.1%}); profile at most {off:.3f} off Cycles'")
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

