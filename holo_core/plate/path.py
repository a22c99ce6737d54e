"""Parts of a plate along a camera path: for a move wider than one plate serves well (a long
dolly, an orbit), a set of plates, each facing its stretch of the path with that stretch's
viewing zone, carrier and band.

One flat plate's recording grows as the square of its zone's width (a wider zone asks a finer
pitch, and each emitter's light reaches more of the plate), and beyond about ±45° from its
normal it sees the objects edge-on. Parts of a fixed stretch ``w`` of path each cost ∝ w², so
a path of length L costs ∝ L·w: linear in the path's length, and a view reads one part.
Consecutive stretches overlap by at least a pupil, so every pupil of the path lies wholly
inside one part's zone (each zone holds a pupil at every point of its stretch, and a margin).

Each part's plate lies at ``distance`` [m] from the objects' centre towards its stretch (its
local +Z at the stretch's middle, +Y the cameras' mean up), cut to the window through which
the objects' light reaches its zone.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np

from .. import validate
from ..memory import gib
from ..scene.camera import Camera
from ..scene.mesh import Mesh, outward
from ..scene.plate import SHOT_ZONE_MARGIN, Plate, ViewingZone, box_corners
from ..scene.plate_set import PathPart, PlateSet, reach_beyond
from ..validate import InputError, shown
from .plan import CHANNELS, LOOKS, plan
from .zone_light import seen_area

DEFAULT_STRETCH = 0.1  # [m] of path a part holds (the 10 cm dolly one plate serves well)
WINDOW_PAD = 0.02  # fraction of the window added on each side of a part's plate
LATTICE_TURN = math.radians(5)  # [rad] of the path's turn about the objects a lattice serves


def parts_along(
    cameras,
    bounds,
    *,
    distance: float,
    stretch: float = DEFAULT_STRETCH,
    margin: float = SHOT_ZONE_MARGIN,
) -> tuple[PathPart, ...]:
    """Plan the parts of a plate serving ``cameras`` (one a frame, in order along the path).

    Parameters
    ----------
    cameras : sequence of Camera
        The shot's cameras over its frames (positions, rotations, lens and pupil).
    bounds : (2, 3) [m]
        The objects' box in the world (min and max corners).
    distance : float
        [m] from the objects' centre to each part's plate, along the line to its stretch's
        middle; the plate must lie between every object and every camera it serves.
    stretch : float
        [m] of path length a part's zone is fitted to at most; parts overlap by a pupil D, so
        a path of length L takes n = ⌈(L − D)/(stretch − D)⌉ parts, each then shortened to
        (L − D)/n + D so that they tile the path evenly (a part's recording grows as its
        zone's width squared: a 0.4 m path's five parts of 10 cm would cost a quarter more per
        metre than one part's 10 cm).
    margin : float
        [m] each zone reaches beyond its pupils (the frames' own positions need none; each
        millimetre widens the zone, whose recording grows as its width squared).

    Returns
    -------
    tuple of PathPart
        Each part's plate (its pose and size [m], and the zone it is recorded for), the
        stretch of path [m] it serves and its frames.

    Raises
    ------
    InputError
        Where a camera lies inside the objects' box, or at or behind its part's plate (naming
        its frame), or a length is out of range.

    Notes
    -----
    Every part shares the views' pupil (the largest aperture of the path) and pixel angle (the
    finest), so that their emitters' spacing is one.

    Examples
    --------
    Two frames 2 cm apart, served by one part 10 cm from the objects:

    >>> import numpy as np
    >>> from holo_core import Camera, Mesh, look_at, parts_along, record_set
    >>> cameras = [Camera(matrix_world=look_at((x, -0.5, 0.0), (0, 0, 0)), resolution=(32, 24),
    ...                   fstop=8.0, focus_distance=0.5) for x in (-0.01, 0.01)]
    >>> bounds = np.array([[-0.01, -0.01, -0.01], [0.01, 0.01, 0.01]])
    >>> parts = parts_along(cameras, bounds, distance=0.1)
    >>> len(parts), parts[0].frames, round(parts[0].plate.zone.centre[2], 3)
    (1, (0, 1), 0.4)
    """
    cams = list(cameras) if not isinstance(cameras, Camera) else [cameras]
    if not cams or not all(isinstance(c, Camera) for c in cams):
        raise InputError("cameras must be a non-empty sequence of Camera (one a frame)")
    box = validate.array("bounds", bounds, "(2, 3) min and max corners [m]")
    if box.shape != (2, 3) or not np.isfinite(box).all() or (box[1] < box[0]).any():
        raise InputError(
            f"bounds must be (2, 3) finite min and max corners [m]; got "
            f"{np.asarray(bounds).tolist()}"[:300]
        )
    distance = validate.positive("distance", distance, "m")
    margin = validate.finite("margin", margin, "m")
    if margin < 0:
        raise InputError(f"margin must be >= 0 [m]; got {shown(margin)}")
    pupil = max(c.aperture_diameter or 0.0 for c in cams)
    pixel = min(c.pixel_angle() for c in cams)
    stretch = validate.positive("stretch", stretch, "m")
    if stretch <= pupil:
        raise InputError(
            f"stretch must exceed the pupil ({pupil:.4g} m), which consecutive "
            f"parts overlap by; got {shown(stretch)} m"
        )
    positions = np.array([c.position for c in cams])
    for f, p in enumerate(positions):
        if ((p >= box[0]) & (p <= box[1])).all():
            raise InputError(
                f"frame {f}: the camera at ({p[0]:.4g}, {p[1]:.4g}, {p[2]:.4g}) m "
                f"lies inside the objects' box {box.tolist()}: a plate can only "
                f"be looked at from outside the objects"
            )
    for f, (p, q) in enumerate(itertools.pairwise(positions)):
        if _crosses(p, q, box):
            raise InputError(
                f"frame {f}: the path from its camera to frame {f + 1}'s passes "
                f"through the objects' box {box.tolist()}: a plate can only be "
                f"looked at from outside the objects"
            )
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(positions, axis=0), axis=1))]
    length = float(s[-1])
    count = 1 if length <= stretch else math.ceil((length - pupil) / (stretch - pupil))
    if count > 1:  # the parts shortened to tile the path, consecutive ones a pupil in common
        stretch = (length - pupil) / count + pupil
    starts = np.linspace(0.0, max(length - stretch, 0.0), count)
    centre = box.mean(0)
    parts = []
    for k, a in enumerate(starts):
        span = (float(a), float(min(a + stretch, length)))
        path = _path_between(positions, s, *span, step=max(pupil, margin, 1e-3) / 2)
        inside = [f for f, sf in enumerate(s) if span[0] <= sf <= span[1]] or [
            min(int(np.searchsorted(s, span[0])), len(s) - 1)
        ]
        up = np.mean([cams[f].matrix_world[:3, 1] for f in inside], 0)
        plate = _facing(
            path, {f: positions[f] for f in inside}, up, box, centre, distance, pupil, margin, pixel
        )
        held = [f for f, p in enumerate(positions) if reach_beyond(plate, p, pupil) <= 1e-9]
        parts.append(PathPart(plate=plate, stretch=span, frames=tuple(held)))
    for f, p in enumerate(positions):
        if not any(f in part.frames for part in parts):  # the stretches' overlap prevents it
            raise InputError(
                f"frame {f}: no part's zone holds the camera's pupil at "
                f"({p[0]:.4g}, {p[1]:.4g}, {p[2]:.4g}) m"
            )
    return tuple(parts)


def _crosses(p, q, box) -> bool:
    """Whether the segment from ``p`` to ``q`` (3,) [m] meets the box ``box`` (2, 3) [m]
    (slabs)."""
    d = q - p
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = (box[0] - p) / d, (box[1] - p) / d
    lo = np.where(
        d == 0, np.where((p >= box[0]) & (p <= box[1]), -np.inf, np.inf), np.minimum(t0, t1)
    )
    hi = np.where(
        d == 0, np.where((p >= box[0]) & (p <= box[1]), np.inf, -np.inf), np.maximum(t0, t1)
    )
    return bool(max(lo.max(), 0.0) <= min(hi.min(), 1.0))


def _path_between(positions, s, s0, s1, step) -> np.ndarray:
    """The path's points (N, 3) [m] from length ``s0`` to ``s1`` [m], linear between the
    frames and at most ``step`` [m] apart."""
    n = max(2, math.ceil((s1 - s0) / step) + 1)
    at = np.linspace(s0, s1, n)
    if len(positions) == 1:
        return positions[:1]
    return np.stack([np.interp(at, s, positions[:, i]) for i in range(3)], 1)


def _facing(path, frames: dict, up, box, centre, distance, pupil, margin, pixel) -> Plate:
    """The plate of a part: ``distance`` [m] from ``centre`` towards the middle of ``path``
    (N, 3) [m], +Y along ``up``, cut to the window the objects' light to its zone crosses;
    ``frames`` (index: world position [m]) the frames on its stretch, named where refused."""
    z = path.mean(0) - centre
    if np.linalg.norm(z) < 1e-9:
        raise InputError(
            f"frame {min(frames)}: the path's stretch there is centred on the "
            f"objects' centre; no plate can face it"
        )
    z = z / np.linalg.norm(z)
    x = np.cross(up, z)
    if np.linalg.norm(x) < 1e-6:  # the cameras' up along the plate's normal
        x = np.cross((1.0, 0.0, 0.0) if abs(z[0]) < 0.9 else (0.0, 1.0, 0.0), z)
    x = x / np.linalg.norm(x)
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, :3] = np.stack([x, y, z], 1)
    pose[:3, 3] = centre + distance * z
    plate = Plate(matrix_world=pose, width=1.0, height=1.0)
    objects = plate.to_plate(box_corners(box))
    if objects[:, 2].max() >= 0:
        raise InputError(
            f"frames {min(frames)}-{max(frames)}: a plate {distance:.4g} m from "
            f"the objects' centre facing them cuts the objects (they reach z = "
            f"{objects[:, 2].max():.4g} m in its frame); place it farther from "
            f"them"
        )
    for f, p in frames.items():
        z_f = plate.to_plate(p[None])[0, 2]
        if z_f <= 0:
            raise InputError(
                f"frame {f}: the camera is {-z_f:.4g} m behind its part's plate "
                f"(the plates lie {distance:.4g} m from the objects' centre); "
                f"the path passes behind a part there: place the plates nearer "
                f"the objects"
            )
    local = plate.to_plate(path)
    if (local[:, 2] <= 0).any():  # between frames: named by the frame before
        raise InputError(
            f"frame {min(frames)}: the path after it passes behind its part's "
            f"plate (z = {local[:, 2].min():.4g} m in the plate's frame)"
        )
    zone = ViewingZone.fit(local, pupil=pupil, margin=margin, pixel=pixel)
    # the window through which the objects' light reaches the zone
    b, q = objects[:, None, :], zone.corners()[None, :, :]
    hit = b + (-b[..., 2:] / (q[..., 2:] - b[..., 2:])) * (q - b)
    lo, hi = hit[..., :2].reshape(-1, 2).min(0), hit[..., :2].reshape(-1, 2).max(0)
    pad = WINDOW_PAD * (hi - lo)
    lo, hi = lo - pad, hi + pad
    mid = (lo + hi) / 2
    pose[:3, 3] += x * mid[0] + y * mid[1]
    shifted = np.asarray(zone.centre) - (mid[0], mid[1], 0.0)
    zone = ViewingZone(
        centre=tuple(shifted), half_extents=zone.half_extents, pupil=pupil, pixel=pixel
    )
    return Plate(
        matrix_world=pose, width=float(hi[0] - lo[0]), height=float(hi[1] - lo[1]), zone=zone
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class SetPlan:
    """The plans of a set's parts (``plans``, a :class:`holo_core.plate.plan.PlatePlan` a
    part, each of ``looks`` looks) along a path of ``length`` [m], its emitters found from
    ``lattices`` of its parts' zones (:func:`lattice_parts`): what the set holds and costs,
    before any emitter is found."""

    plans: tuple
    length: float
    lattices: int = 1

    @property
    def samples(self) -> int:
        return sum(p.samples for p in self.plans)

    def disk_bytes(self, channels=CHANNELS) -> float:
        """Bytes of every part's looks on disk."""
        return sum(p.disk_bytes(channels) for p in self.plans)

    def memory_bytes(self, channels=CHANNELS) -> float:
        """Host bytes while recording: one part at a time, every look."""
        return max(p.memory_bytes(channels * p.looks) for p in self.plans)

    def record_seconds(self, channels=CHANNELS) -> float:
        """Seconds of every part's zone sum at the development machine's idle rate (the
        emitters' search and visibility, the files and this machine's speed not counted;
        ``bench/results/shot_set_*.json`` holds what whole recordings took)."""
        return sum(p.record_seconds(channels) for p in self.plans)

    def describe(self, estimate=None) -> str:
        """The set in plain words: parts, samples, disk, memory, what a view reads, and its
        recording's time: ``estimate``'s (an :class:`holo_core.estimate.Estimate`, this
        machine's: :func:`holo_core.estimate.plate_set`), else the zone sums' at the
        development machine's rate."""
        widest = max(self.plans, key=lambda p: p.samples)
        time = (
            f"records in {estimate.words()}"
            if estimate is not None
            else (
                f"its zone sums about {self.record_seconds():.0f} s at the development machine's "
                f"rate (the emitters, the files and this machine's speed not counted)"
            )
        )
        return (
            f"{len(self.plans)} part(s) along {self.length:.3g} m of path, "
            f"{self.samples / 1e6:.3g} Mpx in all (the largest {widest.shape[1]} x "
            f"{widest.shape[0]}), {self.plans[0].looks} look(s): "
            f"{gib(self.disk_bytes())} on disk, {gib(self.memory_bytes())} of memory "
            f"while recording (a part at a time); {time}; a view reads one part"
        )


