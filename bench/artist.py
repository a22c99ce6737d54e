"""What an artist meets: each scene composited with its holographic object beside Cycles'
frame of the same scene with that object an ordinary one, measured, and written side by side
(Cycles left, the composite right) as ``out/artist_<scene>.png``.

- ``cards``: a red card in front of the holographic green card in front of a blue wall, all
  out of focus (f/1.2 and f/2.8), and the green card moving (motion blur): 10-90 % widths of
  the edges against Cycles' and the largest step of the profile off Cycles'.
- ``units``: the cards at unit scale 0.01, 1 and 100: widths, depth layers and the pass's time.
- ``instances``: one sphere as collection, geometry-node and particle instances, lit.
- ``shot``: a lit, textured Suzanne on a table behind a defocused vase, f/2, AgX.
- ``preview``: the viewport preview's latency, first picture and refresh after a change.

    python bench/artist.py [-o out] [--size W H] [SCENE ...]

Only the add-on's operators are called, so the same script measures an earlier tree
(``PYTHONPATH=<tree>``) where the operators exist.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import results  # the bench folder's own: the figures as data

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="holo-bench-"))
sys.path.append(str(Path(__file__).resolve().parents[1]))  # after PYTHONPATH: a tree named there
import bpy

import holo_addon
from holo_addon.blender import compat
from holo_addon.demo import point_at
from holo_core.io.image import exr_attribute, read_exr, srgb


def fresh(out: Path, size, *, samples=128, view="Standard", world=None):
    """An empty scene rendered by Cycles at ``samples`` (a box filter, no denoising) at
    ``size``, its ``view`` transform, a world of colour ``world`` (None: black)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.cycles.samples = samples
    scene.view_settings.view_transform = view
    if world is not None:
        scene.world = bpy.data.worlds.new("world")
        scene.world.color = world
    scene.holo.output_dir = str(out / "holo") + os.sep
    scene.render.engine = "CYCLES"
    scene.cycles.use_denoising = False
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.seed = 1
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    compat.set_exr_output(scene, multilayer=False)
    return scene


def material(obj, rgb, *, emission=0.0, roughness=0.5, base=None):
    mat = bpy.data.materials.new(obj.name)
    compat.enable_nodes(mat)
    bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Base Color"].default_value = (*(rgb if base is None else base), 1)
    bsdf.inputs["Emission Color"].default_value = (*rgb, 1)
    bsdf.inputs["Emission Strength"].default_value = emission
    bsdf.inputs["Roughness"].default_value = roughness
    obj.data.materials.append(mat)
    return bsdf


def card(name, size, location, rgb, base=(0, 0, 0)):
    bpy.ops.mesh.primitive_plane_add(size=size, location=location, rotation=(np.pi / 2, 0, 0))
    obj = bpy.context.object
    obj.name = name
    material(obj, rgb, emission=1.0, base=base)
    return obj


def camera(location, target, lens=50, fstop=None, focus=None):
    bpy.ops.object.camera_add(location=location)
    cam = bpy.context.object
    point_at(cam, target)
    cam.data.lens = lens
    if fstop:
        cam.data.dof.use_dof = True
        cam.data.dof.aperture_fstop = fstop
        cam.data.dof.focus_distance = focus
    bpy.context.scene.camera = cam
    return cam


def render(scene, path: Path) -> np.ndarray:
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    _, c = read_exr(path, what="render")
    return np.stack([c[k] for k in "RGBA"], -1)


def composite(scene, emitter, path: Path, kind="POINTS") -> tuple[np.ndarray, float]:
    """The frame with ``emitter`` holographic; the seconds Render Pass took."""
    emitter.holo.emitter = kind
    started = time.perf_counter()
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    seconds = time.perf_counter() - started
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    return render(scene, path), seconds


def side_by_side(name, out: Path, cycles, mine, scene) -> Path:
    """Both frames through the scene's view transform, Cycles' left, as one PNG."""
    pair = np.concatenate([cycles, mine], 1)
    h, w, _ = pair.shape
    image = bpy.data.images.new(name, w, h, alpha=True, float_buffer=True)
    image.pixels.foreach_set(np.ascontiguousarray(pair[::-1]).ravel())
    path = out / f"artist_{name}.png"
    if hasattr(compat, "png_output"):
        with compat.png_output(scene):
            image.save_render(str(path), scene=scene)
    else:  # a tree from before: plain sRGB
        from PIL import Image

        Image.fromarray((srgb(pair[..., :3]) * 255 + 0.5).astype(np.uint8)).save(path)
    bpy.data.images.remove(image)
    return path


def profile(image, channel, rows, cols):
    p = image[rows, cols, channel].mean(0)
    left, right = p[:4].mean(), p[-4:].mean()
    return (p - right) / (left - right)


def width(p) -> float:
    x = np.arange(len(p))
    return float(np.interp(-0.1, -p, x) - np.interp(-0.9, -p, x))


