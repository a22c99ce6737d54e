"""What a phase display shows, per encoding, on the splatting protocol (facts.md section 11):
8 µm pitch, lasers at 638, 520 and 488 nm, a 1024×1536 wave computed on a grid twice as
large each way and cropped to its centre, 8-bit phase, a focal stack of 30 slices over
±5 mm about the scene's centre.

Two scenes, each scaled into the display's volume (centred 10 mm behind the display, ±5 mm)
and 85 % of its shorter side across: the demo's (``holo_core.demo.scene_emitters``: a
textured checkerboard, a vertex-coloured octahedron and three beads, 80 % of the volume
deep) and a textured tilted plane (a resolution chart from 5.5 to 14.5 mm behind the
display). Their surfaces are sampled as the eye box's centre
sees them (``holo_core.plate.emitters.surface_points``, the front layer: occlusion as seen
from the eye box), with the colour of their texture and one phase (a smooth-phase display
hologram: random phases would make the reference itself speckle), and their waves recorded
at the display (``holo_core.plate.point_sources.point_wave``, each point's cone band-limited
to the grid).

For each encoding (double-phase; gradient descent warm-started from it; Gerchberg–Saxton),
each scene: mean PSNR [dB] and SSIM over the stack's slices (the quantised pattern through
the display's half-Nyquist filter against the complex wave through the same filter,
:mod:`holo_core.phase.stack`), and seconds per colour frame (all three lasers, from the
recorded wave, the stack's simulation excluded). Then the 1080p targets: a colour frame of
double-phase, and 100 steps of gradient descent per laser, at 1920×1080 (the demo's wave
padded to it).

``--eye MM``: the stacks as an eye sees them, through a pupil MM millimetres wide at the
eye box's centre (EYE in front), focused on each slice (:class:`holo_core.phase.stack.
EyePupil`), and the points' phases such that their light reaches the pupil's centre in one
phase (one phase at the points themselves would send a tilted surface's light along its
normal, past the eye); the figures' names end in ``eye``.

    python bench/display.py [--quick] [--out DIR] [--iterations 100]
    python bench/display.py --scenes demo --skip-1080p --part /tmp/a.json   # one part ...
    python bench/display.py --merge /tmp/a.json /tmp/b.json /tmp/c.json     # ... and all

``--quick``: a 256×384 window, 10 slices, 40 steps, no 1080p timings (minutes here).
``--out DIR`` keeps each scene and encoding's patterns with their layouts and both focal
stacks (EXR, PNG sheet).
Figures go to ``bench/results/display.json`` (``display-quick.json`` with ``--quick``).
"""

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

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from holo_core.demo import scene_emitters
from holo_core.phase.display import Display
from holo_core.phase.encode import METHODS, encode
from holo_core.phase.export import export_frame
from holo_core.phase.slm import Laser, SLMSetup
from holo_core.phase.stack import EyePupil, Optics
from holo_core.plate.emitters import surface_points
from holo_core.plate.point_sources import point_wave
from holo_core.scene.mesh import Mesh

PITCH = 8e-6
WAVELENGTHS = (638e-9, 520e-9, 488e-9)
CENTRE = -10e-3  # the scene's centre, behind the display [m]
HALF_DEPTH = 5e-3  # the focal stack's half-depth [m]
EYE = 0.3  # the eye box's centre on the axis [m], where occlusion is seen from
SPOT = PITCH / 0.5  # the resolved spot through the half-Nyquist filter [m]


def fitted(meshes, width, depth):
    """``meshes`` scaled into the volume: across to ``width`` [m] (x and y alike), along the
    axis to ``depth`` [m], centred on the axis at CENTRE."""
    every = np.concatenate([m.vertices for m in meshes])
    lo, hi = every.min(0), every.max(0)
    scale = np.array([width / (hi[0] - lo[0])] * 2 + [depth / (hi[2] - lo[2])])
    shift = np.array([0.0, 0.0, CENTRE]) - (lo + hi) / 2 * scale
    return [
        Mesh(
            vertices=m.vertices * scale + shift,
            triangles=m.triangles,
            uvs=m.uvs,
            texture=m.texture,
            colours=m.colours,
        )
        for m in meshes
    ]


