"""The scene read into the job (holo_addon/export: the emitters as the render draws them, their
colours and materials, the plate and its zone, the digests that name the holograms)."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _plate_camera_cube  # noqa: E402


def _fingerprint(scene):
    from holo_addon.render import pipeline

    return pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get()).fingerprint


def test_the_fingerprint_covers_emitter_kind_material_and_lens(empty_scene):
    scene = empty_scene
    cube, cam, plate = _plate_camera_cube(scene)
    plate.holo.zone_margin = 0.05  # a zone that holds the lens's pupil once depth of field is on
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
    plate.scale = (0.3, 0.3, 1)  # 0.18 m: the cube's outline is cut
    bpy.context.view_layer.update()
    (warning,) = _prepare(scene).warnings
    assert "covers" in warning and "cut from the pass" in warning, warning
    plate.scale = (1, 1, 1)
    plate.location.x = 2.0  # beside the line of sight
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
    scene.holo.exposure = 1e6  # a script's: held to the core's range, which float32 keeps
    assert Settings.from_scene(scene, 1.0).exposure == 2.0**64
    scene.holo.output_dir = "//holo/"
    assert not bpy.data.filepath
    with pytest.raises(ExportError, match=r"save the \.blend first"):
        pipeline.output_dir(scene)


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
    cube.hide_render = True  # the user's own Disable in Renders
    cube.holo.emitter = "TRIANGLES"  # changing the kind leaves it alone
    assert cube.hide_render
    with pytest.raises(ExportError, match="no holographic emitters in the render"):
        _emitter_meshes(scene)


def test_collection_instances_of_an_emitter_are_recorded_where_they_stand(empty_scene):
    scene = empty_scene
    _, _, _ = _plate_camera_cube(scene)
    scene.objects[0].holo.emitter = "NONE"  # the plain cube of the helper
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
    assert warning.startswith(
        "material 'shiny': Metallic, Alpha, Emission Strength, Normal not shown"
    ), warning
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
    bsdf.inputs["Roughness"].default_value = 0.2  # the material changed: baked again
    assert bake.current(cube) is None


def test_a_state_recorded_before_is_not_recorded_again(empty_scene, monkeypatch):
    """Iterations 1 → 2 → 1: two recordings, not three; each state has its own files (farm
    workers on different frames never share a hologram file). The render's size, which a
    plate does not depend on, records nothing."""
    from holo_addon.render import pipeline

    scene = empty_scene
    _plate_camera_cube(scene)
    scene.holo.mode = "PLATE"
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    recorded = []
    original = pipeline.run

    def run(job, progress=None, on_log=None, **kw):
        recorded.append(job.records)
        return original(job, progress, on_log, **kw)

    monkeypatch.setattr(pipeline, "run", run)
    paths = []
    for iterations in (1, 2, 1):
        scene.holo.iterations = iterations
        assert bpy.ops.holo.record_hologram() == {"FINISHED"}
        paths.append(_prepare(scene).holograms[0])
    assert recorded == [True, True, False], recorded
    assert paths[0] == paths[2] != paths[1] and all(p.is_file() for p in paths)
    scene.render.resolution_percentage = 50
    assert bpy.ops.holo.record_hologram() == {"FINISHED"}
    assert recorded[-1] is False, recorded


def test_a_plate_file_replaced_by_another_scenes_is_recorded_again(empty_scene):
    """A plate file replaced by another scene's valid plate under its name (a farm folder
    synced from another shot) was rendered as this scene's. The file carries the recording
    it is: one that names another is not current, so the job records the plate again, and
    the job names the recording the worker must find."""
    import json

    from holo_core.io.hologram import recording_of
    from holo_core.io.image import read_exr, write_exr

    scene = empty_scene
    _plate_camera_cube(scene)
    scene.holo.mode = "PLATE"
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    assert bpy.ops.holo.record_hologram() == {"FINISHED"}
    prepared = _prepare(scene)
    path = prepared.holograms[0]
    assert not prepared.records and recording_of(path) == prepared.fingerprint
    assert prepared.job.route.recording == prepared.fingerprint
    header, channels = read_exr(path)
    other = "f" * 16 if prepared.fingerprint != "f" * 16 else "e" * 16
    write_exr(path, channels, holo=json.dumps({**json.loads(header["holo"]), "recording": other}))
    assert _prepare(scene).records, "another recording's plate under this name was current"
