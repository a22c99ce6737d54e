"""The demo's scene over a camera move, rendered as an animation through the add-on, in Plate
mode and in Camera mode, as an artist's F12 or a farm's ``blender -a`` renders it.

The scene is ``make demo``'s (a lit, glossy holographic sphere among rasterized objects, 40 mm
at f/2.8, 1280×720); the camera dollies ``--dolly`` (10 cm) across over ``--frames`` frames.
In Plate mode the plate's zone is fitted to the shot (*Fit Zone to Shot*, ``--margin``
around the pupil), so the first frame records it and every frame renders from it; in Camera
mode each frame records its own camera hologram. Each frame's holographic pass is timed
where the render's frame handler makes it (the job's hand-over to the worker, its work, its
files; Blender's raster of the frame, the same in both modes, is not counted). Each mode
runs in a Blender process of its own. Prints the CPU and its load, each mode's frames, and
the frame count from which the plate costs less than a camera hologram per frame.

    python bench/shot_blender.py [--frames 8] [--dolly 0.1] [--margin 0.01] [--out DIR]
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "bench")]

from shot import cpu  # noqa: E402

RESULT = "SHOT-RESULT "  # the child's line of timings


def render_mode(mode: str, args) -> list[tuple[int, float]]:
    """(frame, seconds of its holographic pass) for each frame of the animation in ``mode``,
    in this process (Blender's, through the bpy module)."""
    import bpy

    from holo_addon import register
    from holo_addon.blender import compat
    from holo_addon.demo import build_scene
    from holo_addon.render import pipeline

    bpy.ops.wm.read_factory_settings(use_empty=True)
    register()
    scene = build_scene(bpy, resolution=(1280, 720), fstop=2.8)
    scene.holo.output_dir = str(args.out / mode / "holo") + os.sep
    scene.holo.mode = mode
    scene.cycles.samples = 1  # the raster is the same in both modes and not timed
    camera, x = scene.camera, scene.camera.location.x
    for frame, dx in ((1, -args.dolly / 2), (args.frames, args.dolly / 2)):
        camera.location.x = x + dx
        camera.keyframe_insert("location", frame=frame)
    scene.frame_start, scene.frame_end = 1, args.frames
    scene.frame_set(1)
    if mode == "PLATE":
        plate = scene.objects["Hologram Plate"]
        bpy.context.view_layer.objects.active = plate
        plate.select_set(True)
        plate.holo.zone_margin = args.margin
        if bpy.ops.holo.fit_zone_to_shot() != {"FINISHED"}:
            sys.exit("shot_blender: Fit Zone to Shot failed")
    if bpy.ops.holo.setup_compositing() != {"FINISHED"}:
        sys.exit("shot_blender: Set Up Compositing failed")
    compat.set_png_output(scene)
    scene.render.filepath = str(args.out / mode / "frame_")
    timings, run = [], pipeline.run

    def timed(job, *a, **kw):  # the handler's call: the hand-over, the worker's work, files
        t = time.perf_counter()
        result = run(job, *a, **kw)
        timings.append((job.job.output.frame, time.perf_counter() - t))
        return result

    pipeline.run = timed
    bpy.ops.render.render(animation=True)
    if len(timings) != args.frames:
        sys.exit(f"shot_blender: {len(timings)} of {args.frames} passes made in {mode} mode")
    return timings


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--frames", type=int, default=8, help="frames of the move (8)")
    p.add_argument("--dolly", type=float, default=0.1, help="the camera's move [m] (0.1)")
    p.add_argument("--margin", type=float, default=0.01, help="zone margin [m] (0.01)")
    p.add_argument("--out", type=Path, default=None, help="a folder for the frames")
    p.add_argument("--mode", choices=("PLATE", "CAMERA"), help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.frames < 2:
        p.error("--frames must be at least 2")
    if args.mode:  # the child: one mode in this Blender process
        args.out = args.out.resolve()
        print(RESULT + json.dumps(render_mode(args.mode, args)), flush=True)
        return
    print(f"CPU: {cpu()}; load {os.getloadavg()[0]:.1f} (1 min) at the start")
    with tempfile.TemporaryDirectory() as scratch:
        out = args.out or Path(scratch)
        frames = {}
        for mode in ("PLATE", "CAMERA"):
            child = subprocess.run(
                [
                    sys.executable,
                    __file__,
                    "--mode",
                    mode,
                    "--frames",
                    str(args.frames),
                    "--dolly",
                    str(args.dolly),
                    "--margin",
                    str(args.margin),
                    "--out",
                    str(out),
                ],
                capture_output=True,
                text=True,
                check=False,
            )
            lines = [ln for ln in child.stdout.splitlines() if ln.startswith(RESULT)]
            if child.returncode or not lines:
                sys.exit(
                    f"shot_blender: {mode} mode failed: "
                    f"{(child.stderr or child.stdout).strip()[-2000:]}"
                )
            frames[mode] = [s for _, s in sorted(json.loads(lines[-1][len(RESULT) :]))]
            print(
                f"{mode.lower()} mode, each frame's pass [s]: "
                + " ".join(f"{s:.2f}" for s in frames[mode])
                + f" (load {os.getloadavg()[0]:.1f})",
                flush=True,
            )
    plate, camera = frames["PLATE"], frames["CAMERA"]
    first, frame_s, pass_s = plate[0], float(np.median(plate[1:])), float(np.median(camera))
    figures = {
        "frames": args.frames,
        "dolly [m]": args.dolly,
        "plate mode: the first frame [s]": first,
        "plate mode: a frame, median [s]": frame_s,
        "camera mode: a frame, median [s]": pass_s,
    }
    print(
        f"plate: the first frame {first:.1f} s (the plate recorded, lit by Cycles, written), "
        f"then {frame_s:.2f} s a frame; camera holograms {pass_s:.2f} s a frame"
    )
    if pass_s > frame_s:
        n = int(np.ceil((first - frame_s) / (pass_s - frame_s)))
        print(
            f"the plate costs less than a camera hologram per frame from {n} frames on; "
            f"24 frames: {first + 23 * frame_s:.0f} s against {24 * pass_s:.0f} s"
        )
        figures.update(
            {
                "break-even [frames]": n,
                "24 frames from the plate [s]": first + 23 * frame_s,
                "24 frames as camera holograms [s]": 24 * pass_s,
            }
        )
    else:
        print("a plate's frame costs more than a camera hologram's: no break-even")
        figures["break-even [frames]"] = "none"
    results.write("shot_blender", figures)


if __name__ == "__main__":
    main()