def demo_meshes(width):
    """The demo's scene filling 85 % of the display's width and 80 % of the volume's depth."""
    return fitted(scene_emitters(), 0.85 * width, 0.8 * 2 * HALF_DEPTH)


def chart(size=512):
    """A resolution chart: a Siemens star, bars of falling period, a grey ramp (linear)."""
    y, x = (np.mgrid[:size, :size] + 0.5) / size - 0.5
    r, a = np.hypot(x, y), np.arctan2(y, x)
    star = (np.sin(24 * a) > 0) & (r < 0.3)
    img = np.where(r < 0.3, star * 0.9 + 0.05, 0.0)
    bars = (np.sin(2 * np.pi * x * (8 + 40 * (x + 0.5))) > 0) & (np.abs(y + 0.4) < 0.07)
    img = np.where(np.abs(y + 0.4) < 0.07, bars * 0.9 + 0.05, img)
    img = np.where(np.abs(y - 0.4) < 0.06, 0.1 + 0.8 * (x + 0.5), img)
    tint = np.stack([img, img * (0.6 + 0.4 * (x + 0.5)), img * (1.0 - 0.5 * (x + 0.5))], -1)
    return np.clip(tint, 0, 1)


def chart_meshes(width, depth=9e-3):
    """The chart on a plane tilted about y, 85 % of the display's ``width`` [m] across and as
    high, its left edge nearer, spanning ``depth`` [m]."""
    width = height = 0.85 * width
    x0, x1 = -width / 2, width / 2
    z0, z1 = CENTRE + depth / 2, CENTRE - depth / 2
    v = np.array(
        [[x0, -height / 2, z0], [x1, -height / 2, z1], [x1, height / 2, z1], [x0, height / 2, z0]]
    )
    return [
        Mesh(
            vertices=v,
            triangles=np.array([[0, 1, 2], [0, 2, 3]]),
            uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]),
            texture=chart(),
        )
    ]


def scene_wave(meshes, shape, wavelengths, spacing=SPOT, at_eye=False):
    """The scene's wave at the display, per laser (complex64 (rows, cols)): its surface seen
    from the eye box's centre, recorded on twice the display's grid and cropped; ``at_eye``:
    the points' light in one phase at the eye box's centre, else at the points."""
    centre = np.array([0.0, 0.0, EYE])
    pos, colour, *_ = surface_points(meshes, centre, np.eye(3), spacing / (EYE - CENTRE), layers=1)
    big = (2 * shape[0], 2 * shape[1])
    r0, c0 = (big[0] - shape[0]) // 2, (big[1] - shape[1]) // 2
    waves = []
    for c, lam in enumerate(wavelengths):
        amp = np.sqrt(colour[:, c]).astype(np.complex64)
        if at_eye:
            reach = np.linalg.norm(pos - centre, axis=1)
            amp = amp * np.exp(-2j * np.pi / lam * np.remainder(reach, lam)).astype(np.complex64)
        u = point_wave(pos, amp, wavelength=lam, pitch=PITCH, shape=big)
        waves.append(np.asarray(u)[r0 : r0 + shape[0], c0 : c0 + shape[1]])
    return waves, len(pos)


