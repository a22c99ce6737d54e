"""The looks and the supersampling a plate's views need to reach a quality target, predicted
before any recording. Pure arithmetic: Blender's process calls it beside the plan.

A view's error against the camera hologram of the same camera (the looks' limit) has two
parts, measured apart by ``bench/closeup.py`` (two seeds' looks: what changes with the seed
and what does not):

- the speckle the looks leave. Its relative variance on a uniform surface, (σ/⟨I⟩)², is
  :func:`holo_core.optics.speckle.uniform_surface_variance` of the view's defocus blur, the
  looks and the supersampling (tabled in ``SPECKLE_DB``): coded looks cancel the cross terms
  between neighbouring emitters, which a sharp spot mixes, and leave those between emitters
  further apart, which a defocused spot mixes too; fine pixels average more of the grains.
  A view focused on its objects' front has their back blurred by D·|1/z − 1/f| over the
  pixel angle: the close-up (bench/closeup.py: a 3.6 cm cube at 0.6 m, 50 mm f/2.8,
  640×360) up to 4.4 px, the shot (bench/shot.py at 640×360) 1 px;
- what no seed changes: the edges of colours and silhouettes, where the plate's emitters
  (one a resolved spot seen from the zone's centre) and the camera hologram's (one a fine
  pixel of its own view) put each edge at a different place within half a pixel. Its mean
  square falls as the edges' share of the objects' pixels: as one over the objects' size in
  pixels.

Both parts' mean squares, over the peak's square, fall as one over the objects' size in
pixels (the speckle's too: half and more of it lies within 2 px of an edge, where a spot
sees fewer of a surface's emitters), so the prediction is

    PSNR = 10·log10(size / (EDGE_ERROR + SPECKLE_SCALE · (σ/⟨I⟩)²))

with (σ/⟨I⟩)² the table's mean over the objects' depths for a view focused on their front.
The two constants are fitted by bench/quality_fit.py to the close-up at 320×180 and the shot
at 640×360 (both measured by bench/closeup.py, two seeds); the close-up at 640×360, not
fitted, is then predicted within 1.5 dB of each measured setting, mostly low (docs: Plates
and shots).

Auto's looks (:func:`choose`) fit the Memory and Disk Budgets as the recording checks them
(:func:`looks_within`), and go beyond the coded pair only where each further count gains
at least GAIN_PER_DOUBLING (1 dB) per doubling of the looks (:func:`looks_ceiling`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .. import memory as memory_mod
from .. import validate
from ..scene.plate import box_corners
from .plan import (
    CHANNELS,
    FINE_PIXEL_SECONDS,
    FURTHER_CODED,
    PAIRS_PER_SECOND,
    VIEW_SAMPLE_SECONDS,
    PlatePlan,
)

TARGET_DB = 30.0  # PSNR inside the objects against the camera hologram, the default goal
LOOK_CHOICES = (2, 4, 9)  # coded looks (the checkerboard pair, m² of m = 2, 3)
SUPERSAMPLE_CHOICES = (2, 3, 4)  # fine pixels a pixel of the views (at most the Nyquist 4)
FRAMES = 24  # a shot's frames, over which the recording's time is shared
# [dB] the least a further look count must gain per doubling of the looks for Auto to take it: its
# disk and memory grow as the looks
GAIN_PER_DOUBLING = 1.0
# (σ/⟨I⟩)² [dB] of a uniform surface's pixels (uniform_surface_variance, 24 px, 2 draws) by
# (blur [px], looks, supersample)
# fmt: off
SPECKLE_DB = {
    (0, 2, 2): -15.47, (0, 2, 3): -16.82, (0, 2, 4): -17.04,
    (1, 2, 2): -13.36, (1, 2, 3): -14.54, (1, 2, 4): -14.78,
    (2, 2, 2): -10.91, (2, 2, 3): -11.98, (2, 2, 4): -12.22,
    (3, 2, 2): -9.67, (3, 2, 3): -10.67, (3, 2, 4): -10.9,
    (4.5, 2, 2): -9.06, (4.5, 2, 3): -10.04, (4.5, 2, 4): -10.25,
    (0, 4, 2): -18.35, (0, 4, 3): -19.57, (0, 4, 4): -19.78,
    (1, 4, 2): -17.76, (1, 4, 3): -19.21, (1, 4, 4): -19.48,
    (2, 4, 2): -15.77, (2, 4, 3): -17.3, (2, 4, 4): -17.63,
    (3, 4, 2): -13.73, (3, 4, 3): -15.03, (3, 4, 4): -15.32,
    (4.5, 4, 2): -12.33, (4.5, 4, 3): -13.42, (4.5, 4, 4): -13.67,
    (0, 9, 2): -22.8, (0, 9, 3): -24.69, (0, 9, 4): -25.03,
    (1, 9, 2): -22.53, (1, 9, 3): -24.41, (1, 9, 4): -24.73,
    (2, 9, 2): -21.94, (2, 9, 3): -24.07, (2, 9, 4): -24.45,
    (3, 9, 2): -20.41, (3, 9, 3): -22.57, (3, 9, 4): -23.02,
    (4.5, 9, 2): -17.51, (4.5, 9, 3): -18.98, (4.5, 9, 4): -19.32,
}
# fmt: on
SPECKLE_SCALE = 1.86  # the speckle's mean square over (σ/⟨I⟩)² times the objects' size [px]
EDGE_ERROR = 0.082  # [px] the seed-free mean square (of the peak's) times the objects' size


@dataclass(frozen=True, slots=True, kw_only=True)
class Option:
    """One setting of a plate's views and what it is predicted to give.

    looks : coded looks; supersample : fine pixels a pixel
    psnr : the predicted PSNR [dB] inside the objects against the camera hologram
    seconds : the recording's time shared over ``FRAMES`` frames plus a view's [s]
    """

    looks: int
    supersample: int
    psnr: float
    seconds: float


@dataclass(frozen=True, slots=True, kw_only=True)
class QualityChoice:
    """The looks and supersampling chosen for a plate's views (:func:`choose`).

    looks, supersample : what the views use (the user's where they set them, else the plan's)
    psnr : their predicted PSNR [dB]; target : the goal [dB]
    planned : the plan's own choice (an :class:`Option`), the cheapest that reaches the
        target, or the best where none does
    blur : the largest defocus blur [px] of a view focused anywhere on the objects
    size : the objects' size [px] in the reference view
    user_looks, user_supersample : what the user set (0: Auto)
    budget : what held Auto's looks down ("the Disk Budget of 8 GiB"), or "" where nothing
        did; unbudgeted : Auto's choice without the budgets (None where they took nothing)
    """

    looks: int
    supersample: int
    psnr: float
    target: float
    planned: Option
    blur: float
    size: float
    user_looks: int = 0
    user_supersample: int = 0
    budget: str = ""
    unbudgeted: Option | None = None

    @property
    def loss(self) -> float:
        """[dB] the user's settings lose against the plan's choice (0 where they lose
        nothing)."""
        return max(0.0, self.planned.psnr - self.psnr)

    def describe(self) -> str:
        """What was chosen and why, in plain words."""
        why = (
            f"the objects' back lies up to {self.blur:.2g} px out of focus when the front "
            f"is sharp, and a defocused spot mixes emitters that coded looks do not "
            f"cancel"
            if self.blur >= 1
            else f"the objects lie within {self.blur:.2g} px of focus, where coded looks cancel "
            f"most of the speckle"
        )
        p = self.planned
        reach = (
            f"predicted {p.psnr:.1f} dB against the camera hologram (the target {self.target:g} dB)"
            if p.psnr >= self.target
            else f"predicted {p.psnr:.1f} dB, short of the target {self.target:g} dB: "
            f"{self.budget} holds no more looks"
            if self.budget
            else f"predicted {p.psnr:.1f} dB, short of the target {self.target:g} dB: the "
            f"edges of colours and silhouettes ({self.size:.0f} px objects) limit it "
            f"whatever the looks; more pixels or Camera mode reach it"
        )
        return f"{p.looks} looks, supersample {p.supersample}: {reach}; {why}"

    def capped(self) -> str:
        """What the budgets held Auto's looks to, in plain words ("" where they did not)."""
        u = self.unbudgeted
        if not self.budget or u is None:
            return ""
        return (
            f"Auto chose {self.planned.looks} looks, the most {self.budget} holds; "
            f"{u.looks} would reach {u.psnr:.1f} dB"
        )

    def warning(self) -> str | None:
        """What the user's Iterations or Supersample lose, or None."""
        if self.loss < 0.05:
            return None
        mine = [
            f"{name} {value}"
            for name, value, auto in (
                ("Iterations", self.looks, self.user_looks),
                ("Supersample", self.supersample, self.user_supersample),
            )
            if auto
        ]
        return (
            f"{' and '.join(mine)} (set by hand) predict {self.psnr:.1f} dB against the "
            f"camera hologram, {self.loss:.1f} dB less than Auto's {self.planned.looks} "
            f"looks at supersample {self.planned.supersample} ({self.planned.psnr:.1f} dB): "
            f"expect visible grain; set them to 0 (Auto) for the plan's choice"
        )