def edges(mine, cycles, spans):
    lines = []
    for label, channel, rows, cols in spans:
        a, b = (profile(im, channel, rows, cols) for im in (mine, cycles))
        lines.append(
            f"{label}: 10-90 % width {width(a):.2f} px, Cycles' {width(b):.2f} px "
            f"({width(a) / width(b) - 1:+.1%}); profile at most "
            f"{np.abs(a - b).max():.3f} off Cycles'"
        )
    return lines


def cards_scene(size, fstop, unit=1.0):
    scene = fresh(OUT, size)
    scene.unit_settings.scale_length = unit
    scene.cycles.max_bounces = 0
    scene.holo.lighting = "ALBEDO"
    camera((0, -1.0, 0), (0, 10, 0), fstop=fstop, focus=1.0)
    card("red", 1.0, (-0.52, -0.4, 0), (1, 0, 0))
    card("blue", 40, (0, 5.0, 0), (0, 0, 1))
    green = card("green", 0.8, (0, 1.5, 0), (0, 1, 0), base=(0, 1, 0))
    bpy.context.view_layer.update()
    return scene, green


def spans(size):
    w, h = size
    rows = slice(h // 3, 2 * h // 3)
    s = w / 320
    return [
        ("holographic card over the wall", 1, rows, slice(int(200 * s), int(262 * s))),
        ("red card over the holographic card", 0, rows, slice(int(112 * s), int(178 * s))),
    ]


def cards(size):
    for fstop in (1.2, 2.8):
        scene, green = cards_scene(size, fstop)
        ref = render(scene, OUT / "cycles.exr")
        mine, seconds = composite(scene, green, OUT / "holo.exr")
        print(f"cards f/{fstop} ({size[0]}x{size[1]}): pass {seconds:.1f} s")
        for line in edges(mine, ref, spans(size)):
            print(f"  {line}")
        side_by_side(f"cards_f{fstop}", OUT, ref, mine, scene)
    scene, green = cards_scene(size, None)
    bpy.data.objects["red"].hide_render = True
    curve = green.driver_add("location", 0)  # 0.1 unit a frame, exactly, through 0 at 2
    curve.driver.type = "SCRIPTED"
    curve.driver.expression = "(frame - 2) * 0.1"
    scene.render.use_motion_blur = True
    scene.frame_set(2)
    ref = render(scene, OUT / "cycles.exr")
    mine, seconds = composite(scene, green, OUT / "holo.exr")
    w, h = size
    rows = slice(h // 3, 2 * h // 3)
    print(f"moving card ({size[0]}x{size[1]}, 0.1 unit a frame, shutter 0.5): pass {seconds:.1f} s")
    for line in edges(mine, ref, [("right edge", 1, rows, slice(int(w * 0.64), int(w * 0.8)))]):
        print(f"  {line}")
    side_by_side("motion", OUT, ref, mine, scene)


def units(size):
    for unit in (0.01, 1.0, 100.0):
        scene, green = cards_scene(size, 2.8, unit)
        ref = render(scene, OUT / "cycles.exr")
        mine, seconds = composite(scene, green, OUT / "holo.exr")
        info = json.loads(exr_attribute(OUT / "holo" / "holo_pass_0001.exr", "holo") or "{}")
        print(f"scale {unit}: pass {seconds:.1f} s, {info.get('layers')} depth layers")
        for line in edges(mine, ref, spans(size)):
            print(f"  {line}")


def instances(size):
    scene = fresh(OUT, size, samples=64, view="AgX", world=(0.05, 0.05, 0.05))
    bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=0.15)
    sphere = bpy.context.object
    bpy.ops.object.shade_smooth()
    material(sphere, (0.8, 0.35, 0.1), roughness=0.3)
    asset = bpy.data.collections.new("Asset")
    scene.collection.children.link(asset)
    for c in list(sphere.users_collection):
        c.objects.unlink(sphere)
    asset.objects.link(sphere)
    bpy.context.view_layer.layer_collection.children["Asset"].exclude = True
    for i in range(5):
        empty = bpy.data.objects.new(f"Instance {i}", None)
        empty.instance_type = "COLLECTION"
        empty.instance_collection = asset
        empty.location = (-0.8 + 0.4 * i, 0.3 * (i % 2), 0.15)
        scene.collection.objects.link(empty)
    bpy.ops.mesh.primitive_plane_add(size=8)
    material(bpy.context.object, (0.5, 0.5, 0.5))
    bpy.ops.object.light_add(type="SUN", rotation=(np.radians(55), 0, np.radians(-40)))
    bpy.context.object.data.energy = 3.0
    camera((0.2, -3.0, 1.3), (0, 0.1, 0.15))
    bpy.context.view_layer.update()
    ref = render(scene, OUT / "cycles.exr")
    mine, seconds = composite(scene, sphere, OUT / "holo.exr")
    print(
        f"instances (5 collection instances, lit): pass {seconds:.1f} s; "
        f"{inside_the_object(mine, ref)}"
    )
    side_by_side("instances", OUT, ref, mine, scene)


def inside_the_object(mine, ref) -> str:
    """The composite against Cycles' frame where the pass is opaque: luminance correlation
    and mean ratio."""
    alpha = read_exr(OUT / "holo" / "holo_pass_0001.exr", what="pass")[1]["ViewLayer.Combined.A"]
    inside = alpha > 0.99
    lum = [im[..., :3] @ (0.2126, 0.7152, 0.0722) for im in (mine, ref)]
    corr = np.corrcoef(lum[0][inside], lum[1][inside])[0, 1]
    return (
        f"inside {inside.sum()} px: luminance correlation {corr:.3f}, mean "
        f"{lum[0][inside].mean() / lum[1][inside].mean():.3f} x Cycles'"
    )


def shot(size):
    """An artist's product shot: a textured Suzanne (a checker Base Color) on a table, a
    vase out of focus in front, an area light and a low sun, f/2 focused on Suzanne, AgX."""
    scene = fresh(OUT, size, samples=64, view="AgX", world=(0.12, 0.13, 0.16))
    bpy.ops.mesh.primitive_monkey_add(size=0.6, location=(0, 0, 0.42))
    suzanne = bpy.context.object
    suzanne.rotation_euler = (0, 0, np.radians(-20))
    mod = suzanne.modifiers.new("Smooth", "SUBSURF")
    mod.levels = mod.render_levels = 2
    bpy.ops.object.shade_smooth()
    bsdf = material(suzanne, (0.7, 0.7, 0.7), roughness=0.35)
    checker = bsdf.id_data.nodes.new("ShaderNodeTexChecker")
    checker.inputs["Scale"].default_value = 6.0
    checker.inputs["Color1"].default_value = (0.8, 0.25, 0.1, 1)
    checker.inputs["Color2"].default_value = (0.9, 0.8, 0.5, 1)
    bsdf.id_data.links.new(checker.outputs["Color"], bsdf.inputs["Base Color"])
    bpy.ops.mesh.primitive_cube_add(size=1, location=(0, 0.3, 0.0))
    table = bpy.context.object
    table.scale = (1.6, 1.0, 0.1)
    material(table, (0.35, 0.22, 0.12), roughness=0.6)
    bpy.ops.mesh.primitive_cylinder_add(radius=0.07, depth=0.5, location=(0.3, -0.7, 0.3))
    material(bpy.context.object, (0.1, 0.3, 0.7), roughness=0.1)
    bpy.ops.mesh.primitive_plane_add(size=6, location=(0, 1.5, 1.5), rotation=(np.pi / 2, 0, 0))
    material(bpy.context.object, (0.6, 0.6, 0.6))
    bpy.ops.object.light_add(type="AREA", location=(-1.2, -1.2, 1.6))
    area = bpy.context.object
    area.data.energy, area.data.size = 120.0, 0.8
    point_at(area, (0, 0, 0.4))
    bpy.ops.object.light_add(type="SUN", rotation=(np.radians(60), 0, np.radians(50)))
    bpy.context.object.data.energy = 1.5
    camera((0.35, -2.0, 0.75), (0, 0, 0.4), lens=60, fstop=2.0, focus=2.05)
    bpy.context.view_layer.update()
    ref = render(scene, OUT / "cycles.exr")
    mine, seconds = composite(scene, suzanne, OUT / "holo.exr")
    diff = np.abs(mine[..., :3] - ref[..., :3]).mean(-1)
    print(
        f"shot ({size[0]}x{size[1]}, f/2, Lighting: Scene): pass {seconds:.1f} s; "
        f"{inside_the_object(mine, ref)}; whole frame mean |difference| {diff.mean():.4f}, "
        f"99th percentile {np.percentile(diff, 99):.3f}"
    )
    side_by_side("shot", OUT, ref, mine, scene)


def preview(size):
    from holo_addon.ui import preview as view

    scene, green = cards_scene(size, 2.8)
    green.holo.emitter = "POINTS"
    times = []
    for step in range(3):
        if step:
            green.location.x += 0.02
            bpy.context.view_layer.update()
        begun = time.perf_counter()
        assert view.start(scene, bpy.context.evaluated_depsgraph_get())
        while view.poll(scene):
            time.sleep(0.02)
        times.append(time.perf_counter() - begun)
    h, w, _ = view.state().picture.shape
    print(
        f"preview ({w}x{h} of {size[0]}x{size[1]}): first picture {times[0]:.2f} s, after "
        f"a change {times[1]:.2f} and {times[2]:.2f} s (the worker's start included)"
    )


SCENES = {"cards": cards, "units": units, "instances": instances, "shot": shot, "preview": preview}

if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("-o", "--out", default="out")
    parser.add_argument("--size", nargs=2, type=int, default=(640, 360))
    parser.add_argument("scenes", nargs="*", default=list(SCENES))
    args = parser.parse_args()
    OUT = Path(args.out).resolve()
    OUT.mkdir(parents=True, exist_ok=True)
    holo_addon.register()
    figures = {}
    for name in args.scenes:  # each scene's measured lines are its figures
        with contextlib.redirect_stdout(io.StringIO()) as said:
            SCENES[name](tuple(args.size))
        sys.stdout.write(said.getvalue())
        figures[name] = " ".join(line.strip() for line in said.getvalue().splitlines())
    results.write("artist", figures)
    sys.stdout.flush()
    os._exit(0)  # bpy's own teardown is slow and says nothing
