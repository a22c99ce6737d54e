"""Reproducers of the Blender integration issue's findings (bpy in-process)."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _camera_columns, _plate_camera_cube, _read_exr  # noqa: E402


def _fingerprint(scene):
    from holo_addon.render import pipeline
    return pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get()).fingerprint


def test_the_fingerprint_covers_emitter_kind_material_and_lens(empty_scene):
    scene = empty_scene
    cube, cam, _ = _plate_camera_cube(scene)
    scene.holo.mode = "PLATE"
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    seen = [_fingerprint(scene)]
    cube.holo.emitter = "TRIANGLES"
    seen.append(_fingerprint(scene))
    material = bpy.data.materials.new("red")
    material.diffuse_color = (1, 0, 0, 1)
    cube.data.materials.append(material)
    seen.append(_fingerprint(scene))
    assert len(set(seen)) == len(seen), seen
    # reading the scene writes nothing into it: the zone the job resolved is kept on the plate
    # once it is recorded (here as a recording's result is applied)
    from holo_addon.render import pipeline
    from holo_core.job import Result
    plate = next(o for o in scene.objects if o.holo.is_plate)
    prepared = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get())
    assert not plate.holo.zone_set and prepared.zone is not None
    pipeline.apply(scene, prepared, Result())
    assert plate.holo.zone_set and _fingerprint(scene) == seen[-1]
    # a plate is recorded for its viewing zone: the camera's lens and focus leave it as it is
    cam.data.dof.use_dof = True
    cam.data.dof.focus_distance = 3.0
    assert _fingerprint(scene) == seen[-1]
    scene.holo.mode = "CAMERA"  # a camera hologram is recorded for its lens
    lens = _fingerprint(scene)
    cam.data.dof.focus_distance = 2.0
    assert _fingerprint(scene) != lens


def _moving_cube(scene, tmp_path):
    cube, cam, plate = _plate_camera_cube(scene, cube_size=0.4)
    plate.holo.zone_margin = 0.01  # a zone close around the camera: a sharper plate
    bpy.ops.object.light_add(type="SUN", rotation=(np.radians(60), 0, 0))  # lights its front
    bpy.context.object.data.energy = 3.0
    scene.render.resolution_x, scene.render.resolution_y = 48, 36
    scene.render.resolution_percentage = 100
    scene.render.engine = "CYCLES"  # Workbench draws every object: emitters too
    scene.cycles.samples = 4
    scene.render.film_transparent = False
    scene.holo.mode = "PLATE"
    scene.holo.iterations = 1
    scene.holo.max_resolution = 512
    for frame, x in ((1, -0.15), (2, 0.15), (3, -0.05)):
        cube.location.x = x
        cube.keyframe_insert("location", frame=frame)
    return cube, cam


def _middle(path):
    alpha = _read_exr(path)["ViewLayer.Combined.A"]
    cols = np.nonzero(alpha > 0.5)[1]
    return (cols.min() + cols.max() + 1) / 2


def test_an_animation_started_away_from_the_timeline_frame_uses_each_frames_geometry(
        empty_scene, tmp_path):
    """The timeline rests on frame 1; frames 2-3 are rendered (a farm chunk): each pass shows
    its own frame's cube, where the camera projects it (within half a pixel)."""
    from holo_addon.blender import compat
    from holo_addon.render import pipeline
    scene = empty_scene
    cube, cam = _moving_cube(scene, tmp_path)
    scene.frame_set(1)
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    compat.set_png_output(scene)
    scene.render.filepath = str(tmp_path / "frame_")
    scene.frame_start, scene.frame_end = 2, 3
    bpy.ops.render.render(animation=True)
    out = pipeline.output_dir(scene)
    corners = np.array([(x, y, z) for x in (-0.2, 0.2) for y in (-0.2, 0.2) for z in (-0.2, 0.2)])
    for frame, x in ((2, 0.15), (3, -0.05)):
        got = _middle(out / f"holo_pass_{frame:04d}.exr")
        cols = _camera_columns(scene, cam, corners + (x, 0, 0))
        want = (min(cols) + max(cols)) / 2
        print(f"frame {frame}: silhouette middle {got} px, projected {want:.2f} px")
        assert abs(got - want) <= 0.5, (frame, got, want)


