"""A holographic display's animation exported from Blender (issue 51's 24-frame target):
every frame's patterns, layouts and focal stack written, and frames bit-identical in any
order.

The scene is :mod:`holo_addon.display_demo`'s (a textured card and a colour sphere, lit by
a sun with Cycles, animated), shown on a display (a custom 256 x 256 at 8 µm by default:
``--display 1920 1080 8`` for the 1080p protocol). Render Animation (the bpy module's
``render.render(animation=True)``, as ``blender -b … -a``) renders frames 1 to N into one
output folder; then frames N, N/2 and 1, each alone, in that order, into a fresh folder
each (a farm's nodes); every file of those frames must be byte for byte the sequence's.
The figures: seconds per frame (the sequence's mean; the time of one frame alone as the
reference measured in the same run: the ratio is what the sequence's shared worker saves),
PSNR and SSIM of the focal stack per laser (the mean over slices and frames), whether every
frame was written, whether the frames alone were identical. Written to
``bench/results/display_animation.json``.

    python bench/display_animation.py [--frames 24] [--display W H PITCH_UM]
        [--lighting SCENE|ALBEDO] [--slices 5] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import results  # the bench folder's own: the figures as data


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--frames", type=int, default=24)
    p.add_argument(
        "--display", type=float, nargs=3, default=(256, 256, 8.0), metavar=("W", "H", "PITCH_UM")
    )
    p.add_argument("--lighting", choices=("SCENE", "ALBEDO"), default="SCENE")
    p.add_argument("--slices", type=int, default=5)
    p.add_argument("--out", type=Path, help="keep the frames here (default: a scratch folder)")
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="%(name)s: %(message)s")
    import bpy

    from holo_addon import register
    from holo_addon.compositor.session import session
    from holo_addon.display_demo import build_scene
    from holo_addon.export.display import frame_folder

    out = (args.out or Path(tempfile.mkdtemp(prefix="holo-display-bench-"))).resolve()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    register()
    session.exit_on_failure = False
    display = (int(args.display[0]), int(args.display[1]), float(args.display[2]))
    scene, shown = build_scene(
        bpy, frames=args.frames, display=display, lighting=args.lighting, slices=args.slices
    )
    scene.render.filepath = str(out / "raster") + os.sep

    def render(folder: Path, frames=None) -> float:
        scene.holo.output_dir = str(folder) + os.sep
        started = time.perf_counter()
        if frames is None:
            bpy.ops.render.render(animation=True)
        else:
            for frame in frames:
                scene.frame_set(frame)
                bpy.ops.render.render(write_still=True)
        return time.perf_counter() - started

    sequence_dir = out / "sequence"
    sequence = render(sequence_dir)
    folder = frame_folder(scene, shown.name)
    written, scores = [], {}
    for frame in range(1, args.frames + 1):
        layout_path = folder / f"frame_{frame:04d}.json"
        try:
            layout = json.loads(layout_path.read_text())
            names = [x[k] for x in layout["lasers"] for k in ("pattern", "layout")] + [
                layout["stack"]["file"],
                layout["stack"]["sheet"],
            ]
            complete = all((folder / n).is_file() for n in names)
        except (OSError, ValueError, KeyError):
            complete, layout = False, None
        written.append(complete)
        for x in (layout or {}).get("lasers", ()):
            scores.setdefault(x["name"], []).append((np.mean(x["psnr_db"]), np.mean(x["ssim"])))
    alone_frames = sorted({args.frames, max(1, args.frames // 2), 1}, reverse=True)
    identical, alone_seconds = [], []
    for i, frame in enumerate(alone_frames):
        alone_dir = out / f"alone_{i}"
        alone_seconds.append(render(alone_dir, [frame]))
        there = frame_folder(scene, shown.name)
        for path in sorted(folder.glob(f"frame_{frame:04d}*")):
            identical.append(
                (there / path.name).is_file()
                and (there / path.name).read_bytes() == path.read_bytes()
            )
    per_frame = sequence / args.frames
    alone = float(np.mean(alone_seconds))
    figures = {
        "display": f"{display[0]}x{display[1]} at {display[2]:g} µm",
        "lighting": args.lighting,
        "frames": args.frames,
        "slices": args.slices,
        "seconds per frame (sequence)": round(per_frame, 2),
        "seconds per frame alone (reference)": round(alone, 2),
        "alone / sequence": round(alone / per_frame, 2),
        "frames written": f"{sum(written)} of {args.frames}",
        "frames alone identical to the sequence's": f"{alone_frames}: {all(identical)}",
        "focal stack": {
            name: {
                "psnr_db": round(float(np.mean([a for a, _ in v])), 2),
                "ssim": round(float(np.mean([b for _, b in v])), 4),
            }
            for name, v in scores.items()
        },
    }
    path = results.write("display_animation", figures)
    print(json.dumps(figures, indent=1))
    print(f"written {path}; frames in {folder}; load {os.getloadavg()}")
    return 0 if all(written) and all(identical) else 1


if __name__ == "__main__":
    sys.exit(main())
