"""Instanced holographic objects (collection instances, geometry-node instances, particles)
against Cycles' render of the same instances as ordinary objects, under both lightings
(bpy in-process; Lighting: Scene's radiance from a Blender process of its own)."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _read_exr  # noqa: E402
from test_lighting import _grow, _luminance, _render, lit_stage, paint  # noqa: E402

SIZE = (160, 120)


def _instancing_scene(scene):
    """A glossy orange sphere in an excluded collection "Asset", shown three ways: two
    collection instances, a geometry-node Instance on Points of it (two points) and a hair
    particle system instancing it (three hairs); a grey floor under a low sun, a dim world,
    a 50 mm pinhole camera; Cycles at 32 samples. Returns the sphere."""
    lit_stage(scene, SIZE, sun=(60, -40), camera=((0.1, -3.2, 1.4), (0.0, 0.2, 0.15)))
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=0.15)
    sphere = bpy.context.object
    sphere.name = "Asset Sphere"
    bpy.ops.object.shade_smooth()
    paint(sphere, "orange", (0.8, 0.35, 0.1), roughness=0.4)
    asset = bpy.data.collections.new("Asset")
    scene.collection.children.link(asset)
    for c in list(sphere.users_collection):
        c.objects.unlink(sphere)
    asset.objects.link(sphere)
    bpy.context.view_layer.layer_collection.children["Asset"].exclude = True
    for i, x in enumerate((-0.9, -0.5)):
        empty = bpy.data.objects.new(f"Instance {i}", None)
        empty.instance_type = "COLLECTION"
        empty.instance_collection = asset
        empty.location = (x, 0.0, 0.15)
        scene.collection.objects.link(empty)
    # geometry nodes: a line of two points, the sphere instanced on each
    tree = bpy.data.node_groups.new("Scatter", "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    line = tree.nodes.new("GeometryNodeMeshLine")
    line.inputs["Count"].default_value = 2
    line.inputs["Offset"].default_value = (0.4, 0.0, 0.0)
    info = tree.nodes.new("GeometryNodeObjectInfo")
    info.inputs["Object"].default_value = sphere
    info.inputs["As Instance"].default_value = True  # instances of the object itself
    on_points = tree.nodes.new("GeometryNodeInstanceOnPoints")
    out = tree.nodes.new("NodeGroupOutput")
    tree.links.new(line.outputs["Mesh"], on_points.inputs["Points"])
    tree.links.new(info.outputs["Geometry"], on_points.inputs["Instance"])
    tree.links.new(on_points.outputs["Instances"], out.inputs[0])
    scatter = bpy.data.objects.new("Scatter", bpy.data.meshes.new("Scatter"))
    scatter.location = (-0.1, 0.0, 0.15)
    scene.collection.objects.link(scatter)
    scatter.modifiers.new("Scatter", "NODES").node_group = tree
    # hair particles: three spheres standing on a small plane at the back
    bpy.ops.mesh.primitive_plane_add(size=0.8, location=(0.0, 0.7, 0.15))
    ground = bpy.context.object
    ground.name = "Particle Ground"
    ground.modifiers.new("Hair", "PARTICLE_SYSTEM")
    settings = ground.particle_systems[0].settings
    settings.type = "HAIR"
    settings.count = 3
    settings.hair_length = 0.3
    settings.render_type = "OBJECT"
    settings.instance_object = sphere
    settings.particle_size = 1.0
    settings.use_rotation_instance = False
    ground.show_instancer_for_render = False
    bpy.context.view_layer.update()
    return sphere


def _instances(depsgraph):
    from holo_addon.export.scene import emitter_instances

    return [inst for inst, _ in emitter_instances(depsgraph)]


@pytest.mark.parametrize("lighting", ["SCENE", "ALBEDO"])
def test_instanced_emitters_are_lit_and_coloured_as_the_same_objects_linked(
    empty_scene, tmp_path, lighting
):
    """Seven instances of one sphere (two collection instances, two geometry-node instances,
    three hair particles) are recorded, and composited they show Cycles' colours: with
    Lighting: Scene, inside the pass's alpha (one pixel in from the rims) the luminance
    correlates >= 0.9 with Cycles' render of the same instances as ordinary objects and its
    mean is within 15 % of it; with Lighting: Albedo the mean colour is the Base Color's
    (unlit: within 2 % of (0.8, 0.35, 0.1) in every channel). Before the fix, collection
    instances were black under Lighting: Scene (their instancer was hidden from the radiance
    render's camera, and Cycles hides an instancer's instances with it)."""
    from holo_addon.render import pipeline

    scene = empty_scene
    scene.holo.lighting = lighting
    sphere = _instancing_scene(scene)
    reference = _render(scene, tmp_path / "cycles.exr")
    sphere.holo.emitter = "POINTS"
    bpy.context.view_layer.update()
    assert len(_instances(bpy.context.evaluated_depsgraph_get())) == 7
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    composite = _render(scene, tmp_path / "holo.exr")
    view = _read_exr(pipeline.pass_file(pipeline.output_dir(scene), 1))
    alpha = view["ViewLayer.Combined.A"]
    inside = ~_grow(alpha <= 0.5, 1)
    assert inside.sum() > 400, inside.sum()
    if lighting == "ALBEDO":
        colour = np.stack([view[f"ViewLayer.Combined.{c}"] for c in "RGB"], -1)[inside]
        mean = colour.mean(0) / alpha[inside].mean()
        print(f"instances, albedo: mean colour {np.round(mean, 4).tolist()}")
        assert np.allclose(mean, (0.8, 0.35, 0.1), rtol=0.02), mean
        return
    mine, theirs = _luminance(composite), _luminance(reference)
    corr = np.corrcoef(mine[inside], theirs[inside])[0, 1]
    ratio = mine[inside].mean() / theirs[inside].mean()
    print(
        f"instances, lit: {inside.sum()} px inside, luminance correlation {corr:.3f}, "
        f"mean ratio {ratio:.3f}"
    )
    assert corr >= 0.9, f"luminance correlation inside the instances {corr:.3f}"
    assert abs(ratio - 1) <= 0.15, f"mean luminance {ratio:.3f} x Cycles'"