def _render_range(scene, start, end, folder, tmp_path):
    from holo_addon.blender import compat
    scene.holo.output_dir = str(folder) + "/"
    compat.set_exr_output(scene, multilayer=False)
    scene.render.filepath = str(tmp_path / folder.name / "frame_")
    scene.frame_start, scene.frame_end = start, end
    bpy.ops.render.render(animation=True)


def test_three_frames_as_one_animation_or_separate_frames_give_identical_passes(
        empty_scene, tmp_path):
    """A cube and the camera both move; ``-a`` over frames 1-3 and three single-frame runs
    (as a farm splits them) give bit-identical passes, each where the camera projects that
    frame's cube (within half a pixel), and each frame's composite shows its own pass."""
    from holo_addon.render import pipeline
    scene = empty_scene
    cube, cam = _moving_cube(scene, tmp_path)
    for frame, dx in ((1, 0.0), (2, 0.05), (3, 0.1)):
        cam.location.x = dx
        cam.keyframe_insert("location", frame=frame)
    scene.frame_set(1)
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    _render_range(scene, 1, 3, tmp_path / "all", tmp_path)
    for frame in (3, 1, 2):  # separate runs, in any order, from wherever the timeline rests
        _render_range(scene, frame, frame, tmp_path / "single", tmp_path)
    corners = np.array([(x, y, z) for x in (-0.2, 0.2) for y in (-0.2, 0.2) for z in (-0.2, 0.2)])
    for frame, x in ((1, -0.15), (2, 0.15), (3, -0.05)):
        a, b = (_read_exr(pipeline.pass_file(tmp_path / run, frame)) for run in ("all", "single"))
        assert all(np.array_equal(a[k], b[k]) for k in a), f"frame {frame}: passes differ"
        scene.frame_set(frame)
        cols = _camera_columns(scene, cam, corners + (x, 0, 0))
        want, got = (min(cols) + max(cols)) / 2, _middle(pipeline.pass_file(tmp_path / "all",
                                                                             frame))
        image = _read_exr(tmp_path / "all" / f"frame_{frame:04d}.exr")
        rgb = np.stack([image[c] for c in "RGB"], -1)
        shown = np.nonzero((np.abs(rgb - rgb[0, 0]).max(-1) > 0.05).any(0))[0]
        composite = (shown.min() + shown.max() + 1) / 2
        print(f"frame {frame}: pass middle {got}, composite {composite}, projected {want:.2f} px")
        assert abs(got - want) <= 0.5 and abs(composite - got) <= 0.5


def test_compositing_keeps_the_users_nodes_and_links(empty_scene, tmp_path):
    """A user's Render Layers → Glare → output chain (and a Viewer) survives the setup: every
    node and link stays, the chain's result feeds the Depth Combine, whose result goes out."""
    from holo_addon.blender import compat
    from holo_addon.compositor import passes as compositing
    from holo_addon.render import pipeline
    from holo_core.io.view import write_view
    from holo_core.view import RenderResult
    scene = empty_scene
    _plate_camera_cube(scene)
    tree = compat.compositor_tree(scene)
    rl = tree.nodes.new("CompositorNodeRLayers")
    glare = tree.nodes.new("CompositorNodeGlare")
    viewer = tree.nodes.new("CompositorNodeViewer")
    tree.links.new(rl.outputs["Image"], glare.inputs[0])
    tree.links.new(glare.outputs[0], compat.output_socket(tree))
    tree.links.new(rl.outputs["Image"], viewer.inputs[0])

    def links():
        return {(l.from_node.name, l.from_socket.identifier, l.to_node.name,
                 l.to_socket.identifier) for l in tree.links}
    before, nodes = links(), {n.name for n in tree.nodes}
    out = pipeline.output_dir(scene)
    write_view(RenderResult(rgb=np.ones((24, 32, 3)), alpha=np.ones((24, 32)),
                            depth=np.ones((24, 32))), pipeline.pass_file(out, scene.frame_current))
    for _ in range(2):  # again: only the add-on's nodes are rebuilt
        compositing.setup(scene, out)
    combine = tree.nodes[compositing.NODE_PREFIX + "Depth Combine"]
    output_link = next(l for l in before if l[0] == glare.name)
    assert before - links() == {output_link}, "only the link into the output is re-routed"
    assert nodes <= {n.name for n in tree.nodes}
    assert combine.inputs[2].links[0].from_node == glare
    assert compat.output_socket(tree).links[0].from_node == combine
    assert sum(n.name.startswith(compositing.NODE_PREFIX + "Depth") for n in tree.nodes) == 1