def speckle_variance(blur, looks: int, supersample: int) -> np.ndarray:
    """(σ/⟨I⟩)² of a uniform surface's pixels at defocus blurs ``blur`` [px] (linear between
    the table's blurs, the last held beyond), for ``looks`` coded looks (independent looks:
    a coded count's table scaled by the counts' ratio) and ``supersample`` (the nearest
    tabled)."""
    blurs = sorted({b for b, _, _ in SPECKLE_DB})
    coded = max(n for n in LOOK_CHOICES if n <= max(looks, 2))
    s = min(SUPERSAMPLE_CHOICES, key=lambda c: abs(c - supersample))
    table = np.array([SPECKLE_DB[b, coded, s] for b in blurs])
    db = np.interp(np.asarray(blur, np.float64), blurs, table)
    return 10 ** (db / 10) * coded / looks


def predicted_psnr(looks: int, supersample: int, *, blurs, size: float) -> float:
    """The predicted PSNR [dB] inside the objects (module docstring) of views with ``looks``
    and ``supersample`` whose surfaces lie at the defocus blurs ``blurs`` [px] (each as much
    of the objects), the objects ``size`` [px] across."""
    speckle = float(np.mean(speckle_variance(blurs, looks, supersample)))
    return 10 * math.log10(size / (EDGE_ERROR + SPECKLE_SCALE * speckle))


