"""A plate recorded once, viewed from three cameras, against each camera's own camera hologram,
on the same scene and in the same run (the issue's test scene at full size, and its cost).

The scene (``tests/plate_scene.py``): a textured cube partly hiding a textured sphere, a 10 cm
plate halfway between them and the cameras, 640×360 at 50 mm f/2.8, cameras 2 cm apart inside
the viewing zone (3 cm around the centre camera's pupil). The plate is recorded once as
``--looks`` m² coded looks of one seed (``look_code``: phase codes that cancel the speckle's
cross terms between neighbouring emitters), each look timed; then each camera views one look
(look 0), two (the checkerboard pair, looks 0 and 3) and all m² of them. The reference is the
camera hologram's pass of that camera: its looks' limit ('incoherent'), and the default pass
(16 looks) whose time the views are compared with. Prints per camera and number of looks the
PSNR inside the objects, silhouette IoU and the speckle contrast on the cube's squares, the
occlusion (the cube and the sphere's visible part against the camera holograms, and how the
hidden part changes between the left and right views), then per number of looks the times:
the recording, a view, a camera-hologram pass, and the number of views from which the plate
costs less than the camera holograms (the crossover).

    python bench/plate_views.py [--samples 4096] [--scale 1.0] [--looks 2] [--out DIR]
"""

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from plate_scene import EYES, PLATE, camera, meshes

from holo_core.camera.render import render_camera
from holo_core.io.image import write_png
from holo_core.plate.record import look_code, record_plate
from holo_core.plate.view import render_view


def psnr(view, reference, inside) -> float:
    err = view.rgb[inside] - reference.rgb[inside]
    return float(20 * np.log10(reference.rgb[inside].max() / np.sqrt(np.mean(err**2))))


def iou(a, b) -> float:
    return float((a & b).sum() / (a | b).sum())


def flat_contrast(view, reference) -> tuple[float, int]:
    """The colour's contrast against the reference on the cube's faces where the reference is
    flat over 3×3 pixels (inside a checker square)."""
    solid = (view.alpha >= 1) & (reference.alpha >= 1) & (view.depth < NEAR)
    ref = reference.rgb.mean(-1)
    pad = np.pad(ref, 1, mode="edge")
    h, w = ref.shape
    spread = np.max([np.abs(pad[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] - ref)
                     for dy in (-1, 0, 1) for dx in (-1, 0, 1)], 0)
    flat = solid & (spread < 0.02 * ref.max())
    return float(np.std(view.rgb.mean(-1)[flat] / ref[flat])), int(flat.sum())


NEAR = 0.625  # [m] from the cameras: the cube lies nearer, the visible sphere farther


def regions(view):
    """(the cube's pixels, the visible sphere's pixels) by depth."""
    solid = view.alpha >= 0.5
    return solid & (view.depth < NEAR), solid & (view.depth >= NEAR)