def _scene_with_pass(scene, tmp_path):
    from holo_addon.blender import compat
    _moving_cube(scene, tmp_path)
    scene.frame_set(1)
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    compat.set_exr_output(scene, multilayer=False)


def _shown_columns(path):
    image = _read_exr(path)
    rgb = np.stack([image[c] for c in "RGB"], -1)
    return np.nonzero((np.abs(rgb - rgb[0, 0]).max(-1) > 0.05).any(0))[0]


def _read_parts(path):
    """Every channel of every part (Blender 5 writes a multilayer EXR as one part per layer)."""
    import OpenEXR
    with OpenEXR.File(str(path), separate_channels=True) as f:
        return {k: v.pixels.copy() for part in f.parts for k, v in part.channels.items()}


def test_each_rendered_frame_gets_its_holographic_layers_beside_it(empty_scene, tmp_path):
    """Beside the frame ``shot_0001.exr`` a multilayer ``holo_shot_0001.exr``: the composite
    (equal to the frame), the pass alone (equal to the pass file), its depth, and the
    composite's depth (the nearer of the pass's and the raster's), depths in ``.Z`` channels
    as Blender's own passes (Blender's File Output names them ``.V``)."""
    from holo_addon.render import pipeline
    scene = empty_scene
    _scene_with_pass(scene, tmp_path)
    scene.render.filepath = str(tmp_path / "out" / "shot_####")
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    scene.frame_start = scene.frame_end = 1
    bpy.ops.render.render(animation=True)
    layers = _read_parts(tmp_path / "out" / "holo_shot_0001.exr")
    frame = _read_exr(tmp_path / "out" / "shot_0001.exr")
    holo = _read_exr(pipeline.pass_file(pipeline.output_dir(scene), 1))
    for c in "RGBA":
        np.testing.assert_allclose(layers[f"Composite.{c}"], frame[c], atol=1e-6)
        np.testing.assert_allclose(layers[f"Holo.{c}"], holo[f"ViewLayer.Combined.{c}"],
                                   atol=1e-6)
    assert not [k for k in layers if k.endswith(".V")], "depth channels are named .Z"
    np.testing.assert_allclose(layers["HoloDepth.Z"], holo["ViewLayer.Depth.Z"], rtol=1e-6)
    shown = holo["ViewLayer.Combined.A"] > 0.5
    assert shown.any() and (layers["Depth.Z"] <= layers["HoloDepth.Z"]).all()
    np.testing.assert_allclose(layers["Depth.Z"][shown], layers["HoloDepth.Z"][shown],
                               rtol=1e-6)


def test_a_failed_pass_never_composites_a_stale_one(empty_scene, tmp_path, monkeypatch):
    """In the interface a handler cannot cancel the render: the failed frame shows the raster
    alone (the stale pass set aside, kept), and the next good pass shows again."""
    from holo_addon.compositor import passes as compositing
    from holo_addon.render import pipeline
    from holo_core.worker import WorkerError
    scene = empty_scene
    _scene_with_pass(scene, tmp_path)
    monkeypatch.setattr(compositing, "EXIT_ON_FAILURE", False)
    original = pipeline.run

    def broken(job, progress=None, on_log=None):
        raise WorkerError("a crash in native code")
    monkeypatch.setattr(pipeline, "run", broken)
    assert pipeline.pass_file(pipeline.output_dir(scene), 1).is_file()  # the stale pass
    scene.render.filepath = str(tmp_path / "failed.exr")
    bpy.ops.render.render(write_still=True)
    assert _shown_columns(tmp_path / "failed.exr").size == 0, "a stale pass was composited"
    assert (pipeline.output_dir(scene) / "holo_pass_0001.stale.exr").is_file()
    monkeypatch.setattr(pipeline, "run", original)
    scene.render.filepath = str(tmp_path / "good.exr")
    bpy.ops.render.render(write_still=True)
    assert _shown_columns(tmp_path / "good.exr").size > 0


