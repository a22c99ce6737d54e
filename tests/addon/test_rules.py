"""Rules of Blender an artist and a render farm rely on (bpy in-process, and background
Blender processes where the exit status is the point)."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _plate_camera_cube, _raster_alpha_and_depth, _read_exr  # noqa: E402
from test_compositor import BACKGROUND, BACKGROUND_SCENE, in_background  # noqa: E402

from holo_addon.blender.objects import show_as_raster  # noqa: E402


def test_the_pass_depth_is_in_scene_units(empty_scene, tmp_path):
    """1 Blender unit = 1 cm: the pass's depth is in scene units, as Blender's Depth pass is,
    so the depth merge compares like with like (median error over the object <= 0.5 % of its
    depth extent in Blender's Depth pass; in metres it was 100 times too small)."""
    from holo_addon.render import pipeline

    scene = empty_scene
    scene.unit_settings.scale_length = 0.01
    cube, cam, plate = _plate_camera_cube(scene, cube_size=50)
    cube.rotation_euler = (0.5, 0.3, 0.2)
    cam.location = (0, -300, 0)
    cam.data.clip_end = 1000
    cam.data.lens = 100
    plate.location, plate.scale = (0, -150, 0), (100, 100, 100)
    scene.render.resolution_x, scene.render.resolution_y = 96, 72
    scene.holo.samples = 2
    bpy.context.view_layer.update()
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    holo = _read_exr(pipeline.pass_file(pipeline.output_dir(scene), 1))
    show_as_raster(cube)
    alpha, depth = _raster_alpha_and_depth(scene, tmp_path)
    both = (holo["ViewLayer.Combined.A"] > 0.5) & (alpha > 0.5) & (depth < 1e9)
    extent = np.ptp(depth[both])
    err = np.median(np.abs(holo["ViewLayer.Depth.Z"][both] - depth[both])) / extent
    print(
        f"scale_length 0.01: median depth error {err:.2%} of {extent:.1f} units ({both.sum()} px)"
    )
    assert both.sum() > 100 and err <= 0.005, f"median depth error {err:.2%} of {extent:.1f}"


def _faceless(scene, name="Wire"):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([(0, 0, 0), (0.2, 0, 0), (0.2, 0.2, 0)], [(0, 1), (1, 2)], [])
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    obj.holo.emitter = "POINTS"
    return obj


def test_a_failing_emitter_is_a_warning_naming_it_while_the_rest_renders(empty_scene):
    """A second emitter without faces: the pass is made of the cube, with a warning naming
    the wire; alone, the wire gives the no-emitter error, which names it too."""
    from holo_addon.export.scene import NoEmitters
    from holo_addon.render import pipeline

    scene = empty_scene
    cube, _, _ = _plate_camera_cube(scene)
    _faceless(scene)
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.holo.samples = 2
    job = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get())
    assert len(job.job.points) == 1
    (warning,) = [w for w in job.warnings if "Wire" in w]
    assert "emitter 'Wire' is left out" in warning and "no faces" in warning, warning
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    alpha = _read_exr(pipeline.pass_file(pipeline.output_dir(scene), 1))["ViewLayer.Combined.A"]
    assert (alpha > 0.5).sum() > 20, "the cube is in the pass"
    cube.holo.emitter = "NONE"
    with pytest.raises(NoEmitters, match="emitter 'Wire' is left out"):
        pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get())


def _composited_cube(scene, size=(48, 36)):
    """The helper cube under a sun, its pass made and composited; Cycles at 4 samples."""
    from holo_addon.blender import compat

    cube, cam, plate = _plate_camera_cube(scene, cube_size=0.4)
    bpy.ops.object.light_add(type="SUN", rotation=(np.radians(60), 0, 0))
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 4
    scene.holo.samples = 2
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    compat.set_exr_output(scene, multilayer=False)
    return cube, cam, plate