def view_blurs(
    bounds, eye, *, pupil: float, pixel_angle: float, focus: float | None = None, count: int = 9
) -> np.ndarray:
    """Defocus blurs [px] over the objects' depths for a view from ``eye`` (3,) [m] through
    a pupil of ``pupil`` [m] with pixels of ``pixel_angle`` [rad], focused at ``focus`` [m]
    (None: the objects' front, the worst a view focused on them meets), at ``count`` depths
    evenly in 1/z over the box ``bounds`` (2, 3) [m]: D·|1/z − 1/f| / Δ."""
    depth = np.linalg.norm(box_corners(np.asarray(bounds, np.float64)) - np.asarray(eye), axis=1)
    near, far = float(depth.min()), float(depth.max())
    f = near if focus is None else float(focus)
    inverse = np.linspace(1 / far, 1 / near, count)
    return pupil * np.abs(inverse - 1 / f) / pixel_angle


def reference_view(p: PlatePlan, focus: float | None = None) -> tuple[np.ndarray, float]:
    """(the defocus blurs [px] over the objects' depths, the objects' size [px]) of the plan's
    reference view: from the zone's centre through its pupil, with the pixels λ = D·Δ/2 asks
    (:func:`view_blurs`, ``focus`` [m] as there; :func:`objects_size`)."""
    eye = np.asarray(p.zone.centre, np.float64)
    pixel = 2 * p.wavelength / p.pupil
    return (
        view_blurs(p.bounds, eye, pupil=p.pupil, pixel_angle=pixel, focus=focus),
        objects_size(p.bounds, eye, pixel),
    )


def objects_size(bounds, eye, pixel_angle: float) -> float:
    """The objects' size [px]: the square root of the angular area their box spans from
    ``eye`` over the pixel's."""
    v = box_corners(np.asarray(bounds, np.float64)) - np.asarray(eye)
    t = v[:, :2] / np.abs(v[:, 2:3])
    return float(math.sqrt(np.prod(t.max(0) - t.min(0))) / pixel_angle)