def plan_parts(parts, points, *, looks: int = LOOKS, meshes=None) -> SetPlan:
    """The :class:`SetPlan` of ``parts`` (:func:`parts_along`) for objects at ``points``
    (N, 3) [m] (the world: their vertices, or their box's corners), ``looks`` looks a part
    (pure arithmetic, as :func:`holo_core.plate.plan.plan`); ``meshes`` (the world), where
    known, count each part's emitters from the surfaces its zone sees, else its box does
    (:func:`holo_core.plate.zone_light.seen_area`)."""
    parts = tuple(parts)
    if not parts or not all(isinstance(p, PathPart) for p in parts):
        raise InputError("parts must be a non-empty sequence of PathPart (parts_along)")
    world = validate.array("points", points, "(N, 3) object points [m]")
    if world.ndim != 2 or world.shape[1] != 3 or not len(world):
        raise InputError(f"points must be (N, 3) object points [m]; got shape {world.shape}")
    shapes = None if meshes is None else [meshes] if isinstance(meshes, Mesh) else list(meshes)
    sides = None if shapes is None else [outward(m) for m in shapes]  # in every part's frame
    plans = []
    for part in parts:
        local = part.plate.to_plate(world)
        zone = part.plate.zone
        seen = (
            None
            if shapes is None
            else seen_area(
                [replace(m, vertices=part.plate.to_plate(m.vertices)) for m in shapes],
                zone.centre,
                sides,
            )
        )
        plans.append(
            plan(
                (part.plate.width, part.plate.height),
                np.array([local.min(0), local.max(0)]),
                zone=zone,
                pixel_angle=zone.pixel,
                looks=looks,
                seen=seen,
                triangles=0 if shapes is None else sum(len(m.triangles) for m in shapes),
            )
        )
    centres = [
        part.plate.matrix_world[:3, :3] @ np.asarray(part.plate.zone.centre)
        + part.plate.matrix_world[:3, 3]
        for part in parts
    ]
    return SetPlan(
        plans=tuple(plans),
        length=float(parts[-1].stretch[1] - parts[0].stretch[0]),
        lattices=len(lattice_parts(centres, world.mean(0))),
    )