def test_a_crop_gives_a_pass_of_exactly_the_crops_size(empty_scene, tmp_path):
    """160x120 cropped to (7/160 .. 135/160, 5/120 .. 113/120): Blender renders 128x108 (each
    edge is border x size in single precision, truncated); the pass is 128x108 too (it was
    129x107) and shows the cube where the full frame has it, shifted by the crop's corner."""
    from holo_addon.render import pipeline

    scene = empty_scene
    _composited_cube(scene, size=(160, 120))
    path = pipeline.pass_file(pipeline.output_dir(scene), 1)
    full = _read_exr(path)["ViewLayer.Combined.A"] > 0.5
    r = scene.render
    r.use_border = r.use_crop_to_border = True
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = (
        7 / 160,
        135 / 160,
        5 / 120,
        113 / 120,
    )
    r.filepath = str(tmp_path / "crop.exr")
    bpy.ops.render.render(write_still=True)
    rendered = _read_exr(tmp_path / "crop.exr")["R"].shape
    crop = _read_exr(path)["ViewLayer.Combined.A"] > 0.5
    print(f"crop: Blender {rendered[::-1]}, pass {crop.shape[::-1]}")
    assert rendered == crop.shape == (108, 128), (rendered, crop.shape)
    top = 120 - int(np.float32(r.border_max_y) * np.float32(120))
    rows, cols = np.nonzero(full)
    crows, ccols = np.nonzero(crop)
    shift = (crows.mean() + top - rows.mean(), ccols.mean() + 7 - cols.mean())
    assert np.abs(shift).max() <= 1.0, f"the cube is {shift} px off in the cropped pass"


def test_emitters_hidden_in_the_viewport_are_recorded_as_the_render_draws_them(empty_scene):
    """Hidden with H, disabled in viewports, or in a collection hidden in the viewport, an
    emitter still renders, so Render Pass records it (and leaves it hidden); disabled in
    renders, it is left out and the refusal says so."""
    from holo_addon.render import pipeline

    scene = empty_scene
    cube, _, _ = _plate_camera_cube(scene)
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.holo.samples = 2
    path = pipeline.pass_file(pipeline.output_dir(scene), 1)
    collection = bpy.data.collections.new("Hidden")
    scene.collection.children.link(collection)
    collection.objects.link(cube)
    layer = bpy.context.view_layer.layer_collection.children["Hidden"]
    for hide, show, hidden in (
        (lambda: cube.hide_set(True), lambda: cube.hide_set(False), cube.hide_get),
        (
            lambda: setattr(cube, "hide_viewport", True),
            lambda: setattr(cube, "hide_viewport", False),
            lambda: cube.hide_viewport,
        ),
        (
            lambda: setattr(layer, "hide_viewport", True),
            lambda: setattr(layer, "hide_viewport", False),
            lambda: layer.hide_viewport,
        ),
    ):
        hide()
        path.unlink(missing_ok=True)
        assert bpy.ops.holo.render_pass() == {"FINISHED"}
        assert (_read_exr(path)["ViewLayer.Combined.A"] > 0.5).sum() > 20
        assert hidden(), "left hidden as the user had it"
        show()
    cube.hide_render = True
    with pytest.raises(RuntimeError, match="no holographic emitters in the render"):
        bpy.ops.holo.render_pass()


def _warnings(caplog):
    return [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]


def test_f12_without_compositing_warns_in_blenders_report(empty_scene, tmp_path, caplog):
    """An emitter and no Set Up Compositing: F12 warns (the log, Render ▸ Holo, and Blender's
    reports in the interface) naming the object and the fix, instead of a silent vanish."""
    from holo_addon.compositor.session import session

    scene = empty_scene
    _plate_camera_cube(scene)
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.render.filepath = str(tmp_path / "f12.png")
    bpy.ops.render.render(write_still=True)
    (warning,) = [w for w in _warnings(caplog) if "not in this render" in w]
    assert "'Cube'" in warning and "Set Up Compositing" in warning, warning
    assert warning in session.warnings["texts"]
    assert bpy.ops.holo.report(message=warning, level="WARNING") == {"FINISHED"}


def test_layers_follow_the_output_path_at_render_time(empty_scene, tmp_path):
    """Compositing set up with the output //out/shot_####, then the output changed (as a
    farm's -o does): the holographic layers go beside the new output, not the old one."""
    scene = empty_scene
    _composited_cube(scene)
    scene.render.filepath = str(tmp_path / "farm" / "take_")
    scene.frame_start = scene.frame_end = 1
    bpy.ops.render.render(animation=True)
    written = sorted(
        p.name for p in tmp_path.rglob("holo_*.exr") if not p.name.startswith("holo_pass_")
    )
    assert written == ["holo_take_0001.exr"], written
    assert (tmp_path / "farm" / "holo_take_0001.exr").is_file()