FAILING_FARM_RENDER = """
import sys
sys.path[:0] = [sys.argv[1], sys.argv[2]]
import bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
import holo_addon
holo_addon.register()
import test_integration
scene = bpy.context.scene
scene.holo.output_dir = sys.argv[3] + "/holo/"
test_integration._scene_with_pass(scene, None)
from holo_addon.render import pipeline
def broken(job, progress=None, on_log=None):
    raise RuntimeError("the worker failed")
pipeline.run = broken
scene.render.filepath = sys.argv[3] + "/frame_"
bpy.ops.render.render(animation=True)
print("rendered")
"""


def test_a_failed_pass_fails_a_background_animation(tmp_path):
    """``blender -b ... -a``: the process ends with status 1 and the error, before writing the
    frame."""
    import subprocess
    import sys
    from pathlib import Path
    here = Path(__file__).resolve()
    run = subprocess.run([sys.executable, "-c", FAILING_FARM_RENDER, str(here.parents[2]),
                          str(here.parent), str(tmp_path)], capture_output=True, text=True,
                         timeout=600)
    assert run.returncode == 1, run.stdout[-2000:] + run.stderr[-2000:]
    assert "the holographic pass of frame 1 failed: the worker failed" in run.stderr
    assert "rendered" not in run.stdout and not list(tmp_path.glob("frame_*"))


def _prepare(scene):
    from holo_addon.render import pipeline
    return pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get())


def test_a_plate_too_small_warns_and_one_off_the_view_is_refused(empty_scene):
    from holo_addon.export.scene import ExportError
    scene = empty_scene
    _, _, plate = _plate_camera_cube(scene)
    scene.holo.mode = "PLATE"
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    assert _prepare(scene).warnings == ()
    plate.scale = (0.3, 0.3, 1)               # 0.18 m: the cube's outline is cut
    bpy.context.view_layer.update()
    (warning,) = _prepare(scene).warnings
    assert "covers" in warning and "cut from the pass" in warning, warning
    plate.scale = (1, 1, 1)
    plate.location.x = 2.0                    # beside the line of sight
    bpy.context.view_layer.update()
    with pytest.raises(ExportError, match="not between the camera and the holographic objects"):
        _prepare(scene)


def test_exposure_is_in_stops_and_unsaved_files_need_a_folder(empty_scene):
    from holo_addon.export.job import Settings
    from holo_addon.export.scene import ExportError
    from holo_addon.render import pipeline
    scene = empty_scene
    _plate_camera_cube(scene)
    scene.holo.exposure = 1.0
    assert Settings.from_scene(scene, 1.0).exposure == 2.0
    scene.holo.exposure = -2.0
    assert Settings.from_scene(scene, 1.0).exposure == 0.25
    scene.holo.output_dir = "//holo/"
    assert not bpy.data.filepath
    with pytest.raises(ExportError, match="save the .blend first"):
        pipeline.output_dir(scene)


def test_the_memory_limit_preference_reaches_the_worker():
    from holo_core.worker import environment
    assert environment((), None, "6.0G")["HOLO_MEMORY_LIMIT"] == "6.0G"
    unset = environment((), None, None).get("HOLO_MEMORY_LIMIT")
    assert unset == __import__("os").environ.get("HOLO_MEMORY_LIMIT")  # not overridden


def _emitter_meshes(scene):
    from holo_addon.export.scene import export_scene
    data = export_scene(scene, bpy.context.evaluated_depsgraph_get())
    return data.points + data.triangles


def _cube_in(collection_name, scene, location=(0, 0, 0)):
    bpy.ops.mesh.primitive_cube_add(size=0.3, location=location)
    cube = bpy.context.object
    cube.holo.emitter = "POINTS"
    coll = bpy.data.collections.new(collection_name)
    scene.collection.children.link(coll)
    for c in list(cube.users_collection):
        c.objects.unlink(cube)
    coll.objects.link(cube)
    return cube, coll


