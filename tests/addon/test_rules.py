"""Rules of Blender an artist and a render farm rely on (bpy in-process, and background
Blender processes where the exit status is the point)."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _plate_camera_cube, _raster_alpha_and_depth, _read_exr, show_in_raster


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
    show_in_raster(cube)
    alpha, depth = _raster_alpha_and_depth(scene, tmp_path)
    both = (holo["ViewLayer.Combined.A"] > 0.5) & (alpha > 0.5) & (depth < 1e9)
    extent = np.ptp(depth[both])
    err = np.median(np.abs(holo["ViewLayer.Depth.Z"][both] - depth[both])) / extent
    print(f"scale_length 0.01: median depth error {err:.2%} of {extent:.1f} units "
          f"({both.sum()} px)")
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
    assert len(job.scene.points) == 1
    (warning,) = [w for w in job.scene.warnings if "Wire" in w]
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
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = 7 / 160, 135 / 160, \
        5 / 120, 113 / 120
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
            (lambda: setattr(cube, "hide_viewport", True),
             lambda: setattr(cube, "hide_viewport", False), lambda: cube.hide_viewport),
            (lambda: setattr(layer, "hide_viewport", True),
             lambda: setattr(layer, "hide_viewport", False), lambda: layer.hide_viewport)):
        hide()
        path.unlink(missing_ok=True)
        assert bpy.ops.holo.render_pass() == {"FINISHED"}
        assert (_read_exr(path)["ViewLayer.Combined.A"] > 0.5).sum() > 20
        assert hidden(), "left hidden as the user had it"
        show()
    cube.hide_render = True
    with pytest.raises(RuntimeError, match="no holographic emitters in the render"):
        bpy.ops.holo.render_pass()