def lattice_parts(centres, target, turn: float = LATTICE_TURN) -> list[int]:
    """The parts whose zone centres cast the set's lattices of emitters: the path's parts
    (``centres`` (P, 3) [m], in order) cut into runs that turn at most ``turn`` [rad] about
    ``target`` (3,) [m] (the objects' middle), the middle part of each run. A lattice serves
    every part of its run, weighted for each (:func:`holo_core.plate.parts.set_emitters`); a
    lattice a part would leave a seam between lattices across the surfaces wherever two
    parts meet (the silhouettes' IoU falls), and too few serve the ends of their runs from far off (at runs
    of 15° an orbit's end frame is about 1 dB below its middle, at 5° level with it: docs,
    Performance)."""
    d = np.asarray(centres, np.float64) - np.asarray(target, np.float64)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    runs, start = [], 0
    for k in range(1, len(d)):
        if math.acos(min(1.0, float(d[start] @ d[k]))) > turn:
            runs.append((start, k - 1))
            start = k
    runs.append((start, len(d) - 1))
    return [(a + b) // 2 for a, b in runs]


def part_for(plates: PlateSet, camera: Camera) -> tuple[int, float]:
    """(the part whose zone holds ``camera``'s pupil with the most room, 0) or, where none
    holds it, (the nearest part, how far [m] the pupil reaches beyond its zone)."""
    pupil = camera.aperture_diameter or 0.0
    reach = [part.reach(camera.position, pupil) for part in plates.parts]
    inside = [k for k, r in enumerate(reach) if r <= 1e-9]
    if not inside:
        k = int(np.argmin(reach))
        return k, reach[k]
    return max(inside, key=lambda k: _room(plates.parts[k], camera.position, pupil)), 0.0


def _room(part: PathPart, position, pupil) -> float:
    """How far [m] the pupil's edge lies inside the part's zone, across the plate."""
    z = part.plate.zone
    local = part.plate.to_plate(np.asarray(position, np.float64)[None])[0]
    return float(
        (np.asarray(z.half_extents[:2]) - np.abs(local[:2] - z.centre[:2])).min() - pupil / 2
    )