def load():
    return [round(x, 2) for x in os.getloadavg()]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", type=Path)
    parser.add_argument("--iterations", type=int)
    parser.add_argument("--gs-iterations", type=int)
    parser.add_argument(
        "--slices-per-step",
        type=int,
        default=1,
        help="planes of the stack drawn a gradient-descent step",
    )
    parser.add_argument(
        "--clip",
        type=lambda v: v if v == "auto" else float(v),
        default="auto",
        help="clip_fraction of the double-phase (and the warm starts): a fraction or 'auto'",
    )
    parser.add_argument("--skip-1080p", action="store_true")
    parser.add_argument(
        "--eye",
        type=float,
        metavar="MM",
        help="judge through an eye's pupil MM wide at the eye box (EYE)",
    )
    parser.add_argument(
        "--hd-steps",
        type=int,
        help="gradient-descent steps run at 1080p (the rest of 100 extrapolated)",
    )
    parser.add_argument(
        "--scenes",
        nargs="*",
        default=["demo", "textured"],
        help="scenes to run (none: the 1080p timings alone)",
    )
    parser.add_argument(
        "--part", type=Path, help="write this run's figures to PART (JSON) for --merge, not results"
    )
    parser.add_argument(
        "--merge", nargs="+", type=Path, help="write the figures of these parts to bench/results"
    )
    args = parser.parse_args(argv)
    if args.merge:
        figures = {}
        for part in args.merge:
            figures.update(json.loads(part.read_text()))
        results.write("display-quick" if args.quick else "display", figures)
        return
    logging.basicConfig(level=logging.WARNING)
    shape = (256, 384) if args.quick else (1024, 1536)
    slices = 10 if args.quick else 30
    iterations = args.iterations or (40 if args.quick else 100)
    gs_iterations = args.gs_iterations or (20 if args.quick else 30)
    display = Display(name="slm-1080p-8um-window", resolution=shape[::-1], pitch=PITCH, bit_depth=8)
    setup = SLMSetup(
        display=display,
        lasers=[Laser(wavelength=w) for w in WAVELENGTHS],
        depth_range=(CENTRE - HALF_DEPTH, CENTRE + HALF_DEPTH),
        slices=slices,
        band=0.5,
    )
    settings = {
        "double-phase": {},
        "gradient-descent": {"iterations": iterations, "slices_per_step": args.slices_per_step},
        "gerchberg-saxton": {"iterations": gs_iterations},
    }
    for s in settings.values():
        s["clip_fraction"] = args.clip
    out = args.out or Path(tempfile.mkdtemp(prefix="holo-display-"))
    eye = None if args.eye is None else EyePupil(diameter=args.eye * 1e-3, distance=EYE)
    suffix = "" if eye is None else " eye"
    figures = {}
    width = min(shape) * PITCH  # the scenes fit the display's shorter side
    scenes = {"demo": demo_meshes, "textured": chart_meshes}
    waves = None
    for scene in args.scenes:
        meshes = scenes[scene](width)
        start = time.perf_counter()
        waves, count = scene_wave(meshes, shape, WAVELENGTHS, at_eye=args.eye is not None)
        print(f"{scene}: {count} points, waves recorded in {time.perf_counter() - start:.1f} s")
        for method in METHODS:
            folder = out / scene / method
            folder.mkdir(parents=True, exist_ok=True)
            frame = export_frame(
                waves,
                setup,
                folder,
                stem="frame_0001",
                distance=CENTRE,
                method=method,
                stack_compression="none",
                eye=eye,
                **settings[method],
            )
            psnr = float(np.mean([c.mean_psnr_db for c in frame.comparisons]))
            ssim = float(np.mean([c.mean_ssim for c in frame.comparisons]))
            figures[f"{scene} {method}{suffix}"] = {
                "psnr_db": round(psnr, 2),
                "ssim": round(ssim, 4),
                "seconds_per_frame": round(frame.seconds, 2),
                "psnr_db per laser": [round(c.mean_psnr_db, 2) for c in frame.comparisons],
                "worst slice psnr_db": round(min(min(c.psnr_db) for c in frame.comparisons), 2),
                "load": load(),
            }
            print(
                f"{scene} {method}: {psnr:.2f} dB, SSIM {ssim:.3f}, {frame.seconds:.1f} s a "
                f"colour frame (load {load()[0]})",
                flush=True,
            )
    if not (args.skip_1080p or args.quick):
        if waves is None:  # no scene ran: the timings do not depend on what the wave shows
            rng = np.random.default_rng(0)
            waves = [
                np.exp(1j * rng.uniform(0, 0.1, shape)).astype(np.complex64) * 0.5
                for _ in WAVELENGTHS
            ]
        figures.update(hd_times(waves, iterations=100, clip=args.clip, steps=args.hd_steps))
    figures[f"protocol{suffix}"] = (
        f"{PITCH * 1e6:g} um, {'/'.join(f'{w * 1e9:.0f}' for w in WAVELENGTHS)}"
        f" nm, {shape[1]}x{shape[0]} computed at 2x and cropped, {slices} "
        f"slices over +-{HALF_DEPTH * 1e3:g} mm, 8-bit, band 0.5; GD "
        f"{iterations} steps of {args.slices_per_step} slices, GS "
        f"{gs_iterations} plane visits, clip_fraction {args.clip}"
        + (
            ""
            if eye is None
            else f"; eye: a {args.eye:g} mm pupil "
            f"{EYE * 1e3:g} mm in front, the points in phase there"
        )
    )
    figures[f"out{suffix}"] = str(out)
    if args.part:
        args.part.write_text(json.dumps(figures, indent=1) + "\n")
        print(f"figures of this part written to {args.part}")
    else:
        results.write("display-quick" if args.quick else "display", figures)


