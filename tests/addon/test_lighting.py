"""A holographic object lit by the scene, against Cycles' render of the same object as an
ordinary one: its shading, its highlight, the shadow it casts on the raster floor, and when a
pass is made again (bpy in-process; the radiance from a Blender process of its own)."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _read_exr  # noqa: E402

SIZE = (128, 96)


def lit_stage(scene, size, *, sun=(65, -70), camera=((0.4, -3.4, 1.5), (0.6, 0.0, 0.2))):
    """Cycles at 32 samples (no denoising, a box filter, the Standard view, float EXR out) of
    ``size``, a dim grey world, a grey floor under a low sun (its rotation ``sun`` about x and
    z in degrees) and a 50 mm pinhole camera at ``camera`` (where, looking at); returns the
    sun."""
    from holo_addon.blender import compat
    from holo_addon.demo import point_at

    scene.render.engine = "CYCLES"
    scene.cycles.samples = 32
    scene.cycles.use_denoising = False
    scene.cycles.pixel_filter_type = "BOX"
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    compat.set_exr_output(scene, multilayer=False)
    world = bpy.data.worlds.new("dim")
    world.color = (0.05, 0.05, 0.05)
    scene.world = world
    bpy.ops.mesh.primitive_plane_add(size=8, location=(0, 0, 0))
    paint(bpy.context.object, "floor", (0.5, 0.5, 0.5))
    bpy.ops.object.light_add(type="SUN", rotation=(np.radians(sun[0]), 0, np.radians(sun[1])))
    light = bpy.context.object
    light.data.energy = 3.0
    bpy.ops.object.camera_add(location=camera[0])
    cam = bpy.context.object
    point_at(cam, camera[1])
    cam.data.lens = 50
    scene.camera = cam
    return light


def paint(obj, name, rgb, roughness=0.5):
    """A Principled material ``name`` of Base Color ``rgb`` on ``obj``."""
    from holo_addon.blender import compat

    material = bpy.data.materials.new(name)
    compat.enable_nodes(material)
    bsdf = next(n for n in material.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Base Color"].default_value = (*rgb, 1)
    bsdf.inputs["Roughness"].default_value = roughness
    obj.data.materials.append(material)


def _lit_scene(scene):
    """A smooth glossy grey sphere on the lit stage (its shadow falls on the floor in
    view)."""
    sun = lit_stage(scene, SIZE)
    bpy.ops.mesh.primitive_uv_sphere_add(
        segments=48, ring_count=24, radius=0.3, location=(0, 0, 0.3)
    )
    sphere = bpy.context.object
    bpy.ops.object.shade_smooth()
    paint(sphere, "glossy grey", (0.6, 0.6, 0.6), roughness=0.3)
    scene.holo.samples = 4
    bpy.context.view_layer.update()
    return sphere, sun


def _render(scene, path):
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    image = _read_exr(path)
    return np.stack([image[c] for c in "RGB"], -1)


def _luminance(rgb):
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def _grow(mask, steps):
    out = mask.copy()
    for _ in range(steps):
        grown = out.copy()
        grown[1:] |= out[:-1]
        grown[:-1] |= out[1:]
        grown[:, 1:] |= out[:, :-1]
        grown[:, :-1] |= out[:, 1:]
        out = grown
    return out


def _plate_between(scene, target):
    """Plate mode through a 1 m plate halfway from the camera to ``target`` (its centre), its
    zone around the camera's pupil: the radiance is seen from the zone's centre, which the
    camera (aimed beside the target) shares."""
    from holo_addon.demo import point_at

    eye = np.array(scene.camera.location)
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=tuple((eye + np.array(target)) / 2))
    plate = bpy.context.object
    point_at(plate, target)  # −Z towards the objects: +Z faces the camera
    plate.holo.is_plate = True
    scene.holo.mode = "PLATE"
    scene.holo.iterations = 2
    bpy.context.view_layer.update()


@pytest.mark.parametrize("mode", ["CAMERA", "PLATE"])
def test_a_lit_holographic_sphere_shades_and_casts_its_shadow_as_cycles_does(
    empty_scene, tmp_path, mode
):
    """Cycles renders the sphere as an ordinary object, then as a POINTS emitter through its
    camera hologram (or a plate's view, the plate recorded for the camera's zone), composited:
    inside the object (the pass's alpha, one pixel in from the rim) the luminance correlates
    >= 0.9 with Cycles' and its mean is within 15 %, the specular highlight is where Cycles
    has it (within 2 px), and the floor in the sphere's shadow is no more than 1.15 times as
    bright as in Cycles. (A plate's radiance was rendered from the scene's camera but projected
    from the zone's view, aimed elsewhere: its highlight moved.)"""
    from holo_addon.render import pipeline

    scene = empty_scene
    sphere, _ = _lit_scene(scene)
    reference = _render(scene, tmp_path / "cycles.exr")
    sphere.hide_render = True
    unshadowed = _render(scene, tmp_path / "no_sphere.exr")
    sphere.hide_render = False
    sphere.holo.emitter = "POINTS"
    if mode == "PLATE":
        _plate_between(scene, tuple(sphere.location))
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    composite = _render(scene, tmp_path / "holo.exr")
    alpha = _read_exr(pipeline.pass_file(pipeline.output_dir(scene), 1))["ViewLayer.Combined.A"]
    inside = ~_grow(alpha <= 0.5, 1)
    mine, theirs = _luminance(composite), _luminance(reference)
    corr = np.corrcoef(mine[inside], theirs[inside])[0, 1]
    ratio = mine[inside].mean() / theirs[inside].mean()
    peak = [
        np.unravel_index(np.argmax(np.where(inside, lum, -1)), lum.shape) for lum in (mine, theirs)
    ]
    shift = float(np.hypot(*np.subtract(*peak)))
    shadow = (_luminance(reference) < 0.5 * _luminance(unshadowed)) & ~_grow(alpha > 0.5, 2)
    shade = mine[shadow].mean() / theirs[shadow].mean()
    print(
        f"lit sphere ({mode}): {inside.sum()} px inside, luminance correlation {corr:.3f}, mean "
        f"ratio {ratio:.3f}, highlight {peak[0]} vs Cycles' {peak[1]} ({shift:.1f} px); "
        f"shadow {shadow.sum()} px, {shade:.3f} x Cycles'"
    )
    assert inside.sum() > 300 and shadow.sum() > 100, (inside.sum(), shadow.sum())
    assert corr >= 0.9, f"luminance correlation inside the object {corr:.3f}"
    assert abs(ratio - 1) <= 0.15, f"mean luminance {ratio:.3f} x Cycles'"
    assert shift <= 2.0, f"highlight at {peak[0]}, Cycles' at {peak[1]}"
    assert shade <= 1.15, f"the floor in the shadow is {shade:.3f} x as bright as Cycles'"


def test_a_changed_light_renders_the_pass_again_and_nothing_changed_reuses_it(
    empty_scene, worker_frames
):
    """Render Pass twice: one worker. The sun's strength doubled: the pass is made again and
    the cube's radiance doubles (no other light: within 5 %); the floor's colour changed
    (light it bounces): made again; nothing changed: reused."""
    from test_addon import _plate_camera_cube

    from holo_addon.blender import compat
    from holo_addon.render import pipeline

    scene = empty_scene
    scene.cycles.samples = 8
    _plate_camera_cube(scene)
    bpy.ops.object.light_add(type="SUN", rotation=(np.radians(60), 0, 0))
    sun = bpy.context.object
    sun.data.energy = 2.0
    bpy.ops.mesh.primitive_plane_add(size=4, location=(0, 0, -0.25))
    floor = bpy.data.materials.new("floor")
    compat.enable_nodes(floor)
    bpy.context.object.data.materials.append(floor)
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.holo.samples = 2
    path = pipeline.pass_file(pipeline.output_dir(scene), scene.frame_current)

    def radiance():
        image = _read_exr(path)
        shown = image["ViewLayer.Combined.A"] > 0.5
        return sum(image[f"ViewLayer.Combined.{c}"][shown].sum() for c in "RGB")

    assert bpy.ops.holo.render_pass() == {"FINISHED"} and worker_frames == [1]
    before = radiance()
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and worker_frames == [1]
    sun.data.energy = 4.0
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and worker_frames == [1, 1]
    ratio = radiance() / before
    print(f"sun 2 -> 4: the pass's radiance x {ratio:.3f}")
    assert abs(ratio - 2) <= 0.1, f"the pass's radiance x {ratio:.3f} for the sun's x 2"
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and worker_frames == [1, 1]
    bsdf = next(n for n in floor.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Base Color"].default_value = (0.2, 0.9, 0.2, 1)
    assert bpy.ops.holo.render_pass() == {"FINISHED"} and worker_frames == [1, 1, 1]
