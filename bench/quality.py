"""Picture quality of the holographic pass against Cycles' raster of the same objects.

A standard scene through the bpy module: a sphere with a fine colour checker, a sharp-edged
cube and a receding checkerboard plane, all emission-like (Cycles: emission strength 1 over a
black world, so both show each surface's own colour), seen by a 50 mm camera 3.5 m away. For
640×480, 1280×720 and 1920×1080, without depth of field and at f/2.8, it renders the pass
(camera holograms, the add-on's default; the plate mode too at 640×480) and Cycles' image,
alpha and Depth, and prints side by side: the cube's silhouette edge width (10–90 %, px), the
checker contrast on the plane, speckle contrast on a flat cube face, silhouette IoU, median
depth error (% of the depth extent), seconds per frame and the worker's peak memory.

    python bench/quality.py [--sizes 640x480 1280x720 1920x1080] [--samples 16]
"""

import argparse
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="holo-bench-"))


def read_exr(path):
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        return {k: v.pixels.copy() for k, v in f.channels().items()}


def checker_image(bpy, name, n, a, b, size=256):
    tiles = np.add.outer(np.arange(size) * n // size, np.arange(size) * n // size) % 2
    rgb = np.where(tiles[..., None] == 1, a, b)
    img = bpy.data.images.new(name, size, size, float_buffer=True)
    img.colorspace_settings.name = "Non-Color"
    img.pixels.foreach_set(
        np.c_[rgb.reshape(-1, 3), np.ones(size * size)].ravel().astype(np.float32)
    )
    return img


def emissive(bpy, obj, rgb=None, image=None):
    """A material the add-on reads (Base Color, or an image on it) that Cycles renders as
    the same colour: emission of that colour, strength 1, over a black world."""
    from holo_addon.blender import compat

    mat = bpy.data.materials.new(obj.name)
    compat.enable_nodes(mat)
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = next(n for n in nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Emission Strength"].default_value = 1.0
    if image is not None:
        tex = nodes.new("ShaderNodeTexImage")
        tex.image = image
        tex.interpolation = "Closest"
        links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
        links.new(tex.outputs["Color"], bsdf.inputs["Emission Color"])
    else:
        bsdf.inputs["Base Color"].default_value = (*rgb, 1)
        bsdf.inputs["Emission Color"].default_value = (*rgb, 1)
    obj.data.materials.append(mat)


def build(bpy, size, fstop):
    from holo_addon.demo import point_at

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.world = bpy.data.worlds.new("black")
    scene.world.color = (0, 0, 0)
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    bpy.ops.mesh.primitive_uv_sphere_add(
        radius=0.45, location=(-0.55, 0.2, 0.45), segments=96, ring_count=48
    )
    emissive(
        bpy,
        bpy.context.object,
        image=checker_image(bpy, "sphere", 24, (0.9, 0.2, 0.1), (0.1, 0.3, 0.9)),
    )
    bpy.ops.mesh.primitive_cube_add(size=0.7, location=(0.6, 0.0, 0.35), rotation=(0, 0, 0.5))
    emissive(bpy, bpy.context.object, rgb=(0.8, 0.6, 0.2))
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0, 0.6, 0.0))
    board = bpy.context.object
    board.scale = (2.4, 3.6, 1)
    emissive(
        bpy, board, image=checker_image(bpy, "board", 12, (0.85, 0.85, 0.85), (0.15, 0.15, 0.15))
    )
    for obj in (o for o in scene.objects if o.type == "MESH"):
        obj.holo.emitter = "POINTS"
    bpy.ops.object.camera_add(location=(0.0, -3.3, 1.2))
    cam = bpy.context.object
    point_at(cam, (0.0, 0.2, 0.35))
    cam.data.lens = 50
    scene.camera = cam
    if fstop:
        cam.data.dof.use_dof = True
        cam.data.dof.aperture_fstop = fstop
        cam.data.dof.focus_distance = 3.4
    bpy.ops.mesh.primitive_plane_add(size=2.0, location=(0.0, -1.6, 0.8))  # for the plate mode
    plate = bpy.context.object
    point_at(plate, (0.0, 0.0, 0.35))  # −Z away from the camera: +Z faces it
    plate.holo.is_plate = True
    bpy.context.view_layer.update()
    return scene


def cycles(bpy, scene, out):
    """Cycles' image (linear RGB), alpha and planar Depth of the holographic objects."""
    from holo_addon.blender import compat
    from holo_addon.blender.objects import show_as_raster

    for obj in scene.objects:
        if obj.type == "MESH" and not obj.holo.is_plate:
            show_as_raster(obj)
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 32
    scene.cycles.max_bounces = 0  # the emission alone: no light bounced between the surfaces
    scene.cycles.pixel_filter_type = "BOX"
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    scene.view_layers[0].use_pass_z = True
    compat.set_exr_output(scene, multilayer=False)
    scene.render.filepath = str(out / "raster.exr")
    bpy.ops.render.render(write_still=True)
    img = read_exr(out / "raster.exr")
    tree = compat.compositor_tree(scene)
    layers = tree.nodes.new("CompositorNodeRLayers")
    layers.scene = scene
    tree.links.new(layers.outputs["Depth"], compat.output_socket(tree))
    scene.render.filepath = str(out / "depth.exr")
    bpy.ops.render.render(write_still=True)
    rgb = np.stack([img[c] for c in "RGB"], -1)
    return rgb, img["A"], read_exr(out / "depth.exr")["R"]


