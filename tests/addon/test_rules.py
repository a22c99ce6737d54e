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