def timed(f, *args, **kw):
    t = time.perf_counter()
    out = f(*args, **kw)
    return out, time.perf_counter() - t


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--samples", type=int, default=4096, help="plate samples per side (4096)")
    p.add_argument("--scale", type=float, default=1.0, help="image size, of 640x360 (1)")
    p.add_argument("--looks", type=int, default=2, help="m: m² coded looks recorded (2)")
    p.add_argument("--margin", type=float, default=0.03, help="zone margin [m] (0.03)")
    p.add_argument("--out", type=Path, default=None, help="a folder for the views' PNGs")
    args = p.parse_args()
    centre = camera("centre", args.scale)
    n = args.looks ** 2
    # warm: programs built, FFT plans made, on a small plate and view
    small = record_plate(meshes(), plate=PLATE, camera=camera("centre", 0.1), resolution=128,
                         zone_margin=args.margin)
    render_view(small, camera("centre", 0.1))
    render_camera(meshes(), camera("centre", 0.1), via="incoherent")
    render_camera(meshes(), camera("centre", 0.1), samples=1)
    plates, record_s, codes = [], [], [look_code(k, n) for k in range(n)]
    for code in codes:
        h, t = timed(record_plate, meshes(), plate=PLATE, camera=centre,
                     zone_margin=args.margin, resolution=args.samples, code=code)
        plates.append(h)
        record_s.append(t)
    h = plates[0]
    print(f"plate: {h.shape[1]}x{h.shape[0]} complex, λ = {h.wavelengths[0]:.4g} m, band "
          f"{h.band:.3g}, {n} coded look(s) recorded in {sum(record_s):.1f} s "
          f"({np.mean(record_s):.1f} s each)", flush=True)
    pair = [look_code(j, 2) for j in (0, 1)]  # the checkerboard pair, where it was recorded
    sets = {1: [0]} | ({2: [codes.index(c) for c in pair]} if set(pair) <= set(codes) else {}) \
        | {n: list(range(n))}
    rows, offsets, costs = [], {}, {}
    for eye in EYES:
        cam = camera(eye, args.scale)
        exact, exact_s = timed(render_camera, meshes(), cam, via="incoherent")
        looks, looks_s = timed(render_camera, meshes(), cam, samples=16)
        costs.setdefault("16 looks", []).append(looks_s)
        costs.setdefault("incoherent", []).append(exact_s)
        lp = psnr(looks, exact, (exact.alpha >= 1) & (looks.alpha >= 1))
        for count, chosen in sets.items():
            view, view_s = timed(render_view, [plates[i] for i in chosen], cam)
            costs.setdefault(count, []).append(view_s)
            inside = (exact.alpha >= 1) & (view.alpha >= 1)
            contrast, n_flat = flat_contrast(view, exact)
            (cube_v, sphere_v), (cube_e, sphere_e) = regions(view), regions(exact)
            offsets[eye, count] = int(sphere_v.sum()), int(sphere_e.sum()), \
                iou(cube_v, cube_e), iou(sphere_v, sphere_e)
            rows.append((eye, count, psnr(view, exact, inside),
                         iou(view.alpha > 0.5, exact.alpha > 0.5), contrast, lp, view_s,
                         exact_s, looks_s))
            print(f"{eye}, {count} look(s): PSNR {rows[-1][2]:.2f} dB, IoU {rows[-1][3]:.4f}, "
                  f"speckle {contrast:.3f} ({n_flat} px); view {view_s:.1f} s, camera hologram "
                  f"{looks_s:.1f} s (16 looks), {exact_s:.1f} s (incoherent)", flush=True)
            if args.out is not None:
                args.out.mkdir(parents=True, exist_ok=True)
                write_png(args.out / f"{eye}_plate_{count}.png",
                          np.clip(view.rgb * view.alpha[..., None], 0, 1) ** (1 / 2.2))
        if args.out is not None:
            write_png(args.out / f"{eye}_camera.png",
                      np.clip(exact.rgb * exact.alpha[..., None], 0, 1) ** (1 / 2.2))
    print("\ncamera  looks  PSNR [dB]  IoU     speckle  (16 looks vs limit [dB])  view [s]  "
          "incoherent [s]  16 looks [s]")
    for eye, count, ps, j, c, lp, vs, es, ls in rows:
        print(f"{eye:7s} {count:5d} {ps:9.2f}  {j:.4f}  {c:7.3f}  {lp:24.2f}  {vs:8.1f}  "
              f"{es:14.1f}  {ls:12.1f}")
    for count in sets:
        change = [offsets["right", count][i] - offsets["left", count][i] for i in (0, 1)]
        print(f"occlusion, {count} look(s): the sphere's visible pixels, right view minus left: "
              f"plate {change[0]}, camera holograms {change[1]}; IoU of the cube and of the "
              f"visible sphere against the camera holograms: " + ", ".join(
                  f"{eye} {offsets[eye, count][2]:.3f} / {offsets[eye, count][3]:.3f}"
                  for eye in EYES))
    for count in sets:
        view_s, rec_s = float(np.mean(costs[count])), float(np.mean(record_s)) * count
        for name in ("16 looks", "incoherent"):
            cost = float(np.mean(costs[name]))
            if cost > view_s:
                print(f"{count} look(s) against the camera hologram ({name}, {cost:.1f} s a "
                      f"view): the plate ({rec_s:.0f} s once + {view_s:.1f} s a view) costs "
                      f"less from {math.ceil(rec_s / (cost - view_s))} views on")
            else:
                print(f"{count} look(s) against the camera hologram ({name}, {cost:.1f} s a "
                      f"view): a plate view ({view_s:.1f} s) costs more: no crossover")


if __name__ == "__main__":
    main()