def hd_times(waves, *, iterations, clip, steps=None):
    """Seconds for a 1080p colour frame: double-phase, and ``iterations`` steps of gradient
    descent over the 30-slice stack, one slice drawn a step (the last scene's wave, or a
    random one when no scene ran, padded to 1920×1080).
    ``steps`` < ``iterations``: only that many steps are run and the rest extrapolated (every
    step costs the same: one pattern's spectrum, one slice there and back, one gradient).
    Wall and CPU seconds (the process's, all its threads): on a machine shared with other
    jobs the CPU seconds are what the work costs."""
    shape = (1080, 1920)
    display = Display(name="slm-1080p-8um", resolution=shape[::-1], pitch=PITCH)
    distances = np.linspace(CENTRE - HALF_DEPTH, CENTRE + HALF_DEPTH, 30)
    padded = []
    for w in waves:
        u = np.zeros(shape, np.complex64)
        r, c = ((n - m) // 2 for n, m in zip(shape, w.shape))
        u[r : r + w.shape[0], c : c + w.shape[1]] = w
        padded.append(u)
    wall, cpu = time.perf_counter(), time.process_time()
    for u, lam in zip(padded, WAVELENGTHS):
        encode(u, display, wavelength=lam, method="double-phase", clip_fraction=clip)
    dp = (time.perf_counter() - wall, time.process_time() - cpu)
    steps = iterations if steps is None else min(steps, iterations)
    gd, made = np.zeros(2), np.zeros(2)
    for u, lam in zip(padded, WAVELENGTHS):
        wall, cpu = time.perf_counter(), time.process_time()
        optics = Optics(shape, pitch=PITCH, wavelength=lam, distances=distances)
        targets = optics.stack(u)  # the focal stack's targets, made once per frame
        made += (time.perf_counter() - wall, time.process_time() - cpu)
        wall, cpu = time.perf_counter(), time.process_time()
        encode(
            u,
            display,
            wavelength=lam,
            method="gradient-descent",
            optics=optics,
            targets=targets,
            iterations=steps,
            slices_per_step=1,
            clip_fraction=clip,
        )
        gd += (time.perf_counter() - wall, time.process_time() - cpu)
    gd *= iterations / steps
    print(
        f"1080p colour frame: double-phase {dp[0]:.2f} s ({dp[1]:.2f} s CPU), {iterations} "
        f"steps of gradient descent {gd[0]:.1f} s ({gd[1]:.1f} s CPU"
        f"{f', {steps} run' if steps < iterations else ''}) after {made[0]:.1f} s "
        f"({made[1]:.1f} s CPU) making the targets (load {load()[0]})"
    )
    return {
        "1080p colour frame double-phase": {
            "seconds_per_frame": round(dp[0], 2),
            "cpu_seconds": round(dp[1], 2),
            "target": 5.0,
            "load": load(),
        },
        f"1080p colour frame {iterations} steps gradient-descent": {
            "seconds_per_frame": round(float(gd[0]), 2),
            "cpu_seconds": round(float(gd[1]), 2),
            "target": 60.0,
            "load": load(),
            "slices per step": 1,
            "steps run (the rest extrapolated)": steps,
            "targets' stack [s]": round(float(made[0]), 2),
            "targets' stack cpu [s]": round(float(made[1]), 2),
        },
    }


if __name__ == "__main__":
    main()