def test_motion_blur_in_plate_mode_warns_once_and_makes_one_pass_per_frame(
    empty_scene, tmp_path, caplog, worker_frames
):
    """Motion blur on in Plate mode (a plate is recorded once for many frames, unblurred),
    -a over frames 1-3 of a moving cube: Blender evaluates each frame at its shutter's steps
    (sub-frames), but one pass per frame is made (3 workers, was 11), each of its own
    frame's geometry (its silhouette within half a pixel of the frame's projection: no
    in-between geometry left in the files), and one warning says the holographic object is
    not blurred. (Camera mode blurs it: tests/addon/test_blur.py.)"""
    from test_addon import _camera_columns
    from test_compositor import _middle, _moving_cube

    from holo_addon.render import pipeline

    scene = empty_scene
    _, cam = _moving_cube(scene, tmp_path)
    scene.frame_set(1)
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    pipeline.pass_file(pipeline.output_dir(scene), 1).unlink()
    scene.render.use_motion_blur = True
    scene.render.filepath = str(tmp_path / "frame_")
    scene.frame_start, scene.frame_end = 1, 3
    bpy.ops.render.render(animation=True)
    assert worker_frames == [1, 1, 2, 3], worker_frames  # Render Pass's, then the render's
    blur = [w for w in _warnings(caplog) if "motion blur" in w]
    assert len(blur) == 1, blur
    corners = np.array([(x, y, z) for x in (-0.2, 0.2) for y in (-0.2, 0.2) for z in (-0.2, 0.2)])
    for frame, x in ((1, -0.15), (2, 0.15), (3, -0.05)):
        cols = _camera_columns(scene, cam, corners + (x, 0, 0))
        got = _middle(pipeline.pass_file(pipeline.output_dir(scene), frame))
        print(f"frame {frame}: pass middle {got}, projected {(min(cols) + max(cols)) / 2:.2f}")
        assert abs(got - (min(cols) + max(cols)) / 2) <= 0.5, frame


def test_a_stale_pass_warns_with_its_age(empty_scene, tmp_path, caplog):
    """Pass on Every Render off and the cube moved since its pass was made: the frame
    composites that pass and warns that it is stale, with its age; with the pass gone, that
    the holographic objects are missing."""
    import os
    import time

    from holo_addon.render import pipeline

    scene = empty_scene
    cube, _, _ = _composited_cube(scene)
    path = pipeline.pass_file(pipeline.output_dir(scene), 1)
    an_hour_ago = time.time() - 3600
    os.utime(path, (an_hour_ago, an_hour_ago))
    scene.holo.pass_on_render = False
    scene.render.filepath = str(tmp_path / "same.exr")
    bpy.ops.render.render(write_still=True)
    assert not [w for w in _warnings(caplog) if "stale" in w], "an up-to-date pass is quiet"
    cube.location.x = 0.3
    scene.render.filepath = str(tmp_path / "moved.exr")
    bpy.ops.render.render(write_still=True)
    (warning,) = [w for w in _warnings(caplog) if "stale" in w]
    assert "frame 1" in warning and "made 1 h ago" in warning, warning
    path.unlink()
    scene.render.filepath = str(tmp_path / "gone.exr")
    bpy.ops.render.render(write_still=True)
    assert [w for w in _warnings(caplog) if "no holographic pass" in w]


NO_EMITTER_LEFT = (
    BACKGROUND_SCENE
    + """
for obj in scene.objects:
    obj.holo.emitter = "NONE"
scene.render.filepath = sys.argv[3] + "/frame_"
scene.frame_start, scene.frame_end = 1, 2
bpy.ops.render.render(animation=True)
holo_addon.unregister()
print("rendered", flush=True)
# bpy 4.2.0's own teardown after a render crashes (SIGSEGV) and 4.5.15's never returns, with or
# without the add-on: the status is this script's
import os
os._exit(0)
"""
)


