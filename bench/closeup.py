"""A close-up plate scene through the add-on's defaults, against each frame's camera hologram.

The scene is ``tests/plate_scene.py`` at full size: a textured cube 3.6 cm across partly
hiding a textured sphere, about 0.6 m from the cameras; a 10 cm plate halfway (0.3 m); 50 mm
at f/2.8, 640×360. The plate's zone is the add-on's Fit Zone to Shot over the three cameras
(the centre and 2 cm either side) with its default Zone Margin (5 mm; ``--zone camera``: Fit
Zone to Camera around the centre camera, ``--margin`` 5 cm, the add-on's earlier default, which
the side cameras' pupils leave by 2 mm). Four coded looks of one seed are recorded (as two
pairs, so that the recording holds half of them at a time: the checkerboard pair is looks 0
and 3 of the four). For each setting (2 or 4 looks, Supersample 2 or the view's Nyquist rate,
:func:`holo_core.plate.window.nyquist_supersample`) and for the plan's own choice
(:func:`holo_core.plate.quality.choose`, what Auto renders: its looks recorded apart) the
views of the three cameras are compared with their camera holograms (Speckle: Exact, the
add-on's default camera pass, and the same at supersample 4, taken as converged: the default
pass lies about 35 dB from it): PSNR inside the objects, silhouette IoU, the speckle contrast
on the cube's flat faces, the view's seconds, and the plan's prediction with what its model
takes (bench/quality_fit.py fits the model to these figures). With ``--seeds 2`` (the
default) a second seed's looks split each error into the speckle's part and the part no seed
changes. With ``--out`` the views, the references and their error maps are written as PNGs.

    python bench/closeup.py [--scene closeup|shot] [--zone shot|camera] [--margin M]
                            [--scale 1.0] [--seeds 2] [--out DIR]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
import results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from plate_scene import PLATE, camera, meshes  # noqa: E402

from holo_core.camera.render import render_camera  # noqa: E402
from holo_core.io.image import write_png  # noqa: E402
from holo_core.plate.look_codes import look_code  # noqa: E402
from holo_core.plate.looks import record_planned  # noqa: E402
from holo_core.plate.quality import choose, reference_view, speckle_variance  # noqa: E402
from holo_core.plate.recording import plate_plan  # noqa: E402
from holo_core.plate.view import render_view  # noqa: E402
from holo_core.plate.window import nyquist_supersample  # noqa: E402
from holo_core.scene.plate import SHOT_ZONE_MARGIN, Plate, ViewingZone  # noqa: E402

CONVERGED = 4  # the camera hologram's supersampling taken as converged (beside its default)
CAMERA_MARGIN = 0.05  # [m] --zone camera's margin: around one camera, room to look about
EYES = {"left": (-0.02, 0.0, 0.3), "centre": (0.0, 0.0, 0.3), "right": (0.02, 0.0, 0.3)}


def psnr(view, reference, inside) -> float:
    """PSNR [dB] of the colour inside the objects, peak the reference's brightest there."""
    err = view.rgb[inside] - reference.rgb[inside]
    return float(20 * np.log10(reference.rgb[inside].max() / np.sqrt(np.mean(err**2))))


def iou(a, b) -> float:
    return float((a & b).sum() / max((a | b).sum(), 1))


def speckle_contrast(view, reference) -> float:
    """The luminance's contrast against the reference's on the objects' flat squares (pixels
    whose reference neighbourhood is flat), as tests/core/plate/test_view.py measures it."""
    solid = (view.alpha >= 1) & (reference.alpha >= 1)
    lum, ref = view.rgb.mean(-1), reference.rgb.mean(-1)
    pad = np.pad(ref, 1, mode="edge")
    spread = np.max(
        [
            np.abs(pad[1 + dy : 1 + dy + ref.shape[0], 1 + dx : 1 + dx + ref.shape[1]] - ref)
            for dy in (-1, 0, 1)
            for dx in (-1, 0, 1)
        ],
        0,
    )
    flat = solid & (spread < 0.02 * ref.max())
    return float(np.std(lum[flat] / ref[flat])) if flat.sum() >= 20 else float("nan")


