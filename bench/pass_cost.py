"""The holographic pass against Cycles' frame: the demo scene (``make demo``) at 1280×720 and
1920×1080, f/2.8, in one run.

For each size, in this order: the holographic pass of the sphere (camera hologram, the add-on's
defaults, through the worker process as a render makes it, caches warm after a first small
pass), then Cycles' render of the whole frame at the demo's 32 samples with the sphere as an
ordinary object. Prints both times and their ratio (the issue's goal: at most 0.5 at 1080p).

    python bench/pass_cost.py [--sizes 1280x720 1920x1080] [--samples 16]
"""

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="holo-bench-"))


def timed_pass(bpy, pipeline, scene) -> float:
    depsgraph = bpy.context.evaluated_depsgraph_get()
    t = time.perf_counter()
    pipeline.run(pipeline.prepare(scene, depsgraph))
    return time.perf_counter() - t


def timed_cycles(bpy, scene, sphere, out: Path) -> float:
    from holo_addon.blender.objects import raster_visibility

    sphere.holo.emitter = "NONE"
    raster_visibility(sphere)
    scene.render.filepath = str(out / "cycles.png")
    t = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    seconds = time.perf_counter() - t
    sphere.holo.emitter = "POINTS"
    raster_visibility(sphere)
    return seconds


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", nargs="+", default=["1280x720", "1920x1080"])
    p.add_argument("--samples", type=int, default=16)
    args = p.parse_args()
    import bpy

    sys.path.insert(0, str(ROOT))
    from holo_addon import register
    from holo_addon.demo import build_scene
    from holo_addon.render import pipeline

    bpy.ops.wm.read_factory_settings(use_empty=True)
    register()
    out = Path(tempfile.mkdtemp(prefix="holo-pass-cost-"))
    rows = []
    for i, size in enumerate(args.sizes):
        w, h = (int(v) for v in size.split("x"))
        if i == 0:
            bpy.ops.wm.read_factory_settings(use_empty=True)
            scene = build_scene(bpy, resolution=(w, h), fstop=2.8)
            scene.holo.output_dir = str(out / "holo") + os.sep
            scene.holo.samples = args.samples
            scene.render.resolution_percentage = 25  # warm: kernels built, plans made
            timed_pass(bpy, pipeline, scene)
        scene.render.resolution_x, scene.render.resolution_y = w, h
        scene.render.resolution_percentage = 100
        sphere = scene.objects["Hologram Sphere"]
        holo = timed_pass(bpy, pipeline, scene)
        cycles = timed_cycles(bpy, scene, sphere, out)
        rows.append((size, holo, cycles))
        print(
            f"{size}: holographic pass {holo:.1f} s, Cycles frame ({scene.cycles.samples} "
            f"samples) {cycles:.1f} s, ratio {holo / cycles:.2f}",
            flush=True,
        )
    print("\nsize        pass [s]  Cycles [s]  pass/Cycles")
    for size, holo, cycles in rows:
        print(f"{size:10s} {holo:9.1f} {cycles:11.1f} {holo / cycles:12.2f}")
    results.write(
        "pass_cost",
        {
            size: {"pass [s]": holo, "Cycles [s]": cycles, "pass / Cycles": holo / cycles}
            for size, holo, cycles in rows
        },
    )


if __name__ == "__main__":
    main()
