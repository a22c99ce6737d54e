"""A plate's plan: what it samples, what its views resolve, and what both cost, before any
recording. Pure arithmetic: it imports no OpenCL or FFT driver, so Blender's process calls it.

- Wavelength. A view resolves λ/D through its camera's pupil D; the plate is made for a
  reference view (the zone's pupil and a pixel angle Δ): λ = D·Δ/s makes that one fine pixel
  of s per pixel, as the camera hologram does.
- Samples. The plate stores its object wave against the carrier converging on the zone's
  centre (:mod:`.carrier`), so it carries only the directions from each of its points into
  the zone (widened by a soft rim): band = the largest difference of direction cosines between
  the line towards the zone's centre and a line towards a point of the zone, pitch =
  λ/(2·band), over the window the light from the objects to the zone crosses.
- Emitters. One per resolved spot seen from the zone's centre (the fine bin λ/D), on up to
  ``layers`` surfaces along each ray (depth peeling); each lights its footprint, the cone
  from it to the zone cut by the plate: a recording costs the footprints' samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import estimate as estimate_mod
from .. import memory as memory_mod
from .. import validate
from ..optics.depth import DEPTH_MARGIN, partner_wavelength
from ..optics.pupil import defocus_limited_diameter
from ..scene.plate import ViewingZone, box_corners
from ..validate import InputError
from .zone_light import emitters_seen, window_on_plate, zone_band

SUPERSAMPLE = 2  # fine pixels per pixel: the reference view resolves one
# of a spot: a zone's pixel and pupil kept in float32 (a .blend's) round them by 6e-8
SHARP_SLACK = 1e-6
LAYERS = 3  # surfaces an emitter ray may cross and still be recorded (depth peeling)
TILE = 2048  # samples a side of a tiled recording's tile, at most (fitted_tile)
TILE_COST = 2**17  # samples a tile costs beyond its own: its task, its emitters' lists
LOOKS = 2  # coded looks recorded by default (the checkerboard pair)
CHANNELS = 4  # R, G, B at λ1 and the depth partner at λ2
SAMPLE_BYTES = 8  # complex64
# measured on the development machine (2-core EPYC Zen 4, Intel's CPU OpenCL, alone): the
# zone sum's pairs (emitter, sample) per second, per channel group (three colours cost one),
# as this plan counts them (the emitters from the surfaces the zone sees, the footprints the
# cones' whole: the sum skips their faded rims, and pays for the tiles they cut)
# and each sample's own (PlatePlan.pairs); the colours one amplitude an emitter: the shot's
# plate of bench/estimates.py at 0.5 and 1.0 (two coded looks), 6.4e9 and 5.6e10 pairs summed
# in 3.3 s and 25.7 s
PAIRS_PER_SECOND = 2.1e9
# a further independent look in the same pass, of a look's time (its channels: on the shot's plate
# two looks took 34.6 s, apart 51.5 s)
FURTHER_LOOK = 0.35
FURTHER_CODED = 0.12  # a further coded look (2 or m² looks): its classes' set-up and mixing
COLOURS_ONLY = 0.8  # no depth partner: the colours' recurrence alone
# where the depth partner rides on the colours' recurrence (its light turns from theirs by at
# most PARTNER_TURN [rad] over a segment of SEG columns: zone_sum.py), a pair costs this much
# (the shot's plate of bench/estimates.py at 1.0 against 0.5)
PARTNER_RIDES = 0.7
SEG = 32  # columns per work item of the zone sum: its recurrence's segment
# [rad] the most (k2 - k)·|Δr| may turn over a segment for the partner to ride on the colours'
# recurrence (linear between its ends: 1.25e-5 off)
PARTNER_TURN = 0.01
# a sample's own cost in the zone sum, in pairs: its work item scans its block's list of
# emitters and writes each channel once, whatever lights it (the shot's plate at 0.25 and 0.5
# fitted together; it holds for the sphere's at two zones)
SAMPLE_PAIRS = 260
VIEW_SAMPLE_SECONDS = 3.9e-9  # per window sample and channel of a view: read, filter, gather
FINE_PIXEL_SECONDS = 7e-8  # per fine pixel and look of a view: spectra, image, assembly


@dataclass(frozen=True, slots=True, kw_only=True)
class PlatePlan:
    """A plate's sampling and costs (module docstring).

    zone : the :class:`ViewingZone`; bounds : (2, 3) the objects' box [m], the plate's frame
    pupil : the reference view's pupil [m] (the zone's, or for pinhole views the widest whose
        defocus over the objects' depths stays within a fine pixel, within the zone)
    wavelength, depth_wavelength : λ1 of the colours and the depth partner λ2 [m]
    spacing : the emitters' spacing in direction cosine seen from the zone's centre
    band : the samples' band in direction cosine (x, y) (the zone's angle seen from the plate)
    pitch, row_pitch : the samples' spacing along x and y [m]; origin : (x, y) [m] of sample
        (0, 0); shape : (rows, cols)
    emitters : the estimated emitter count; footprint : the mean samples an emitter lights;
        triangles : the meshes' triangles the emitters are found among (0: not known)
    looks : coded looks to record; tile : samples a side of a tiled recording's tile
    """

    zone: ViewingZone
    bounds: np.ndarray
    pupil: float
    wavelength: float
    depth_wavelength: float
    spacing: float
    band: tuple
    pitch: float
    row_pitch: float
    origin: tuple
    shape: tuple
    emitters: int
    footprint: float
    triangles: int = 0
    looks: int = LOOKS
    tile: int = TILE

    @property
    def samples(self) -> int:
        return math.prod(self.shape)

    @property
    def size(self) -> tuple[float, float]:
        """(width, height) [m] of the sampled window."""
        return self.shape[1] * self.pitch, self.shape[0] * self.row_pitch

    def disk_bytes(self, channels=CHANNELS, tiled=False) -> float:
        """Bytes of the recorded plate, every look: its files, or its tiled stores, which
        keep their edge tiles whole."""
        held = (
            self.samples
            if not tiled
            else math.ceil(self.shape[0] / self.tile)
            * math.ceil(self.shape[1] / self.tile)
            * self.tile**2
        )
        return SAMPLE_BYTES * channels * self.looks * held

    def needs_tiles(self, limit: float) -> bool:
        """Whether the looks, recorded together in one piece, need more than ``limit``
        [bytes] of memory: the recording then goes tile by tile."""
        return self.memory_bytes(CHANNELS * self.looks) > limit

    def memory_bytes(self, channels=CHANNELS, tiled=False) -> float:
        """Host bytes while recording: the whole plate of one look in memory, or one tile's
        channels and the emitters' tables when ``tiled``."""
        per_emitter = 8 * 3 + 8 * channels + 4 * 4 + 64  # position, amplitudes, footprint, …
        held = self.tile**2 if tiled else self.samples
        return 2 * SAMPLE_BYTES * channels * held + per_emitter * self.emitters

    @property
    def partner_rides(self) -> bool:
        """Whether the depth partner's light rides on the colours' recurrence in the zone
        sum (it turns from theirs by at most PARTNER_TURN over a segment)."""
        k, k2 = (2 * math.pi / lam for lam in (self.wavelength, self.depth_wavelength))
        return abs(k2 - k) * SEG * self.pitch <= PARTNER_TURN

    def pairs(self, channels=CHANNELS) -> float:
        """The zone sum's work, every look in one pass, in pairs (emitter, sample) of one
        look with its channels: the emitters' footprints (cheaper where the partner rides on
        the colours, or there is none) and each sample's own SAMPLE_PAIRS, the further looks
        counted at their share of one."""
        coded = self.looks == 2 or math.isqrt(self.looks) ** 2 == self.looks
        further = FURTHER_CODED if coded else FURTHER_LOOK
        pair = COLOURS_ONLY if channels <= 3 else PARTNER_RIDES if self.partner_rides else 1.0
        pairs = self.emitters * self.footprint * pair + SAMPLE_PAIRS * self.samples
        return (1 + further * (self.looks - 1)) * pairs

    def record_seconds(self, channels=CHANNELS) -> float:
        """The zone sum's seconds, every look in one pass, at the development machine's idle
        rate: the sum alone, without the emitters, the files or any set-up
        (:func:`holo_core.estimate.plate` counts those on this machine)."""
        return self.pairs(channels) / PAIRS_PER_SECOND

    def check_budget(
        self, *, memory=None, disk=None, channels=CHANNELS, tiled=False, held=1
    ) -> None:
        """:class:`InputError` with the sizes and what would take less, before any work, when
        the recording needs more than ``memory`` (the whole plate, or one tile when
        ``tiled``; of ``held`` looks recorded together) or its plate more than ``disk``
        [bytes] (None: no limit)."""
        advice = (
            "a smaller viewing zone, objects nearer the plate, a coarser view (fewer "
            "pixels or a smaller aperture) or fewer looks need less; Camera mode needs "
            "no plate"
        )
        stored = self.disk_bytes(channels, tiled=tiled)
        if disk is not None and stored > disk:
            raise InputError(
                f"the plate needs {memory_mod.gib(stored)} on disk "
                f"({self.looks} look(s) of {self.shape[1]} x {self.shape[0]} "
                f"samples, {channels} channels{', in tiles' if tiled else ''}); "
                f"the disk budget is {memory_mod.gib(disk)}: "
                f"{advice}"
            )
        need = self.memory_bytes(channels * held, tiled=tiled)
        if memory is not None and need > memory:
            piece = "a tile at a time" if tiled else "in one piece"
            raise InputError(
                f"recording the plate needs {memory_mod.gib(need)} of memory "
                f"{piece}; the memory budget is "
                f"{memory_mod.gib(memory)}: "
                f"{'' if tiled else 'record it tile by tile, or '}{advice}"
            )

    def check_recording(
        self, *, memory=None, disk=None, channels=CHANNELS, tiled: bool | None = False
    ) -> bool:
        """Whether the looks are recorded tile by tile, checked before any work: ``tiled``
        None decides it (:meth:`needs_tiles` against the host's share of its memory, at
        most ``memory``); :class:`InputError` where the recording of every look together
        needs more than the budget ``memory`` or ``disk`` [bytes] (None: no limit,
        :meth:`check_budget`) or the host's share of its memory."""
        if tiled is None:
            tiled = self.needs_tiles(memory_mod.host_share(memory))
        self.check_budget(memory=memory, disk=disk, channels=channels, tiled=tiled, held=self.looks)
        held = (
            f"a {self.tile}x{self.tile} tile"
            if tiled
            else f"a {self.shape[1]}x{self.shape[0]} plate"
        )
        memory_mod.check_host(
            f"{held} of {channels * self.looks} channels",
            self.memory_bytes(channels * self.looks, tiled=tiled),
        )
        return bool(tiled)

    def describe(self) -> str:
        """The plan in plain words: samples, spacing, size on disk (its time:
        :func:`holo_core.estimate.plate`)."""
        mpx = self.samples / 1e6
        return (
            f"{self.shape[1]} x {self.shape[0]} samples ({mpx:.3g} Mpx, "
            f"{self.pitch * 1e6:.3g} µm apart, {self.size[0] * 1e3:.4g} x "
            f"{self.size[1] * 1e3:.4g} mm of the plate) for the zone {self.zone.describe()}; "
            f"about {self.emitters:,} emitters; {self.looks} look(s): "
            f"{memory_mod.gib(self.disk_bytes())}"
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class ViewPlan:
    """What one camera's view of a plate will be (:func:`plan_view`).

    spot_px : the view's resolution λ/D in pixels; sharp : whether it is at most a fine pixel
    outside_zone : how far [m] the pupil reaches beyond the zone (0: inside)
    window : samples of the plate the view reads; seconds : its estimated time, every look
    """

    spot_px: float
    sharp: bool
    outside_zone: float
    window: int
    seconds: float

    def describe(self) -> str:
        verdict = "sharp" if self.sharp else f"about {self.spot_px:.2g} px blurred"
        where = (
            "inside the zone"
            if not self.outside_zone
            else f"{self.outside_zone * 1e3:.3g} mm outside the zone"
        )
        return (
            f"the view is {verdict} (resolves {self.spot_px:.2g} px), the camera "
            f"{where}; it reads {self.window / 1e6:.3g} Mpx of the plate, about "
            f"{duration(self.seconds)} here"
        )


duration = estimate_mod.duration


def plan(
    plate_size,
    bounds,
    *,
    zone: ViewingZone,
    pixel_angle: float,
    supersample: int = SUPERSAMPLE,
    looks: int = LOOKS,
    wavelength=None,
    tile: int | None = None,
    seen: float | None = None,
    triangles: int = 0,
) -> PlatePlan:
    """The plan of a plate of ``plate_size`` (width, height) [m] for objects in the box
    ``bounds`` (2, 3) [m] (the plate's frame, z < 0) seen from ``zone``, whose views have
    pixels of ``pixel_angle`` [rad] (module docstring). ``wavelength`` [m] overrides λ1.
    ``seen``: the area of the surfaces the zone's centre sees (:func:`.zone_light.seen_area`, in squared
    direction tangents), where the meshes are known, counts the emitters; else the box does;
    ``triangles``: the meshes' triangles, where known (the emitters are found among them)."""
    width, height = validate.pair("plate_size", plate_size, "m")
    validate.positive("plate width", width, "m")
    validate.positive("plate height", height, "m")
    if not isinstance(zone, ViewingZone):
        raise InputError(f"zone must be a ViewingZone; got {type(zone).__name__}")
    box = _box(bounds)
    pixel = validate.positive("pixel_angle", pixel_angle, "rad")
    s = validate.integer("supersample", supersample, 1, 16)
    looks = validate.integer("looks", looks, 1, 64)
    if tile is not None:
        tile = validate.integer("tile", tile, 256)
        if tile % 256:
            raise InputError(f"tile must be a multiple of 256 samples; got {tile}")
    # a pinhole's views: the widest pupil its defocus allows, within the zone
    pupil = zone.pupil or min(
        pinhole_pupil(box, zone.centre, pixel / s)[0], 2 * min(zone.half_extents[:2]) or math.inf
    )
    if wavelength is None:
        lam = pupil * pixel / s
        if not validate.MIN_LENGTH <= lam <= validate.MAX_LENGTH:
            raise InputError(
                f"pixel_angle {pixel:.3g} rad through the zone's pupil of "
                f"{pupil:.3g} m asks views at λ = {lam:.3g} m, outside the "
                f"[{validate.MIN_LENGTH:g}, {validate.MAX_LENGTH:g}] m a "
                f"plate holds: give the views' real pixel angle and pupil"
            )
    else:
        lam = validate.length("wavelength", wavelength)
    extent = float(np.linalg.norm(box[1] - box[0]))
    half_depth = DEPTH_MARGIN * extent / 2
    size = " x ".join(f"{d:.3g}" for d in box[1] - box[0])
    if extent == 0:
        raise InputError(
            f"bounds: the objects' box ({size} m) has no size; give the box the objects fill"
        )
    if not lam < 2 * half_depth:
        raise InputError(
            f"bounds: the objects' box ({size} m) is smaller than the wavelength "
            f"its views need (λ = {lam:.3g} m), and the depth pair tells depths "
            f"apart only within a range above it: give the objects' real size"
        )
    lam2 = partner_wavelength(lam, half_depth)
    lo, hi = window_on_plate(box, zone, width, height)
    band = zone_band(lo, hi, zone)
    pitch, row_pitch = (min(lam, lam2) / (2 * b) for b in band)
    shape = (
        int(math.ceil((hi[1] - lo[1]) / row_pitch)) + 1,
        int(math.ceil((hi[0] - lo[0]) / pitch)) + 1,
    )
    narrow = hi[0] - lo[0] < pitch or hi[1] - lo[1] < row_pitch
    if narrow and wavelength is not None:
        raise InputError(
            f"wavelength {lam:.3g} m asks samples {pitch:.3g} x {row_pitch:.3g} m "
            f"apart, wider than the {hi[0] - lo[0]:.3g} x {hi[1] - lo[1]:.3g} m "
            f"of the plate the objects' light crosses: give a shorter one, or "
            f"none (the views' sharpness then sets it)"
        )
    if narrow:
        raise InputError(
            f"plate_size {width:g} x {height:g} m: where the objects' light "
            f"crosses it, it is narrower than one sample at the pitch the zone "
            f"needs ({pitch:.3g} x {row_pitch:.3g} m): make it larger"
        )
    spacing = lam / pupil
    emitters, footprint = emitters_seen(box, zone, spacing, pitch * row_pitch, seen)
    return PlatePlan(
        zone=zone,
        bounds=box,
        pupil=pupil,
        wavelength=lam,
        depth_wavelength=lam2,
        spacing=spacing,
        band=band,
        pitch=pitch,
        row_pitch=row_pitch,
        origin=(float(lo[0]), float(lo[1])),
        shape=shape,
        emitters=emitters,
        footprint=footprint,
        triangles=int(triangles),
        looks=looks,
        tile=tile or fitted_tile(shape),
    )


def fitted_tile(shape, largest=TILE, step=256) -> int:
    """The side of a tiled recording's tiles for a plate of ``shape`` (rows, cols): the
    multiple of ``step`` up to ``largest`` whose tiles cover it with the fewest samples, each
    tile counted TILE_COST more. A store keeps its edge tiles whole, so a tile that fits the
    plate wastes little: bench/shot.py's plate, 2525 x 11965 samples, took 67 % more in
    tiles of 2048 and takes 8.5 % more in its fitted 1280."""

    def cost(t):
        tiles = math.ceil(shape[0] / t) * math.ceil(shape[1] / t)
        return tiles * (t * t + TILE_COST), -t

    return min(range(step, largest + 1, step), key=cost)


def pinhole_pupil(box, eye, bin_angle, rotation=None) -> tuple[float, float]:
    """(diameter [m], focus [m]) of a pinhole view's pupil from ``eye`` (3,) [m] of the box
    ``box`` (2, 3) [m]: the widest whose defocus over the box's depths stays within a fine bin
    ``bin_angle`` [rad], focused on their middle in 1/z (the camera hologram's rule). The
    depths lie along the view axis of the camera's axes ``rotation`` (3, 3; a plate's view),
    or without them along the line towards the box's centre (the plan's reference view)."""
    corners = box_corners(box) - np.asarray(eye, np.float64)
    if rotation is None:
        axis = -corners.mean(0) / np.linalg.norm(corners.mean(0))
        depth = np.clip(corners @ -axis, 1e-9, None)
    else:
        depth = -(corners @ rotation)[:, 2]
    return defocus_limited_diameter(bin_angle, float(depth.min()), float(depth.max()))


def _box(bounds) -> np.ndarray:
    try:
        box = np.asarray(bounds, np.float64).reshape(2, 3)
    except (TypeError, ValueError):
        box = np.full((2, 3), np.nan)
    if not np.isfinite(box).all() or (box[0] > box[1]).any() or box[1, 2] >= 0:
        raise InputError(
            f"bounds must be the objects' box (min, max corners [m]) behind the "
            f"plate (z < 0 in its frame); got {np.asarray(bounds).tolist()!r}"[:300]
        )
    return box


def plan_view(p: PlatePlan, *, position, pixel_angle, pupil=None, resolution) -> ViewPlan:
    """What a camera at ``position`` (3,) [m] in the plate's frame with pixels of
    ``pixel_angle`` [rad], an entrance pupil of ``pupil`` [m] (None: a pinhole, the plan's
    own) and ``resolution`` (W, H) sees of the plate planned as ``p``."""
    position = validate.vector("position", position, 3, "m")
    if position[2] <= 0:
        raise InputError(
            f"the camera must be in front of the plate (z > 0 in its frame); it "
            f"is at z = {position[2]:.4g} m"
        )
    pixel = validate.positive("pixel_angle", pixel_angle, "rad")
    pupil = p.pupil if pupil is None else validate.positive("pupil", pupil, "m")
    w, h = validate.shape2d("resolution", resolution)
    spot = p.wavelength / (pupil * pixel)
    objects = box_corners(p.bounds)
    t = -objects[:, 2:3] / (position[2] - objects[:, 2:3])
    xy = objects[:, :2] + t * (position[None, :2] - objects[:, :2])
    lo = np.maximum(xy.min(0) - pupil, p.origin)
    hi = np.minimum(xy.max(0) + pupil, np.asarray(p.origin) + np.asarray(p.size))
    window = int(np.prod(np.maximum(hi - lo, 0)) / (p.pitch * p.row_pitch))
    fine = max(SUPERSAMPLE, math.ceil(SUPERSAMPLE * spot * (1 - SHARP_SLACK)))
    seconds = p.looks * (
        CHANNELS * window * VIEW_SAMPLE_SECONDS + w * h * fine * fine * FINE_PIXEL_SECONDS
    )
    return ViewPlan(
        spot_px=spot,
        sharp=spot * SUPERSAMPLE <= 1 + SHARP_SLACK,
        outside_zone=p.zone.distance_outside(position, pupil / 2),
        window=window,
        seconds=seconds,
    )