def options(p: PlatePlan, *, blurs, size: float, resolution) -> list[Option]:
    """Every tabled setting's prediction for the plan ``p`` and a view of ``resolution``
    (W, H): its PSNR and its time (the recording shared over ``FRAMES`` frames, and a view)."""
    w, h = resolution
    out = []
    for n in LOOK_CHOICES:
        record = p.emitters * p.footprint * (1 + FURTHER_CODED * (n - 1)) / PAIRS_PER_SECOND
        for s in SUPERSAMPLE_CHOICES:
            view = n * (
                CHANNELS * p.samples / 2 * VIEW_SAMPLE_SECONDS + w * h * s * s * FINE_PIXEL_SECONDS
            )
            out.append(
                Option(
                    looks=n,
                    supersample=s,
                    seconds=record / FRAMES + view,
                    psnr=predicted_psnr(n, s, blurs=blurs, size=size),
                )
            )
    return out


def looks_within(plans, budget=(None, None)) -> tuple[int, str]:
    """(the most tabled looks whose recording fits ``budget`` (memory, disk) [bytes], None: no
    limit; what refuses the next count, "" where none does), checked as the recording checks
    it (:meth:`~holo_core.plate.plan.PlatePlan.check_budget`): one plan tile by tile where its
    looks exceed the memory in one piece (:func:`holo_core.runner.plate_plan`); a set's
    ``plans`` each in one piece, their disk summed (:mod:`holo_core.plate.parts`). Where not
    even the coded pair fits, the pair (its recording refuses with its own message)."""
    plans = list(plans)
    memory, disk = budget
    most, refused = LOOK_CHOICES[0], ""
    for n in LOOK_CHOICES:
        looked = [replace(p, looks=n) for p in plans]
        if len(looked) == 1:
            q = looked[0]
            tiled = q.needs_tiles(memory_mod.host_share(memory))
            stored, held = q.disk_bytes(tiled=tiled), [q.memory_bytes(CHANNELS * n, tiled=tiled)]
        else:
            stored = sum(q.disk_bytes() for q in looked)
            held = [q.memory_bytes(CHANNELS * n) for q in looked]
        if disk is not None and stored > disk:
            refused = f"the Disk Budget of {memory_mod.gib(disk)}"
        elif memory is not None and max(held) > memory:
            refused = f"the Memory Budget of {memory_mod.gib(memory)}"
        else:
            most = n
            continue
        break
    return most, refused


def looks_ceiling(every: list[Option]) -> int:
    """The most looks Auto takes: from the coded pair up, each further tabled count only
    where its best PSNR over the supersamplings gains at least GAIN_PER_DOUBLING [dB] per
    doubling of the looks over the count below. Tiny views (a 32x24 test camera, a preview)
    are limited by their objects' few pixels, not by the speckle, and stay at the pair."""
    best = {n: max(o.psnr for o in every if o.looks == n) for n in LOOK_CHOICES}
    ceiling = LOOK_CHOICES[0]
    for n in LOOK_CHOICES[1:]:
        if best[n] - best[ceiling] < GAIN_PER_DOUBLING * math.log2(n / ceiling):
            break
        ceiling = n
    return ceiling


