"""The built-in demo (``make demo``): headless through the bpy module, a holographic object
among rasterized ones, recorded, rendered, composited in depth.

The scene: a glossy, vertex-coloured holographic sphere (point emitters) on a floor, a
rasterized red cube behind it, a blue pillar in front of it and a green cone beside it, under a
low sun; a 40 mm camera at f/2.8 focused on the sphere, 1280×720. The sphere is rendered
through its camera hologram (the default mode; the plate between them serves ``--mode
PLATE``), lit by the scene (its colours are Cycles' radiance of it), and casts its shadow on
the floor and the cone. Writes ``out/demo.png``
(the composite), ``out/demo.exr`` (the composite, float RGBA), ``out/holo/`` (the holographic
pass), ``out/holo_demo.exr`` (its layers beside the render) and prints where they are.

    python -m holo_addon.demo [-o out] [--resolution W H] [--samples N] [--mode CAMERA|PLATE]
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from pathlib import Path

import numpy as np

from holo_core.io.image import atomic_path

from . import register
from .blender import compat
from .render import pipeline


def _colour_sphere(bpy, name, location, radius):
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4, radius=radius, location=location)
    obj = bpy.context.object
    obj.name = name
    me = obj.data
    attr = me.color_attributes.new("Col", "FLOAT_COLOR", "POINT")
    co = np.empty(len(me.vertices) * 3)
    me.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3) / radius
    rgb = np.clip(0.55 + 0.45 * co[:, [0, 1, 2]] * [1, -1, 1], 0.05, 1)  # a hue per octant
    attr.data.foreach_set("color", np.c_[rgb, np.ones(len(rgb))].ravel())
    me.color_attributes.active_color = attr
    bpy.ops.object.shade_smooth()
    # a glossy material whose Base Color is the colour attribute: Cycles lights it
    mat = bpy.data.materials.new(name)
    compat.enable_nodes(mat)
    tree = mat.node_tree
    bsdf = next(n for n in tree.nodes if n.type == "BSDF_PRINCIPLED")
    colour = tree.nodes.new("ShaderNodeVertexColor")
    colour.layer_name = "Col"
    tree.links.new(colour.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.35
    me.materials.append(mat)
    return obj


def _material(bpy, obj, rgb):
    mat = bpy.data.materials.new(obj.name)
    mat.diffuse_color = (*rgb, 1.0)
    compat.enable_nodes(mat)
    if mat.node_tree is not None:
        bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
        bsdf.inputs["Base Color"].default_value = (*rgb, 1.0)
    obj.data.materials.append(mat)


def point_at(obj, target):
    """Turn ``obj`` so its −Z looks at ``target`` with +Y up (a camera's convention)."""
    from mathutils import Vector

    d = Vector(target) - obj.location
    obj.rotation_euler = d.to_track_quat("-Z", "Y").to_euler()


def build_scene(bpy, *, resolution=(1280, 720), fstop=2.8):
    """The demo scene in the current (empty) file; returns the scene."""
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 32
    scene.cycles.device = "CPU"
    scene.render.resolution_x, scene.render.resolution_y = resolution
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"  # plain sRGB: the PNG shows the numbers
    world = bpy.data.worlds.new("World")
    scene.world = world
    world.color = (0.05, 0.05, 0.06)

    sphere = _colour_sphere(bpy, "Hologram Sphere", (0.0, 0.0, 0.35), 0.3)
    sphere.holo.emitter = "POINTS"
    bpy.ops.mesh.primitive_plane_add(size=6, location=(0, 0, 0.0))
    _material(bpy, bpy.context.object, (0.5, 0.5, 0.5))
    bpy.ops.mesh.primitive_cube_add(size=0.5, location=(-0.35, 0.7, 0.25))
    _material(bpy, bpy.context.object, (0.8, 0.1, 0.08))
    bpy.ops.mesh.primitive_cylinder_add(radius=0.08, depth=0.9, location=(0.3, -0.55, 0.45))
    _material(bpy, bpy.context.object, (0.1, 0.2, 0.9))
    bpy.ops.mesh.primitive_cone_add(radius1=0.2, depth=0.5, location=(0.65, 0.15, 0.25))
    _material(bpy, bpy.context.object, (0.1, 0.7, 0.15))
    bpy.ops.object.light_add(type="SUN", location=(2, -2, 4))
    bpy.context.object.data.energy = 3.0
    bpy.context.object.rotation_euler = (1.0, 0.0, -0.9)  # low: a long shadow in view

    bpy.ops.object.camera_add(location=(0.9, -3.2, 1.3))
    camera = bpy.context.object
    point_at(camera, (0.05, 0.0, 0.35))
    scene.camera = camera
    camera.data.lens = 40
    camera.data.dof.use_dof = True
    camera.data.dof.focus_object = sphere
    camera.data.dof.aperture_fstop = fstop

    # the plate: between camera and sphere, facing the camera (+Z towards the viewer)
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0.5, -1.75, 0.85))
    plate = bpy.context.object
    plate.name = "Hologram Plate"
    point_at(plate, tuple(2 * np.array(plate.location) - np.array(camera.location)))
    plate.holo.is_plate = True
    bpy.context.view_layer.update()
    return scene


