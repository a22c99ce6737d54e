"""The pass made or reused (holo_addon/render/pipeline.py and the worker's options): a pass up to
date or of a static shot is not made again, and a render region shapes the pass."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _plate_camera_cube, _read_exr  # noqa: E402
from test_compositor import _middle, _scene_with_pass, _shown_columns  # noqa: E402


def test_the_memory_limit_preference_reaches_the_worker():
    from holo_core.worker import environment

    assert environment((), None, "6.0G")["HOLO_MEMORY_LIMIT"] == "6.0G"
    unset = environment((), None, None).get("HOLO_MEMORY_LIMIT")
    assert unset == __import__("os").environ.get("HOLO_MEMORY_LIMIT")  # not overridden


def test_a_render_cropped_to_an_off_centre_border_gets_the_border_of_the_pass(
    empty_scene, tmp_path
):
    """Crop to Render Region: the pass has the cropped render's size and shows the cube where
    the full frame's pass has it, shifted by the region's corner (within a pixel)."""
    from holo_addon.render import pipeline

    scene = empty_scene
    _scene_with_pass(scene, tmp_path)
    full = pipeline.pass_file(pipeline.output_dir(scene), 1)
    full_alpha = _read_exr(full)["ViewLayer.Combined.A"]
    full_mid = _middle(full)
    scene.render.use_border = scene.render.use_crop_to_border = True
    scene.render.border_min_x, scene.render.border_max_x = 0.25, 0.9
    scene.render.border_min_y, scene.render.border_max_y = 0.1, 0.8
    scene.render.filepath = str(tmp_path / "crop.exr")
    bpy.ops.render.render(write_still=True)
    crop = _read_exr(full)
    rendered = _read_exr(tmp_path / "crop.exr")["R"]
    assert crop["ViewLayer.Combined.A"].shape == rendered.shape, (rendered.shape, full_alpha.shape)
    x0 = int(0.25 * 48)
    got = _middle(full) + x0
    print(f"crop: pass {rendered.shape[::-1]} px, cube middle {got} vs full frame {full_mid}")
    assert abs(got - full_mid) <= 1.0
    assert _shown_columns(tmp_path / "crop.exr").size, "the cropped composite shows the cube"


def test_an_up_to_date_pass_is_not_rendered_again(empty_scene, worker_frames):
    """The frame's pass carries a digest of what it was made from: the same scene renders
    nothing again; any change (here the exposure) renders anew."""
    from holo_addon.render import pipeline

    scene = empty_scene
    _plate_camera_cube(scene)
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.holo.samples = 2
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and worker_frames == [1]
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and worker_frames == [1]
    scene.holo.exposure = 1.0
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and worker_frames == [1, 1]
    assert pipeline.cached_pass(pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get()))
    # a camera hologram renders points and triangles alike: switching the kind is no change
    cube = next(o for o in scene.objects if o.holo.emitter == "POINTS")
    cube.holo.emitter = "TRIANGLES"
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and worker_frames == [1, 1]


def test_a_render_region_without_crop_clears_the_pass_outside_it(empty_scene, tmp_path):
    """Blender renders only inside the region: the pass matches the full frame's inside and
    is clear outside, so no holographic object floats over the unrendered part."""
    from holo_addon.render import pipeline

    scene = empty_scene
    _scene_with_pass(scene, tmp_path)
    path = pipeline.pass_file(pipeline.output_dir(scene), 1)
    full = _read_exr(path)["ViewLayer.Combined.A"]
    scene.render.use_border, scene.render.use_crop_to_border = True, False
    scene.render.border_min_x, scene.render.border_max_x = 0.0, 0.5
    scene.render.border_min_y, scene.render.border_max_y = 0.0, 1.0
    scene.render.filepath = str(tmp_path / "region.exr")
    bpy.ops.render.render(write_still=True)
    region = _read_exr(path)["ViewLayer.Combined.A"]
    assert region.shape == full.shape and full[:, 24:].any()
    assert np.array_equal(region[:, :24], full[:, :24]) and not region[:, 24:].any()


def test_a_static_shot_is_made_once_and_each_frame_stays_pure(empty_scene, tmp_path, worker_frames):
    """Frames 1-3 of a shot where nothing moves: one worker; frames 2 and 3 reuse frame 1's
    pass pixel for pixel (their digests differ in the frame number alone), each file carrying
    its own frame's digest. Frame 3 rendered alone, into an empty folder (a farm's node), gives
    the same pixels. The cube moving at frame 4 makes frame 4 anew."""
    from holo_addon.render import pipeline

    scene = empty_scene
    cube, _, _ = _plate_camera_cube(scene)
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.holo.samples, scene.holo.lighting = 2, "ALBEDO"
    for frame in (1, 2, 3):
        scene.frame_set(frame)
        assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert worker_frames == [1], worker_frames
    out = pipeline.output_dir(scene)
    first = _read_exr(pipeline.pass_file(out, 1))
    for frame in (2, 3):
        again = _read_exr(pipeline.pass_file(out, frame))
        assert all(np.array_equal(first[k], again[k]) for k in first), f"frame {frame}"
        scene.frame_set(frame)
        key = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get()).job.output
        assert pipeline.stored_key(pipeline.pass_file(out, frame)) == key.pass_key
    scene.holo.output_dir = str(tmp_path / "alone") + "/"
    scene.frame_set(3)
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and worker_frames == [1, 3]
    alone = _read_exr(pipeline.pass_file(tmp_path / "alone", 3))
    assert all(np.array_equal(first[k], alone[k]) for k in first), "frame 3 alone differs"
    scene.holo.output_dir = str(out) + "/"
    cube.keyframe_insert("location", frame=3)
    cube.location.x += 0.1
    cube.keyframe_insert("location", frame=4)
    scene.frame_set(4)
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and worker_frames == [1, 3, 4]