def edge_width(lum, alpha):
    """10–90 % width [px] of the cube's top silhouette edge against the black sky: the
    premultiplied luminance down each column of the cube's middle, normalised between the sky
    and the cube's top face."""
    h, w = lum.shape
    widths = []
    for c in range(int(0.62 * w), int(0.85 * w)):
        rows = np.nonzero(alpha[:, c] > 0.5)[0]
        if not len(rows) or rows[0] < 8:
            continue
        r = rows[0]
        seg = lum[r - 6 : r + 7, c]
        plateau = np.median(lum[r + 3 : r + 3 + max(3, h // 60), c])
        if plateau <= 0:
            continue
        f = np.maximum.accumulate(np.clip(seg / plateau, 0, 1))
        x = np.arange(len(f), dtype=float)
        widths.append(np.interp(0.9, f, x) - np.interp(0.1, f, x))
    return float(np.median(widths)) if widths else float("nan")


def metrics(rgb, alpha, depth, ref_alpha, ref_depth):
    lum = rgb.mean(-1) * alpha
    mine, theirs = alpha > 0.5, ref_alpha > 0.5
    iou = (mine & theirs).sum() / max((mine | theirs).sum(), 1)
    both = mine & theirs & (ref_depth < 1e9)
    extent = np.ptp(ref_depth[theirs & (ref_depth < 1e9)])
    derr = np.median(np.abs(depth[both] - ref_depth[both])) / extent
    h, w = lum.shape
    # checker contrast: the board's near half, below the objects
    board = lum[int(h * 0.88) :, w // 8 : 7 * w // 8]
    hi, lo = np.percentile(board, 90), np.percentile(board, 10)
    checker = (hi - lo) / (hi + lo)
    # speckle: the middle of the cube's front face
    face = lum[int(0.45 * h) : int(0.7 * h), int(0.62 * w) : int(0.85 * w)]
    speckle = float(face.std() / face.mean())
    return dict(edge=edge_width(lum, alpha), checker=checker, speckle=speckle, iou=iou, depth=derr)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--sizes", nargs="+", default=["640x480", "1280x720", "1920x1080"])
    p.add_argument("--samples", type=int, default=16)
    args = p.parse_args()
    import bpy

    sys.path.insert(0, str(ROOT))
    import holo_addon
    from holo_addon.render import pipeline

    holo_addon.register()
    rows = []
    for size in args.sizes:
        wh = tuple(int(v) for v in size.split("x"))
        for fstop in (None, 2.8):
            # the plate mode once, small: its recording of this scene's 10^5-10^6 points is slow
            modes = ("CAMERA", "PLATE") if wh == (640, 480) and not fstop else ("CAMERA",)
            for mode in modes:
                out = Path(tempfile.mkdtemp(prefix="holo-quality-"))
                scene = build(bpy, wh, fstop)
                scene.holo.output_dir = str(out / "holo") + os.sep
                scene.holo.mode = mode
                scene.holo.samples = args.samples
                scene.holo.iterations = 2
                t = time.perf_counter()
                ok = bpy.ops.holo.render_pass() == {"FINISHED"}
                seconds = time.perf_counter() - t
                peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1e6
                if not ok:
                    print(f"{size} f/{fstop} {mode}: the pass failed")
                    continue
                holo = read_exr(pipeline.pass_file(pipeline.output_dir(scene), scene.frame_current))
                alpha = holo["ViewLayer.Combined.A"]
                rgb = np.stack([holo[f"ViewLayer.Combined.{c}"] for c in "RGB"], -1)
                rgb = rgb / np.maximum(alpha, 1e-6)[..., None]
                ref_rgb, ref_alpha, ref_depth = cycles(bpy, scene, out)
                ref_rgb = ref_rgb / np.maximum(ref_alpha, 1e-6)[..., None]
                from holo_core.io.image import srgb, write_png

                write_png(
                    ROOT / "out" / f"quality_{size}_{fstop}_{mode}.png",
                    srgb(
                        np.concatenate([rgb * alpha[..., None], ref_rgb * ref_alpha[..., None]], 1)
                    ),
                )
                m = metrics(rgb, alpha, holo["ViewLayer.Depth.Z"], ref_alpha, ref_depth)
                r = metrics(ref_rgb, ref_alpha, ref_depth, ref_alpha, ref_depth)
                rows.append((size, fstop, mode, m, r, seconds, peak))
                print(
                    f"{size:>9} {'f/' + str(fstop) if fstop else 'no DOF':>7} {mode:>6}: "
                    f"edge {m['edge']:.2f} px (Cycles {r['edge']:.2f}), checker contrast "
                    f"{m['checker']:.3f} ({r['checker']:.3f}), speckle {m['speckle']:.3f} "
                    f"({r['speckle']:.3f}), IoU {m['iou']:.3f}, depth error "
                    f"{m['depth']:.2%}, {seconds:.1f} s, worker peak {peak:.2f} GB",
                    flush=True,
                )
    print(
        "goals: edge <= 1.5 px, speckle <= 0.10, IoU >= 0.97, depth <= 0.5 %, 1280x720 <= "
        "60 s, 1920x1080 <= 180 s (2-core CPU)"
    )
    results.write(
        "quality",
        {
            f"{size}, {'f/' + str(fstop) if fstop else 'no DOF'}, {mode.lower()}": {
                "edge 10-90 % [px]": m["edge"],
                "Cycles' edge [px]": r["edge"],
                "checker contrast": m["checker"],
                "Cycles' contrast": r["checker"],
                "speckle": m["speckle"],
                "IoU": m["iou"],
                "depth error": m["depth"],
                "s per frame": seconds,
                "worker peak [GB]": peak,
            }
            for size, fstop, mode, m, r, seconds, peak in rows
        },
    )


if __name__ == "__main__":
    main()