def render_still(bpy, scene, out: Path) -> tuple[Path, Path]:
    """Blender's render of the composited frame: ``demo.png`` and float ``demo.exr``."""
    png, exr = out / "demo.png", out / "demo.exr"
    scene.render.filepath = str(out / "demo")  # the holographic layers go beside it
    for path, setter in (
        (exr, lambda: compat.set_exr_output(scene, multilayer=False)),
        (png, lambda: compat.set_png_output(scene)),
    ):
        setter()
        scene.holo["skip_pass_once"] = True  # the pass was just rendered
        bpy.ops.render.render()
        with atomic_path(path) as tmp:  # a failed run keeps the last demo
            bpy.data.images["Render Result"].save_render(tmp)
    return png, exr


def main(argv=None):
    p = argparse.ArgumentParser(
        prog="python -m holo_addon.demo", description=__doc__.split("\n\n")[0]
    )
    p.add_argument("-o", "--output", type=Path, default=Path("out"))
    p.add_argument("--resolution", type=int, nargs=2, default=(1280, 720), metavar=("W", "H"))
    p.add_argument("--fstop", type=float, default=2.8)
    p.add_argument("--samples", type=int, default=16)
    p.add_argument("--mode", choices=("CAMERA", "PLATE"), default="CAMERA")
    p.add_argument("--iterations", type=int, default=2, help="plate mode: recordings")
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(name)s: %(message)s")
    import bpy

    out = args.output.resolve()
    out.mkdir(parents=True, exist_ok=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    register()
    t0 = time.perf_counter()
    scene = build_scene(bpy, resolution=tuple(args.resolution), fstop=args.fstop)
    scene.holo.output_dir = str(out / "holo") + os.sep
    scene.holo.mode = args.mode
    scene.holo.samples = args.samples
    scene.holo.iterations = args.iterations
    scene.render.filepath = str(out / "demo")  # the holographic layers go beside it
    plate = scene.objects["Hologram Plate"]
    if args.mode == "PLATE":  # say before recording what this plate's views will resolve
        bpy.context.view_layer.objects.active = plate
        bpy.ops.holo.plan_plate()
    for op in (bpy.ops.holo.render_pass, bpy.ops.holo.setup_compositing):
        if op() != {"FINISHED"}:
            sys.exit(f"demo: {op.idname_py()} failed")
    png, exr = render_still(bpy, scene, out)
    scene.render.filepath = str(out / "demo")
    bpy.ops.wm.save_as_mainfile(filepath=str(out / "demo.blend"))
    hologram = f"\n  hologram: {plate.holo.hologram}" if args.mode == "PLATE" else ""
    print(
        f"demo rendered in {time.perf_counter() - t0:.0f} s:\n  {png}\n  {exr}{hologram}\n"
        f"  holographic pass: {pipeline.pass_file(out / 'holo', scene.frame_current)}\n"
        f"  its layers beside the render: {out / 'holo_demo.exr'}\n"
        f"  scene: {out / 'demo.blend'}"
    )


if __name__ == "__main__":
    main()