def choose(
    p: PlatePlan,
    *,
    resolution,
    looks: int = 0,
    supersample: int = 0,
    target: float = TARGET_DB,
    focus: float | None = None,
    budget=(None, None),
    plans=None,
) -> QualityChoice:
    """The looks and supersampling for views of the plate planned as ``p`` (its reference
    view: the zone's pupil and pixel from the zone's centre) at ``resolution`` (W, H): the
    fewest looks predicted to reach ``target`` [dB] and MODEL_MARGIN above it with some
    supersampling, else the fewest within NEAR_BEST of the best, whatever the resolution
    (they are recorded once for every view); the supersampling the cheapest for those looks
    at ``resolution`` that reaches it, else the best; ``looks`` or ``supersample`` > 0 are
    the user's and are kept (0: Auto).
    ``focus`` [m] from the zone's centre (None: the objects' front, the worst a view focused
    on them meets).

    Auto's looks are at most

    - the most whose recording fits ``budget`` (memory, disk) [bytes] (None: no limit), as
      the recording checks it (:func:`looks_within`; ``plans``: a set's parts sharing it,
      default ``[p]``): the choice then says which budget held it and what the looks it
      left out would reach (:meth:`QualityChoice.capped`);
    - :func:`looks_ceiling`: a further count only where it gains at least
      GAIN_PER_DOUBLING (1 dB) per doubling of the looks, so views too small for the speckle
      to matter stay at the coded pair.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.plate.plan import plan
    >>> from holo_core.plate.quality import choose
    >>> from holo_core.scene.plate import ViewingZone
    >>> zone = ViewingZone(centre=(0, 0, 1.75), half_extents=(0.06, 0.02, 0.01),
    ...                    pupil=0.0143, pixel=0.0014)
    >>> p = plan((1, 1), [[-0.4, -0.4, -2.3], [0.5, 0.4, -1.2]], zone=zone,
    ...          pixel_angle=0.0014)
    >>> c = choose(p, resolution=(640, 360), budget=(8 * 2**30, 100 * 2**30))
    >>> c.looks, c.supersample, c.psnr >= 30, c.budget
    (2, 2, True, '')
    """
    looks = validate.integer("looks", looks, 0, 64)
    supersample = validate.integer("supersample", supersample, 0, validate.MAX_SUPERSAMPLE)
    w, h = validate.shape2d("resolution", resolution)
    blurs, size = reference_view(p, focus)
    every = options(p, blurs=blurs, size=size, resolution=(w, h))
    ceiling = looks_ceiling(every)
    most, refused = looks_within([p] if plans is None else plans, budget)
    auto = [o for o in every if o.looks <= min(ceiling, most)]
    aim = target + MODEL_MARGIN  # the model's own error kept in hand
    planned = _fewest_looks(auto, aim)
    free = _fewest_looks([o for o in every if o.looks <= ceiling], aim)
    held = refused if free.looks > planned.looks else ""
    allowed = [
        o
        for o in (every if looks else auto)
        if (not looks or o.looks == looks) and (not supersample or o.supersample == supersample)
    ]
    if allowed:
        mine = _fewest_looks(allowed, aim)
        n, s, psnr = mine.looks, mine.supersample, mine.psnr
    if looks and supersample:  # both the user's, whatever the table holds
        n, s = looks, supersample
        psnr = predicted_psnr(n, s, blurs=blurs, size=size)
    elif not allowed:  # an untabled count or supersampling: predicted as it is
        n = looks or planned.looks
        s = supersample or planned.supersample
        psnr = predicted_psnr(n, s, blurs=blurs, size=size)
    return QualityChoice(
        looks=n,
        supersample=s,
        psnr=psnr,
        target=target,
        planned=planned,
        blur=float(blurs.max()),
        size=size,
        user_looks=looks,
        user_supersample=supersample,
        budget=held,
        unbudgeted=free if held else None,
    )


NEAR_BEST = 0.5  # [dB] short of a target no setting reaches, the fewest looks this near the best
# [dB] Auto aims this far above the target: the most the model predicted above a measured setting of
# the scenes bench/quality_fit.py fits it to
MODEL_MARGIN = 0.75


def _fewest_looks(candidates, target: float) -> Option:
    """The fewest looks of ``candidates`` predicted to reach ``target`` [dB] with some
    supersampling (where none does, to come within NEAR_BEST of the best), at their cheapest
    supersampling (:func:`_cheapest`). The looks are recorded once for every view of the
    plate, at any resolution, so they follow from the predictions alone: a view's cost, which
    the render's resolution sets, chooses only the supersampling, and a smaller preview
    never asks for another recording."""
    best = max(o.psnr for o in candidates)
    goal = target if best >= target else best - NEAR_BEST
    n = min(o.looks for o in candidates if o.psnr >= goal)
    return _cheapest([o for o in candidates if o.looks == n], target)


def _cheapest(candidates, target: float) -> Option:
    """The cheapest of ``candidates`` (one look count's supersamplings) predicted to reach
    ``target`` [dB]; where none does, the best: a finer supersampling costs only the view's
    time, never a recording or its disk."""
    reach = [o for o in candidates if o.psnr >= target]
    if not reach:
        return max(candidates, key=lambda o: (o.psnr, -o.seconds))
    return min(reach, key=lambda o: o.seconds)