def error_split(view, reference, inside) -> dict:
    """Where the squared error inside the objects lies: the share within 2 px of the
    silhouette or of a depth step (edges), and the rest (faces)."""
    edge = ~inside
    depth = np.where(reference.alpha > 0.5, reference.depth, 0)
    step = np.zeros_like(edge)
    step[:, 1:] |= np.abs(np.diff(depth, axis=1)) > 0.01
    step[1:, :] |= np.abs(np.diff(depth, axis=0)) > 0.01
    edge = edge | step
    for _ in range(2):
        grown = edge.copy()
        grown[1:] |= edge[:-1]
        grown[:-1] |= edge[1:]
        grown[:, 1:] |= edge[:, :-1]
        grown[:, :-1] |= edge[:, 1:]
        edge = grown
    err = ((view.rgb - reference.rgb) ** 2).sum(-1)
    total = float(err[inside].sum())
    near = float(err[inside & edge].sum())
    return {
        "edge share of the error": near / total if total else 0.0,
        "edge pixels": int((inside & edge).sum()),
        "face pixels": int((inside & ~edge).sum()),
        "PSNR on faces [dB]": psnr(view, reference, inside & ~edge),
        "PSNR near edges [dB]": psnr(view, reference, inside & edge),
    }


def seed_split(a, b, reference) -> dict:
    """The error of views ``a`` and ``b`` of two seeds' looks (the same settings) split into
    the speckle's part (what changes with the seed: rms(a - b)/sqrt 2 a view) and the part
    that is the same for every seed (the mean of the product of their errors), each as a
    PSNR [dB] over the pixels inside the objects in all three."""
    inside = (reference.alpha >= 1) & (a.alpha >= 1) & (b.alpha >= 1)
    peak = float(reference.rgb[inside].max())
    da, db = (v.rgb[inside] - reference.rgb[inside] for v in (a, b))
    speckle = float(np.mean((da - db) ** 2) / 2)
    common = max(float(np.mean(da * db)), 1e-30)
    return {
        "speckle part [dB]": float(10 * np.log10(peak**2 / speckle)),
        "seed-free part [dB]": float(10 * np.log10(peak**2 / common)),
    }


def settings(nyquist: int) -> dict:
    """Each setting measured: (the looks of the four viewed, the supersampling)."""
    return {
        "defaults (2 looks, supersample 2)": ((0, 3), 2),
        "4 looks, supersample 2": ((0, 1, 2, 3), 2),
        f"2 looks, supersample {nyquist} (Nyquist)": ((0, 3), nyquist),
        f"4 looks, supersample {nyquist} (Nyquist)": ((0, 1, 2, 3), nyquist),
    }


def record_four(planned, seed: int):
    """The four coded looks of ``seed`` (a list, look k at k), recorded as two pairs so that
    the recording holds two at a time; the add-on's two Iterations are looks 0 and 3."""
    looks, t0 = [None] * 4, time.perf_counter()
    for pair in ((0, 3), (1, 2)):
        t = time.perf_counter()
        got = record_planned(planned, codes=[look_code(k, 4) for k in pair], seed=seed)
        for k, h in zip(pair, got):
            looks[k] = h
        print(
            f"  seed {seed}, looks {pair} recorded in {time.perf_counter() - t:.1f} s (load "
            f"{os.getloadavg()[0]:.1f})",
            flush=True,
        )
    return looks, time.perf_counter() - t0


def picture(v):
    return np.clip(v.rgb * v.alpha[..., None], 0, 1) ** (1 / 2.2)


def closeup(args):
    """(meshes, the three cameras, the plate with its zone): the close-up, its zone fitted to
    the three cameras' pupils (Fit Zone to Shot) or around the centre camera's (Fit Zone to
    Camera) with the margin."""
    cams = {eye: camera(pos, scale=args.scale) for eye, pos in EYES.items()}
    if args.zone == "camera":
        zone = PLATE.zone_for(cams["centre"], args.margin)
    else:
        first = cams["left"]
        zone = ViewingZone.fit(
            [c.position for c in cams.values()],
            pupil=first.aperture_diameter,
            margin=args.margin,
            pixel=first.pixel_angle(),
        )
    return (
        meshes(),
        cams,
        Plate(matrix_world=PLATE.matrix_world, width=PLATE.width, height=PLATE.height, zone=zone),
    )