def test_with_no_emitter_left_frames_render_the_raster_alone_with_exit_0(tmp_path):
    """``blender -b ... -a`` on a file whose last emitter was un-marked: the frames render
    (the raster alone: the cube, a raster object again, and clear passes) and the process
    ends with status 0 (it ended with 1)."""
    run = in_background(NO_EMITTER_LEFT, tmp_path)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    assert "rendered" in run.stdout
    frames = sorted(p.name for p in tmp_path.glob("frame_*"))
    assert frames == ["frame_0001.exr", "frame_0002.exr"], frames
    for frame in (1, 2):
        alpha = _read_exr(tmp_path / "holo" / f"holo_pass_{frame:04d}.exr")
        assert not alpha["ViewLayer.Combined.A"].any(), f"frame {frame}'s pass is clear"


FARM_LOG = (
    BACKGROUND
    + """
from test_addon import _plate_camera_cube
_plate_camera_cube(scene)
scene.render.engine = "CYCLES"
scene.cycles.samples = 1
scene.render.resolution_x, scene.render.resolution_y = 32, 24
scene.holo.lighting = "ALBEDO"
assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
scene.render.filepath = sys.argv[3] + "/frame_"
scene.frame_start, scene.frame_end = 1, 2
bpy.ops.render.render(animation=True)
scene.frame_start, scene.frame_end = 2, 2
bpy.ops.render.render(animation=True)
import os
os._exit(0)  # bpy 4.2.0's teardown after a render crashes, 4.5.15's never returns
"""
)


def test_a_background_render_logs_what_each_frames_pass_was(tmp_path):
    """``blender -b ... -a`` (Set Up Compositing before any pass) of a still cube: the log
    says per frame what its pass was, the route that made it, its file and its warnings (none
    here): frame 1's made, in how many seconds; frame 2's the static shot's (frame 1's, only
    the frame changed); rendered again, frame 2's up to date."""
    import re

    run = in_background(FARM_LOG, tmp_path)
    lines = [ln for ln in run.stderr.splitlines() if "Holo: frame" in ln]
    print("\n".join(lines))
    assert run.returncode == 0, run.stderr[-2000:]
    assert len(lines) == 3, lines
    assert re.search(
        r"^INFO Holo: frame 1: holographic pass made in [0-9.]+ s as a camera "
        r"hologram: .*holo_pass_0001\.exr; no warnings$",
        lines[0],
    ), lines[0]
    assert re.search(
        r"^INFO Holo: frame 2: holographic pass reused from holo_pass_0001\.exr "
        r"\(a static shot: only the frame changed\) as a camera hologram: "
        r".*holo_pass_0002\.exr; no warnings$",
        lines[1],
    ), lines[1]
    assert re.search(r"^INFO Holo: frame 2: holographic pass reused \(up to date\)", lines[2])


def _links(tree):
    return {
        (l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
        for l in tree.links
    }


def test_remove_holo_compositing_restores_the_users_own_tree(empty_scene, tmp_path):
    """A user's Render Layers → Glare → output chain: set up, then removed, every node and
    link is as it was and the Depth pass is off again; a scene without a compositor gets
    none back."""
    from holo_addon.blender import compat
    from holo_addon.compositor import tree as passes

    scene = empty_scene
    _composited_cube(scene)
    assert bpy.ops.holo.remove_compositing() == {"FINISHED"}
    assert compat.existing_compositor_tree(scene) is None, "the add-on's own tree is gone"
    assert not scene.view_layers[0].use_pass_z and not passes.uses_pass(scene)
    tree = compat.compositor_tree(scene)
    rl = tree.nodes.new("CompositorNodeRLayers")
    glare = tree.nodes.new("CompositorNodeGlare")
    tree.links.new(rl.outputs["Image"], glare.inputs[0])
    tree.links.new(glare.outputs[0], compat.output_socket(tree))
    before, nodes = _links(tree), {n.name for n in tree.nodes}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    assert passes.uses_pass(scene) and _links(tree) != before
    assert bpy.ops.holo.remove_compositing() == {"FINISHED"}
    assert compat.existing_compositor_tree(scene) == tree
    assert _links(tree) == before and {n.name for n in tree.nodes} == nodes
    assert bpy.ops.holo.remove_compositing() == {"CANCELLED"}
