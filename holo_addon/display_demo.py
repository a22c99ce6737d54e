"""A holographic display's animation, headless through the bpy module: a textured,
lit scene shown frame by frame on a phase SLM.

The scene: a checkered card (triangle emitters, its image texture) turning 1.2 m behind
the display, a colour-wheel sphere (point emitters) rising beside it 0.8 m behind, under a
sun; shown on a holographic display (a 1080p
phase SLM at 8 µm by default, or ``--display W H PITCH_UM``) at Scene
Scale 0.05 (60 and 40 mm: the focal stack's slices at −60 and −40 mm hold each in focus),
in a volume 80 mm deep, with smooth phases, seen through a 4 mm pupil from a 2 mm eye box
as near as the display's diffraction angle allows (:func:`eye_distance`: 700 mm for the
1080p display, 300 mm for 512 × 512 at 8 µm; an eye's defocus blur a·Δz/L must exceed its
Airy pattern 1.22·λL/a for depth to show, hence the deep volume).
Render Animation writes, per frame, the
red, green and blue patterns as 8-bit grey PNGs, their layout, and the focal stack the
display shows (EXR and contact sheet), into ``OUT/holo/display/Display/``; the .blend is
saved as ``OUT/display.blend`` (``blender -b OUT/display.blend -a`` renders it again).

    python -m holo_addon.display_demo [-o out] [--frames N] [--display W H PITCH_UM]
        [--lighting SCENE|ALBEDO] [--slices N]
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import time
from pathlib import Path

import numpy as np

from . import register
from .blender import compat

SCALE = 0.05  # display metres per scene metre: the scene's 1.2 m is 60 mm behind the display
EYE_BOX, PUPIL = 2.0, 4.0  # [mm]


def eye_distance(cols: int, rows: int, pitch: float, shortest=488e-9) -> float:
    """The nearest eye distance [mm], in 50 mm steps, from which the eye box sees the whole
    display inside the angle its half-band filter passes at the ``shortest`` wavelength
    [m] (the add-on's check): hypot(W/2 + E/2, H/2 + E/2) / tan θ, sin θ = λ/(4p); ``pitch``
    [µm]."""
    w, h = cols * pitch * 1e-3, rows * pitch * 1e-3
    sin_t = 0.5 * shortest / (2 * pitch * 1e-6)
    reach = math.hypot(w / 2 + EYE_BOX / 2, h / 2 + EYE_BOX / 2)
    return 50.0 * math.ceil(reach * math.sqrt(1 - sin_t**2) / sin_t / 50.0 * 1.02)


def _checker_card(bpy, size: float, depth: float):
    """A square card ``size`` m wide at ``depth`` m behind the origin, its Base Color an
    8 × 8 checker of warm and cool squares (an image texture the exporter samples)."""
    n = 256
    yy, xx = np.mgrid[0:n, 0:n] // (n // 8)
    odd = ((xx + yy) % 2).astype(bool)
    rgba = np.ones((n, n, 4), np.float32)
    rgba[odd, :3] = (0.9, 0.35, 0.1)
    rgba[~odd, :3] = (0.15, 0.45, 0.9)
    image = bpy.data.images.new("Checker", n, n, float_buffer=True)
    image.pixels.foreach_set(rgba.ravel())
    image.pack()
    bpy.ops.mesh.primitive_plane_add(size=size, location=(0.0, 0.0, -depth))
    card = bpy.context.object
    card.name = "Card"
    mat = bpy.data.materials.new("Checker")
    compat.enable_nodes(mat)
    tree = mat.node_tree
    bsdf = next(n for n in tree.nodes if n.type == "BSDF_PRINCIPLED")
    tex = tree.nodes.new("ShaderNodeTexImage")
    tex.image = image
    tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    card.data.materials.append(mat)
    card.holo.emitter = "TRIANGLES"
    return card


def _sphere(bpy, radius: float, location):
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=radius, location=location)
    sphere = bpy.context.object
    sphere.name = "Sphere"
    me = sphere.data
    attr = me.color_attributes.new("Col", "FLOAT_COLOR", "POINT")
    co = np.empty(len(me.vertices) * 3)
    me.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3) / radius
    rgb = np.clip(0.55 + 0.45 * co, 0.05, 1)
    attr.data.foreach_set("color", np.c_[rgb, np.ones(len(rgb))].ravel())
    me.color_attributes.active_color = attr
    sphere.holo.emitter = "POINTS"
    return sphere


def build_scene(bpy, *, frames: int = 24, display=None, lighting: str = "SCENE", slices: int = 5):
    """The scene (module docstring); ``display``: (cols, rows, pitch [µm]) of a custom
    display, or None (the 1080p, 8 µm preset). Returns (scene, the display object)."""
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, frames
    scene.holo.lighting = lighting
    scene.holo.lighting_samples = 4
    scene.render.engine = "BLENDER_WORKBENCH"  # the raster frame is not what this is for
    scene.render.resolution_x, scene.render.resolution_y = 32, 18
    cols, rows, pitch = (1920, 1080, 8.0) if display is None else display
    width, height = cols * pitch * 1e-6 / SCALE, rows * pitch * 1e-6 / SCALE  # in the scene
    card = _checker_card(bpy, 0.6 * min(width, height), 1.2)
    sphere = _sphere(bpy, 0.08 * width, (0.42 * width, 0.0, -0.8))
    for frame in (1, frames):
        t = (frame - 1) / max(1, frames - 1)
        card.rotation_euler = (0.0, math.radians(-20 + 40 * t), math.radians(30 * t))
        card.keyframe_insert("rotation_euler", frame=frame)
        sphere.location.y = (0.25 - 0.5 * t) * height
        sphere.keyframe_insert("location", frame=frame)
    bpy.ops.object.light_add(type="SUN", location=(1.0, -1.0, 2.0))
    bpy.context.object.rotation_euler = (0.6, 0.3, 0.0)
    bpy.context.object.data.energy = 3.0
    bpy.ops.object.camera_add(location=(0.0, 0.0, 30.0))
    scene.camera = bpy.context.object
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0.0, 0.0, 0.0))
    shown = bpy.context.object
    shown.name = "Display"
    d = shown.holo.display
    if display is not None:
        d.preset = "CUSTOM"
        d.resolution = display[:2]
        d.pitch = display[2]
    d.scene_scale = SCALE
    d.behind, d.front = 80.0, 0.0
    d.eye_distance, d.eye_box, d.pupil = eye_distance(cols, rows, pitch), EYE_BOX, PUPIL
    d.slices = slices
    shown.holo.is_display = True
    bpy.context.view_layer.update()
    return scene, shown


def main(argv=None):
    p = argparse.ArgumentParser(
        prog="python -m holo_addon.display_demo", description=__doc__.split("\n\n")[0]
    )
    p.add_argument("-o", "--output", type=Path, default=Path("out"))
    p.add_argument("--frames", type=int, default=24)
    p.add_argument(
        "--display",
        type=float,
        nargs=3,
        metavar=("W", "H", "PITCH_UM"),
        help="a custom display (default: 1920 x 1080 at 8 µm)",
    )
    p.add_argument("--lighting", choices=("SCENE", "ALBEDO"), default="SCENE")
    p.add_argument("--slices", type=int, default=5)
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(name)s: %(message)s")
    import bpy

    out = args.output.resolve()
    out.mkdir(parents=True, exist_ok=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    register()
    display = (
        None
        if args.display is None
        else (int(args.display[0]), int(args.display[1]), args.display[2])
    )
    scene, shown = build_scene(
        bpy, frames=args.frames, display=display, lighting=args.lighting, slices=args.slices
    )
    scene.holo.output_dir = str(out / "holo") + os.sep
    scene.render.filepath = str(out / "raster") + os.sep
    bpy.ops.wm.save_as_mainfile(filepath=str(out / "display.blend"))
    t0 = time.perf_counter()
    bpy.ops.render.render(animation=True)
    seconds = time.perf_counter() - t0
    print(
        f"display animation: {args.frames} frames in {seconds:.0f} s "
        f"({seconds / args.frames:.1f} s a frame):\n  "
        f"{out / 'holo' / 'display' / shown.name}\n  scene: {out / 'display.blend'}"
    )


if __name__ == "__main__":
    main()
