"""What Lighting: Scene costs: the demo's holographic pass (``make demo``: 1280×720, f/2.8,
16 samples, Cycles at 32 samples) with the emitters' colours from Cycles' lit radiance
against the same pass with their albedo, in one run.

Each pass is made from scratch (its own output folder: nothing reused) through the worker
process as a render makes it; Scene's includes writing the scene for Cycles, the Blender
process that renders the emitters' radiance (cropped to them) and its projection onto them.
The two alternate for ``--rounds`` rounds after a small warm-up pass (kernel and program
caches). Two figures: the lighting stages' time (writing the scene, timed here; the radiance
render and projection, timed by the worker) against the rest of the same pass, which a busy
machine slows alike; and the best whole-pass times of the two, which it does not (on a shared
machine only the first is steady). The issue's goal: lighting adds at most 25 %.

    python bench/lighting.py [--resolution 1280 720] [--samples 16] [--rounds 2]
"""

import argparse
import logging
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="holo-bench-"))


WRITE = []  # seconds spent writing the scene for Cycles, per Scene pass


def timed_pass(bpy, pipeline, scene, folder: Path) -> tuple[float, float]:
    """(the pass's seconds, of which its lighting stages')."""
    scene.holo.output_dir = str(folder) + os.sep
    WRITE.clear()
    t = time.perf_counter()
    result = pipeline.run(pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get()))
    total = time.perf_counter() - t
    return total, sum(WRITE) + (result.report.radiance_seconds or 0.0)


def timing_requests(radiance):
    request = radiance.request

    def timed(*args, **kwargs):
        t = time.perf_counter()
        try:
            return request(*args, **kwargs)
        finally:
            WRITE.append(time.perf_counter() - t)

    radiance.request = timed


def cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return f"{line.split(':', 1)[1].strip()}, {os.cpu_count()} cores"
    except OSError:
        pass
    return f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--resolution", type=int, nargs=2, default=(1280, 720), metavar=("W", "H"))
    p.add_argument("--samples", type=int, default=16)
    p.add_argument("--rounds", type=int, default=2)
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    sys.path.insert(0, str(ROOT))
    import bpy

    from holo_addon import register
    from holo_addon.demo import build_scene
    from holo_addon.export import radiance
    from holo_addon.render import pipeline

    bpy.ops.wm.read_factory_settings(use_empty=True)
    register()
    timing_requests(radiance)
    scene = build_scene(bpy, resolution=tuple(args.resolution))
    scene.holo.samples = args.samples
    out = Path(tempfile.mkdtemp(prefix="holo-bench-lighting-"))
    w, h = args.resolution
    scene.render.resolution_percentage = 25  # warm-up: kernels, programs, FFT plans
    timed_pass(bpy, pipeline, scene, out / "warm")
    scene.render.resolution_percentage = 100
    times, shares = {"ALBEDO": [], "SCENE": []}, []
    for i in range(args.rounds):
        for lighting, seen in times.items():
            scene.holo.lighting = lighting
            total, lit = timed_pass(bpy, pipeline, scene, out / f"{lighting}{i}")
            seen.append(total)
            note = ""
            if lighting == "SCENE":
                shares.append(lit / (total - lit))
                note = f" (lighting {lit:.1f} s: +{shares[-1]:.1%} on the rest of the pass)"
            print(f"round {i + 1}: Lighting {lighting.title()}: {total:.1f} s{note}", flush=True)
    albedo, lit = min(times["ALBEDO"]), min(times["SCENE"])
    print(
        f"the demo's pass at {w}x{h}, {args.samples} samples, on {cpu()}:\n"
        f"  lighting adds {min(shares):.1%}-{max(shares):.1%} to the pass (its stages against "
        f"the rest of the same pass; goal: at most 25 %)\n"
        f"  whole passes, best of {args.rounds}: Albedo {albedo:.1f} s, Scene {lit:.1f} s "
        f"({lit / albedo - 1:+.1%})"
    )
    results.write(
        "lighting",
        {
            "resolution": f"{w}x{h}",
            "samples": args.samples,
            "lighting's share of the pass, least (goal <= 0.25)": min(shares),
            "lighting's share of the pass, most": max(shares),
            "pass, Lighting: Albedo [s]": albedo,
            "pass, Lighting: Scene [s]": lit,
            "Scene / Albedo": lit / albedo,
        },
    )


if __name__ == "__main__":
    main()