def test_blenders_render_visibility_decides_what_is_recorded(empty_scene):
    """Excluded and render-disabled collections and Disable in Renders leave an emitter out;
    the add-on never writes Disable in Renders itself."""
    from holo_addon.export.scene import ExportError
    scene = empty_scene
    cube, _, _ = _plate_camera_cube(scene)
    assert not cube.hide_render
    other, coll = _cube_in("Extra", scene, (0.2, 0, 0))
    assert len(_emitter_meshes(scene)) == 2
    bpy.context.view_layer.layer_collection.children["Extra"].exclude = True
    assert len(_emitter_meshes(scene)) == 1
    bpy.context.view_layer.layer_collection.children["Extra"].exclude = False
    coll.hide_render = True
    assert len(_emitter_meshes(scene)) == 1
    cube.hide_render = True                      # the user's own Disable in Renders
    cube.holo.emitter = "TRIANGLES"              # changing the kind leaves it alone
    assert cube.hide_render
    with pytest.raises(ExportError, match="no holographic emitters in the render"):
        _emitter_meshes(scene)


def test_collection_instances_of_an_emitter_are_recorded_where_they_stand(empty_scene):
    scene = empty_scene
    _, _, _ = _plate_camera_cube(scene)
    scene.objects[0].holo.emitter = "NONE"       # the plain cube of the helper
    cube, coll = _cube_in("Source", scene)
    bpy.context.view_layer.layer_collection.children["Source"].exclude = True
    for x in (-0.3, 0.3):
        empty = bpy.data.objects.new(f"instance {x}", None)
        empty.instance_type = "COLLECTION"
        empty.instance_collection = coll
        empty.location = (x, 0, 0.1)
        scene.collection.objects.link(empty)
    bpy.context.view_layer.update()
    centres = sorted(np.round(m.vertices.mean(0), 6).tolist() for m in _emitter_meshes(scene))
    assert centres == [[-0.3, 0.0, 0.1], [0.3, 0.0, 0.1]], centres


def test_renders_use_render_modifier_levels(empty_scene, tmp_path, monkeypatch):
    """Subdivision at level 0 in the viewport and 2 in renders: the pass of an F12 render is
    made from level 2 (a cube's 12 triangles become 192)."""
    from holo_addon.render import pipeline
    scene = empty_scene
    _scene_with_pass(scene, tmp_path)
    cube = next(o for o in scene.objects if o.holo.emitter == "POINTS")
    sub = cube.modifiers.new("subdivision", "SUBSURF")
    sub.levels, sub.render_levels = 0, 2
    seen = []
    original = pipeline.run

    def run(job, progress=None, on_log=None):
        seen.append(sum(len(m.triangles) for m in job.job.points))
        return original(job, progress, on_log)
    monkeypatch.setattr(pipeline, "run", run)
    scene.render.filepath = str(tmp_path / "f12.exr")
    bpy.ops.render.render(write_still=True)
    assert seen == [192], seen
    assert len(_emitter_meshes(scene)[0].triangles) == 12  # the viewport's level