def shot_scene(args):
    """The same for bench/shot.py's scene: its frames at the start, middle and end of its
    10 cm dolly, the zone fitted to them with the margin."""
    import shot

    cams = {
        eye: shot.camera(x, args.scale)
        for eye, x in (("left", -0.05), ("centre", 0.0), ("right", 0.05))
    }
    first = cams["left"]
    zone = ViewingZone.fit(
        [c.position for c in cams.values()],
        pupil=first.aperture_diameter,
        margin=args.margin,
        pixel=first.pixel_angle(),
    )
    return (
        shot.scene(),
        cams,
        Plate(
            matrix_world=shot.PLATE.matrix_world,
            width=shot.PLATE.width,
            height=shot.PLATE.height,
            zone=zone,
        ),
    )


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scale", type=float, default=1.0, help="image size, of 640x360 (1)")
    p.add_argument("--out", type=Path, default=None, help="a folder for the PNGs")
    p.add_argument(
        "--seeds",
        type=int,
        default=2,
        choices=(1, 2),
        help="seeds recorded: with 2 each error is split into the speckle's part "
        "and the part no seed changes (2)",
    )
    p.add_argument(
        "--zone",
        choices=("shot", "camera"),
        default="shot",
        help="the close-up's zone: fitted to its three cameras, or around the centre one (shot)",
    )
    p.add_argument(
        "--margin",
        type=float,
        default=None,
        help=f"the zone's margin [m] ({SHOT_ZONE_MARGIN:g} for a shot's zone, "
        f"{CAMERA_MARGIN:g} around a camera)",
    )
    p.add_argument(
        "--scene",
        choices=("closeup", "shot"),
        default="closeup",
        help="the close-up, or bench/shot.py's scene measured the same way",
    )
    args = p.parse_args()
    if args.margin is None:
        args.margin = SHOT_ZONE_MARGIN if args.zone == "shot" else CAMERA_MARGIN
    scene, cams, plate = closeup(args) if args.scene == "closeup" else shot_scene(args)
    print(f"load {os.getloadavg()[0]:.1f} at the start")
    planned = plate_plan(scene, plate=plate, looks=2)
    print(f"plan: {planned.plan.describe()}")
    resolution = cams["centre"].resolution
    choice = choose(planned.plan, resolution=resolution)
    print(f"the plan's choice: {choice.describe()}")
    auto = f"the plan's choice ({choice.looks} looks, supersample {choice.supersample})"
    chosen_plan = plate_plan(scene, plate=plate, looks=choice.looks)
    refs, converged = {}, {}
    for eye, cam in cams.items():
        t = time.perf_counter()
        refs[eye] = render_camera(scene, cam, via="incoherent")
        print(f"camera hologram {eye}: {time.perf_counter() - t:.1f} s", flush=True)
        converged[eye] = render_camera(scene, cam, via="incoherent", supersample=CONVERGED)
    views, record_s, nyquist = {}, 0.0, None
    for seed in range(args.seeds):  # each seed's looks held only while its views are made
        looks, seconds = record_four(planned, seed)
        record_s += seconds / args.seeds
        nyquist = nyquist_supersample(looks[0], cams["centre"])
        for name, (which, ss) in settings(nyquist).items():
            for eye, cam in cams.items():
                t = time.perf_counter()
                view = render_view([looks[k] for k in which], cam, supersample=ss)
                views[seed, name, eye] = view, time.perf_counter() - t
        del looks
        t = time.perf_counter()  # what Auto records and renders
        chosen = record_planned(
            chosen_plan, seed=seed, codes=[look_code(k, choice.looks) for k in range(choice.looks)]
        )
        print(
            f"  seed {seed}, the plan's {choice.looks} looks recorded in "
            f"{time.perf_counter() - t:.1f} s",
            flush=True,
        )
        for eye, cam in cams.items():
            t = time.perf_counter()
            view = render_view(chosen, cam, supersample=choice.supersample)
            views[seed, auto, eye] = view, time.perf_counter() - t
        del chosen
    figures = {
        "scene": f"{args.scene} at {cams['centre'].resolution[0]}x"
        f"{cams['centre'].resolution[1]}, 50 mm f/2.8, a 10 cm plate, its zone "
        f"fitted to the {args.zone}, margin {args.margin:g} m",
        "plate": f"{planned.plan.shape[1]} x {planned.plan.shape[0]} samples",
        "four looks recorded [s]": record_s,
        "Nyquist supersample": nyquist,
    }
    predicted = {
        name: choose(planned.plan, resolution=resolution, looks=len(which), supersample=ss).psnr
        for name, (which, ss) in settings(nyquist).items()
    }
    predicted[auto] = choice.psnr
    # what the quality model takes (holo_core.plate.quality; bench/quality_fit.py fits it)
    blurs, size = reference_view(planned.plan)
    figures["objects' size [px]"] = size
    taken = {name: (len(which), ss) for name, (which, ss) in settings(nyquist).items()}
    taken[auto] = (choice.looks, choice.supersample)
    for name in predicted:
        rows = []
        for eye in cams:
            view, seconds = views[0, name, eye]
            ref = refs[eye]
            inside = (ref.alpha >= 1) & (view.alpha >= 1)
            row = {
                "PSNR [dB]": psnr(view, ref, inside),
                "IoU": iou(view.alpha > 0.5, ref.alpha > 0.5),
                "speckle contrast": speckle_contrast(view, ref),
                "view [s]": seconds,
                **error_split(view, ref, inside),
                "predicted [dB]": predicted[name],
                "looks": taken[name][0],
                "supersample": taken[name][1],
                "(σ/⟨I⟩)²": float(np.mean(speckle_variance(blurs, *taken[name]))),
            }
            truth = converged[eye]
            row[f"PSNR against supersample {CONVERGED} [dB]"] = psnr(
                view, truth, (truth.alpha >= 1) & (view.alpha >= 1)
            )
            row[f"IoU against supersample {CONVERGED}"] = iou(view.alpha > 0.5, truth.alpha > 0.5)
            if args.seeds > 1:
                row.update(seed_split(views[0, name, eye][0], views[1, name, eye][0], ref))
            rows.append(row)
            figures[f"{name}, {eye}"] = row
            split = (
                f"; speckle {row['speckle part [dB]']:.2f} dB, seed-free "
                f"{row['seed-free part [dB]']:.2f} dB"
                if args.seeds > 1
                else ""
            )
            print(
                f"{name}, {eye}: PSNR {row['PSNR [dB]']:.2f} dB ({CONVERGED}x "
                f"{row[f'PSNR against supersample {CONVERGED} [dB]']:.2f}; faces "
                f"{row['PSNR on faces [dB]']:.2f}, near edges "
                f"{row['PSNR near edges [dB]']:.2f}, edge share "
                f"{row['edge share of the error']:.2f}){split}, IoU {row['IoU']:.4f}, "
                f"speckle contrast {row['speckle contrast']:.4f}, view {seconds:.2f} s",
                flush=True,
            )
            if args.out is not None:
                args.out.mkdir(parents=True, exist_ok=True)
                tag = name.split(" (")[0].replace(", ", "_").replace(" ", "").replace("'", "")
                write_png(args.out / f"{eye}_{tag}.png", picture(view))
                err = np.abs(view.rgb - ref.rgb).mean(-1) * inside
                write_png(
                    args.out / f"{eye}_{tag}_error.png",
                    np.clip(err / max(float(ref.rgb.max()), 1e-12) * 8, 0, 1)[..., None].repeat(
                        3, -1
                    ),
                )
        against = [r[f"PSNR against supersample {CONVERGED} [dB]"] for r in rows]
        print(
            f"{name}: predicted {predicted[name]:.2f} dB; measured "
            f"{min(r['PSNR [dB]'] for r in rows):.2f}-"
            f"{max(r['PSNR [dB]'] for r in rows):.2f} dB ({min(against):.2f}-"
            f"{max(against):.2f} against supersample {CONVERGED}), IoU "
            f"{min(r['IoU'] for r in rows):.4f}-{max(r['IoU'] for r in rows):.4f} (load "
            f"{os.getloadavg()[0]:.1f})",
            flush=True,
        )
    if args.out is not None:
        for eye, ref in refs.items():
            write_png(args.out / f"{eye}_camera.png", picture(ref))
    name = "closeup" if args.scene == "closeup" else "closeup_shot_scene"
    name += "_camera_zone" if args.zone == "camera" else ""
    results.write(name if args.scale == 1 else f"{name}_scale{args.scale:g}", figures)


if __name__ == "__main__":
    main()
