"""How a plate set's cost grows with its path: the bench shot's scene planned (nothing
recorded) for dollies of 0.1, 0.4, 1 and 2 m at 1280×720 and orbits of 30°, 60° and 90° at
640×360, each as the set of parts :func:`holo_core.plate.path.parts_along` places along it.

For each move it prints the parts, the samples, the disk and the planned recording, each per
metre (per 10° of orbit) of path, and what the middle frame's view reads of its part; the
ratios to the shortest move say whether the cost grows with the path's length (a ratio near
1 a metre) and whether a view's reads stay constant. A path's cost is linear when the
per-metre ratios stay within 20 % of one another (the issue's target).

    python bench/set_scaling.py [--dollies 0.1 0.4 1 2] [--orbits 30 60 90] [--stretch 0.1]
"""

import argparse
import math

import numpy as np
import results  # the bench folder's own: the figures as data
import shot  # the bench shot's scene, cameras and path

from holo_core import estimate
from holo_core.plate.path import parts_along, plan_parts
from holo_core.plate.plan import plan_view


def path_cameras(move: float, *, orbit: bool, scale: float):
    """The path's cameras 5 cm (5°) apart, and the middle frame's camera."""
    span = move / 5 if orbit else move / 0.05
    at = np.linspace(-0.5, 0.5, max(2, round(span) + 1))

    def eye(t):
        if orbit:
            a = math.radians(move * t)
            return shot.TARGET + 2 * shot.DISTANCE * np.array([math.sin(a), 0.0, math.cos(a)])
        return np.array([move * t, 0.0, shot.DISTANCE])

    return [shot.camera(0.0, scale, eye(t)) for t in at], shot.camera(0.0, scale, eye(0.0))


def planned(move: float, *, orbit: bool, scale: float, stretch: float, points) -> dict:
    """One move's set planned: its figures."""
    path, middle = path_cameras(move, orbit=orbit, scale=scale)
    parts = parts_along(
        path, [points.min(0), points.max(0)], distance=shot.DISTANCE, stretch=stretch
    )
    sp = plan_parts(parts, points, meshes=shot.scene())  # emitters from the surfaces seen
    k = min(
        range(len(parts)), key=lambda i: parts[i].reach(middle.position, middle.aperture_diameter)
    )
    local = parts[k].plate.to_plate(np.asarray(middle.position)[None])[0]
    view = plan_view(
        sp.plans[k],
        position=local,
        pixel_angle=middle.pixel_angle(),
        pupil=middle.aperture_diameter,
        resolution=middle.resolution,
    )
    return {
        "parts": len(parts),
        "path [m]": sp.length,
        "samples [Mpx]": sp.samples / 1e6,
        "disk [GiB]": sp.disk_bytes() / 2**30,
        "planned recording [s]": sp.record_seconds(),
        "estimated recording, default rates [s]": estimate.plate_set(
            sp, calibration=(estimate.DEFAULT, False), warm=True, load_average=0
        ).seconds,
        "a view reads [Mpx]": view.window / 1e6,
    }


def per_unit(rows: dict, unit: float) -> None:
    """Each row's samples, disk and recording per ``unit`` of its move, and against the
    first row's."""
    first = None
    for label, r in rows.items():
        move = r.pop("_move")
        each = {
            k: r[k] / (move / unit)
            for k in ("samples [Mpx]", "disk [GiB]", "planned recording [s]")
        }
        first = first or each
        ratios = {f"{k.split(' [')[0]} per unit / the shortest's": each[k] / first[k] for k in each}
        r.update(ratios)
        print(
            f"{label}: {r['parts']} parts, {r['samples [Mpx]']:.1f} Mpx, "
            f"{r['disk [GiB]']:.2f} GiB, recording about "
            f"{r['estimated recording, default rates [s]']:.0f} s (its zone sums "
            f"{r['planned recording [s]']:.0f} s), "
            f"a view reads {r['a view reads [Mpx]']:.1f} Mpx; per unit against the "
            f"shortest: " + ", ".join(f"{k.split(' per')[0]} {v:.2f}" for k, v in ratios.items())
        )


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "--dollies",
        type=float,
        nargs="*",
        default=[0.1, 0.4, 1.0, 2.0],
        help="dolly lengths [m] at 1280x720",
    )
    p.add_argument(
        "--orbits",
        type=float,
        nargs="*",
        default=[30.0, 60.0, 90.0],
        help="orbit angles [°] at 640x360",
    )
    p.add_argument("--stretch", type=float, default=0.1, help="[m] of path a part serves")
    args = p.parse_args()
    points = np.concatenate([m.vertices for m in shot.scene()])
    dollies = {
        f"{d * 100:g} cm dolly, 1280x720": dict(
            planned(d, orbit=False, scale=1.0, stretch=args.stretch, points=points), _move=d
        )
        for d in args.dollies
    }
    orbits = {
        f"{a:g}° orbit, 640x360": dict(
            planned(a, orbit=True, scale=0.5, stretch=args.stretch, points=points), _move=a
        )
        for a in args.orbits
    }
    per_unit(dollies, 1.0)
    per_unit(orbits, 10.0)
    results.write("set_scaling", {**dollies, **orbits})


if __name__ == "__main__":
    main()