def test_procedural_base_colours_are_reported(empty_scene):
    from holo_addon.blender import compat
    scene = empty_scene
    cube, _, _ = _plate_camera_cube(scene)
    material = bpy.data.materials.new("marble")
    compat.enable_nodes(material)
    bsdf = next(n for n in material.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    noise = material.node_tree.nodes.new("ShaderNodeTexNoise")
    material.node_tree.links.new(noise.outputs["Color"], bsdf.inputs["Base Color"])
    cube.data.materials.append(material)
    scene.holo.mode = "PLATE"
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    assert _prepare(scene).warnings == ()  # lit by the scene: Cycles renders it
    scene.holo.lighting = "ALBEDO"
    (warning,) = _prepare(scene).warnings
    assert "'marble'" in warning and "Noise Texture" in warning, warning


def test_material_features_the_hologram_does_not_show_are_reported(empty_scene):
    """A default Principled material: no note. Metallic, alpha and emission set, a normal map
    linked: lit by the scene, a note naming alpha alone (Cycles' radiance shows the rest);
    with the albedo, one naming them all. An Emission shader alone: lit by the scene no note,
    with the albedo a note that the viewport colour is used."""
    from holo_addon.blender import compat
    scene = empty_scene
    cube, _, _ = _plate_camera_cube(scene)
    scene.holo.mode = "PLATE"
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    shiny = bpy.data.materials.new("shiny")
    compat.enable_nodes(shiny)
    cube.data.materials.append(shiny)
    assert _prepare(scene).warnings == ()
    bsdf = next(n for n in shiny.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Metallic"].default_value = 1.0
    bsdf.inputs["Alpha"].default_value = 0.5
    bsdf.inputs["Emission Strength"].default_value = 2.0
    bump = shiny.node_tree.nodes.new("ShaderNodeBump")
    shiny.node_tree.links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])
    (warning,) = _prepare(scene).warnings
    assert warning.startswith("material 'shiny': Alpha not shown"), warning
    scene.holo.lighting = "ALBEDO"
    (warning,) = _prepare(scene).warnings
    assert warning.startswith("material 'shiny': Metallic, Alpha, Emission Strength, Normal "
                              "not shown"), warning
    glow = bpy.data.materials.new("glow")
    compat.enable_nodes(glow)
    tree = glow.node_tree
    tree.nodes.remove(next(n for n in tree.nodes if n.type == "BSDF_PRINCIPLED"))
    emission = tree.nodes.new("ShaderNodeEmission")
    output = next(n for n in tree.nodes if n.type == "OUTPUT_MATERIAL")
    tree.links.new(emission.outputs[0], output.inputs["Surface"])
    cube.data.materials[0] = glow
    (warning,) = _prepare(scene).warnings
    assert "'glow' has no Principled BSDF" in warning, warning
    scene.holo.lighting = "SCENE"
    assert _prepare(scene).warnings == ()


def test_a_render_cropped_to_an_off_centre_border_gets_the_border_of_the_pass(
        empty_scene, tmp_path):
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


def test_an_up_to_date_pass_is_not_rendered_again(empty_scene, monkeypatch):
    """The frame's pass carries a digest of what it was made from: the same scene renders
    nothing again; any change (here the exposure) renders anew."""
    from holo_addon.render import pipeline
    from holo_core import worker
    scene = empty_scene
    _plate_camera_cube(scene)
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.holo.samples = 2
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    started = []
    original = worker.Worker.__init__

    def counting(self, *args, **kwargs):
        started.append(1)
        original(self, *args, **kwargs)
    monkeypatch.setattr(worker.Worker, "__init__", counting)
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and started == []
    scene.holo.exposure = 1.0
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and started == [1]
    assert pipeline.cached_pass(pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get()))


def test_a_procedural_base_colour_is_baked_and_recorded(empty_scene):
    """Base Color = the object-space position (Texture Coordinate ▸ Object, a node the export
    cannot read): Render Pass bakes it with Cycles, and the emitter's samples carry
    max(position, 0) within 0.01 (the atlas' texel is 1.7 mm on a 0.5 m cube)."""
    from holo_addon.blender import compat
    from holo_addon.export import bake
    from holo_addon.render import pipeline
    from holo_core.scene.mesh import sample_points
    scene = empty_scene
    cube, _, _ = _plate_camera_cube(scene)
    material = bpy.data.materials.new("position")
    compat.enable_nodes(material)
    tree = material.node_tree
    bsdf = next(n for n in tree.nodes if n.type == "BSDF_PRINCIPLED")
    coords = tree.nodes.new("ShaderNodeTexCoord")
    tree.links.new(coords.outputs["Object"], bsdf.inputs["Base Color"])
    cube.data.materials.append(material)
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.holo.samples = 1
    scene.holo.lighting = "ALBEDO"  # lit by the scene, Cycles renders it: no bake
    assert bake.current(cube) is None
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bake.current(cube) is not None and bpy.data.images[bake.image_name(cube)].packed_file
    job = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get())
    assert job.warnings == ()
    (mesh,) = job.job.points
    pos, colours = sample_points(mesh, 0.01)
    want = np.clip(pos - np.array(cube.location), 0, 1)
    error = np.abs(colours - want)
    print(f"baked colours: error median {np.median(error):.4f}, 99% {np.percentile(error, 99):.4f}")
    assert np.percentile(error, 99) <= 0.01
    bsdf.inputs["Roughness"].default_value = 0.2      # the material changed: baked again
    assert bake.current(cube) is None


def test_a_state_recorded_before_is_not_recorded_again(empty_scene, monkeypatch):
    """Max Hologram Size 256 → 128 → 256: two recordings, not three; each state has its own
    files (farm workers on different frames never share a hologram file). The render's size,
    which a plate does not depend on, records nothing."""
    from holo_addon.render import pipeline
    scene = empty_scene
    _plate_camera_cube(scene)
    scene.holo.mode = "PLATE"
    scene.holo.iterations = 1
    scene.holo.max_resolution = 256
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    recorded = []
    original = pipeline.run

    def run(job, progress=None, on_log=None):
        recorded.append(job.records)
        return original(job, progress, on_log)
    monkeypatch.setattr(pipeline, "run", run)
    paths = []
    for samples in (256, 128, 256):
        scene.holo.max_resolution = samples
        assert bpy.ops.holo.record_hologram() == {"FINISHED"}
        paths.append(_prepare(scene).holograms[0])
    assert recorded == [True, True, False], recorded
    assert paths[0] == paths[2] != paths[1] and all(p.is_file() for p in paths)
    scene.render.resolution_percentage = 50
    assert bpy.ops.holo.record_hologram() == {"FINISHED"}
    assert recorded[-1] is False, recorded


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


def test_the_pass_of_a_render_can_be_cancelled(empty_scene, tmp_path, monkeypatch):
    """Cancel Pass while a render makes its pass: the worker stops, the frame shows the raster
    alone (the stale pass set aside) and the panel's state is cleared."""
    from holo_addon.compositor import passes as compositing
    from holo_addon.render import pipeline
    scene = empty_scene
    _scene_with_pass(scene, tmp_path)
    scene.holo.exposure = 1.0                      # the pass is out of date: the worker runs
    original, clicked = pipeline.run, []

    def run(job, progress=None, on_log=None):
        def user(fraction):
            if not clicked:                        # the user clicks while it runs
                clicked.append(bpy.ops.holo.cancel_pass())
            progress(fraction)
        return original(job, user, on_log)
    monkeypatch.setattr(pipeline, "run", run)
    scene.render.filepath = str(tmp_path / "cancelled.exr")
    bpy.ops.render.render(write_still=True)
    assert clicked == [{"FINISHED"}]
    assert _shown_columns(tmp_path / "cancelled.exr").size == 0
    assert (pipeline.output_dir(scene) / "holo_pass_0001.stale.exr").is_file()
    assert compositing.RUNNING["frame"] is None and not bpy.ops.holo.cancel_pass.poll()


def test_a_static_shot_is_made_once_and_each_frame_stays_pure(empty_scene, tmp_path,
                                                             monkeypatch):
    """Frames 1-3 of a shot where nothing moves: one worker; frames 2 and 3 reuse frame 1's
    pass pixel for pixel (their digests differ in the frame number alone), each file carrying
    its own frame's digest. Frame 3 rendered alone, into an empty folder (a farm's node), gives
    the same pixels. The cube moving at frame 4 makes frame 4 anew."""
    from holo_addon.render import pipeline
    from holo_core import worker
    scene = empty_scene
    cube, _, _ = _plate_camera_cube(scene)
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.holo.samples, scene.holo.lighting = 2, "ALBEDO"
    started = []
    original = worker.Worker.__init__

    def counting(self, *args, **kwargs):
        started.append(scene.frame_current)
        original(self, *args, **kwargs)
    monkeypatch.setattr(worker.Worker, "__init__", counting)
    for frame in (1, 2, 3):
        scene.frame_set(frame)
        assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert started == [1], started
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
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and started == [1, 3]
    alone = _read_exr(pipeline.pass_file(tmp_path / "alone", 3))
    assert all(np.array_equal(first[k], alone[k]) for k in first), "frame 3 alone differs"
    scene.holo.output_dir = str(out) + "/"
    cube.keyframe_insert("location", frame=3)
    cube.location.x += 0.1
    cube.keyframe_insert("location", frame=4)
    scene.frame_set(4)
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and started == [1, 3, 4]
