"""Choosing the optics for a scene in ordinary metres (Sect. V-B, VI-A, VII-A, VII-D).

Wavelengths need not be those of light (Sect. VII-B): the pipeline is scale-free, so the
wavelength is chosen for the plate's sampling and the image's resolution.

- Band: an object point lights a cone of sin θ = b; the cone's flat part (inside its soft
  rim) covers the directions from the objects towards the camera (or ``DEFAULT_BAND`` when no
  camera is given).
- Off-axis recording: the virtual image, the twin image and the |O|² term separate when the
  reference's sin ϑ = 3b, and the hologram samples the carrier when sin ϑ + b <= λ/(2d)
  (Eq. 19): b = λ/(8d) at the limit, kept ``MARGIN`` below it.
- Points: two per resolved spot of the plate (λ/(2b)) along the diagonal, or two per pixel
  footprint of the camera when that is coarser (finer points are never resolved).
- Image: a pinhole of diameter D resolves λ/D (Sect. VII-A) and blurs by D/r at distance r;
  both reach two pixels Δ when λ = 4Δ²r: the wavelength that serves that image resolution
  without filtering (Sect. VII-D), which fixes the hologram's size N = 8·S·b/λ.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from .. import validate
from ..optics.depth import partner_wavelength
from ..optics.pupil import intensity_supersample, pinhole_wavelength
from ..scene.hologram import ENCODINGS
from ..scene.plate import ViewingZone, box_corners
from ..validate import InputError
from .point_sources import CONE_RIM

log = logging.getLogger(__name__)
DEFAULT_BAND = 0.25      # sin θ of the viewing zone without a camera
MAX_BAND = 0.9           # the widest cone chosen, sin θ (64°), with a camera or without
MARGIN = 0.95            # the cone stays this fraction inside the off-axis sampling limit
DEPTH_MARGIN = 1.25      # the depth pair's unambiguous range over the scene's extent
MIN_RESOLUTION, DEFAULT_RESOLUTION = 256, 1024


@dataclass(frozen=True, slots=True, kw_only=True)
class Sampling:
    """Chosen optics: ``shape`` (rows, cols), ``pitch`` [m], ``wavelength`` [m] of the colour
    channels, ``depth_wavelength`` [m] (λ2 = ε·λ1, Eq. 30), ``band`` sin θ, ``reference_angle``
    [rad], ``spacing`` of mesh points [m]."""

    shape: tuple
    pitch: float
    wavelength: float
    depth_wavelength: float
    band: float
    reference_angle: float
    spacing: float

    def describe(self) -> str:
        return (f"hologram {self.shape[1]}x{self.shape[0]} at pitch {self.pitch:.4g} m, "
                f"λ = {self.wavelength:.4g} m (depth λ2 = {self.depth_wavelength:.6g} m), "
                f"cone sin θ = {self.band:.3g}, reference {math.degrees(self.reference_angle):.2f}°,"
                f" point spacing {self.spacing:.3g} m")


def band_towards(points, camera_position) -> float:
    """sin θ of the widest angle between the plate normal (+z) and the lines from ``points``
    (N, 3) [m] to ``camera_position`` [m], all in the plate's frame."""
    v = np.asarray(camera_position, np.float64) - np.asarray(points, np.float64)
    return float(np.max(np.hypot(v[:, 0], v[:, 1]) / np.linalg.norm(v, axis=1)))


def choose(plate_size, points, *, camera=None, resolution=None,
           max_resolution=2048, wavelength=None) -> Sampling:
    """The hologram and wavelength for ``points`` (N, 3) [m] in the plate's frame behind a plate
    of ``plate_size`` (width, height) [m].

    camera : (position (3,) [m] in the plate's frame, pixel angle [rad]), optional
        Sizes the cone to the camera and the wavelength to its pixels (module docstring).
    resolution : int, optional
        Samples along the plate's longer side; default from the camera (at most
        ``max_resolution``) or ``DEFAULT_RESOLUTION``.
    wavelength : float, optional
        Overrides the chosen λ [m]; the cone then follows from it and the pitch.
    """
    width, height = validate.pair("plate_size", plate_size, "m")
    validate.positive("plate width", width, "m")
    validate.positive("plate height", height, "m")
    try:
        pts = np.asarray(points, np.float64).reshape(-1, 3)
    except (TypeError, ValueError):
        pts = np.zeros((0, 3))
    if not len(pts) or not np.isfinite(pts).all() or (pts[:, 2] >= 0).any():
        raise InputError("points must be finite (x, y, z) [m] behind the plate (z < 0 in its "
                         "frame)")
    max_resolution = validate.integer("max_resolution", max_resolution, 16)
    if wavelength is not None:
        wavelength = validate.wavelength("wavelength", wavelength)
    side = max(width, height)
    band = DEFAULT_BAND
    lam_image, footprint = None, 0.0
    if camera is not None:
        position, pixel = camera
        # the camera inside every point's cone where it is flat, clear of its soft rim
        band = min(MAX_BAND, 1.1 * band_towards(pts, position) / (1 - CONE_RIM))
        r = float(np.min(np.linalg.norm(pts - position, axis=1)))
        lam_image = pinhole_wavelength(pixel, r)
        footprint = pixel * r
    if resolution is None:
        if wavelength or lam_image:
            resolution = math.ceil(8 * side * band / (MARGIN * (wavelength or lam_image)))
            resolution = int(np.clip(resolution, MIN_RESOLUTION, max_resolution))
        else:
            resolution = DEFAULT_RESOLUTION
    resolution = validate.integer("resolution", resolution, 16)
    pitch = side / resolution
    lam = wavelength or 8 * pitch * band / MARGIN
    extent = float(np.linalg.norm(pts.max(0) - pts.min(0)))
    lam2 = partner_wavelength(lam, DEPTH_MARGIN * max(extent, lam) / 2)
    # λ2 < λ1 is the tighter one; a wavelength long against the pitch samples every
    # direction, but a cone ends at 90° (sin θ < 1, what a hologram file holds)
    band = min(MARGIN * lam2 / (8 * pitch), MAX_BAND)
    s = Sampling(shape=(max(1, round(height / pitch)), max(1, round(width / pitch))),
                 pitch=pitch, wavelength=lam, depth_wavelength=lam2, band=band,
                 reference_angle=math.asin(min(0.99, 3 * lam2 / (8 * pitch))),
                 spacing=max(lam / (2 * band) / math.sqrt(2), footprint / 2))
    log.info("sampling: %s", s.describe())
    if lam_image is not None and lam > 1.5 * lam_image:
        # the spot grows as √λ at the pinhole's best (λ = 4Δ²r gives two pixels), and the
        # sharp λ needs the hologram's side to grow as 1/λ
        log.warning("sampling: this plate's view resolves about %.1f px (2 px at best): the "
                    "image needs λ <= %.3g m, a hologram of %d samples allows %.3g m; %d "
                    "samples (Max Hologram Size) or the camera mode would make it sharp",
                    2 * math.sqrt(lam / lam_image), lam_image, resolution, lam,
                    math.ceil(resolution * lam / lam_image))
    return s


# --- plates as scene assets: sampling planned from the viewing zone and the optics -------------

SPOT_SPACING = 1.0   # emitters lie this many resolved spots apart, seen from the zone
SLAB_SPOT = 1.5      # a slab's depth seen at the zone's widest angle from its centre spans
                     # this many spots: an occluding edge, and an emitter moved onto its
                     # slab's plane, move by at most half of it (2: views 2 cm off-centre
                     # 0.6-0.8 dB lower on the plate scene; 1: the recording 1.7x as long)
SHARP_SPOT = 0.5     # a view is sharp when λ/D spans at most this many pixels (a fine pixel,
                     # what the camera hologram resolves)
CHANNELS = 4         # R, G, B at λ1 and the depth partner λ2
FFT_SECONDS = 1.0e-9  # per complex sample and log2(samples) of an FFT (2-core Zen 3, FFTW:
                      # 0.7-1.4e-9 from 1024² to 4096²)
MASK_SECONDS = 1.1e-7  # per slab-grid sample and slab: silhouettes and emitters (the plate
                       # scene: 97 s measured, 68 s of it transforms)
PIXEL_SECONDS = 3e-7  # per fine pixel and look of a view: the reads, the images' transfer and
                      # the pass's assembly
VIEW_SECONDS = 0.3   # a view's fixed cost [s] (programs, pixel tables)


@dataclass(frozen=True, slots=True, kw_only=True)
class PlatePlan:
    """A plate's sampling, planned from its viewing zone and the objects before recording.

    shape : (rows, cols) samples; pitch [m]
    wavelength, depth_wavelength : λ1 of the colours and the depth partner λ2 = ε·λ1 [m]
    band : sin θ the plate carries, the widest angle between its normal and a line from an
        object point to a point of the zone
    needed_band : sin θ the zone needs (the band is smaller only for a given wavelength)
    encoding : 'complex' (the object wave: λ = 2·pitch·sin θ) or 'intensity' (|O + R|², whose
        carrier, twin and |O|² terms take 4x the band per side: λ = 8·pitch·sin θ)
    reference_angle : ϑ [rad] of an intensity plate's reference (sin ϑ = 3·sin θ), else 0
    step : the angle [rad] between neighbouring emitters seen from the zone's centre (about a
        resolved spot λ/D of the zone's pupil: one emitter per spot, as the camera hologram
        has one per bin)
    distance : the distance [m] from the zone's centre to the objects' centre (the emitters'
        density is 1/(step·distance)² per m² there)
    slab : depth [m] of the slabs the occlusion masks are applied at
    zone : the :class:`ViewingZone`; bounds : (2, 3) the objects' box [m] in the plate's frame
    """

    shape: tuple
    pitch: float
    wavelength: float
    depth_wavelength: float
    band: float
    needed_band: float
    encoding: str
    reference_angle: float
    step: float
    distance: float
    slab: float
    zone: ViewingZone
    bounds: np.ndarray

    def describe(self) -> str:
        return (f"{self.encoding} plate {self.shape[1]}x{self.shape[0]} at pitch "
                f"{self.pitch:.4g} m, λ = {self.wavelength:.4g} m (depth λ2 = "
                f"{self.depth_wavelength:.6g} m), band sin θ = {self.band:.3g} for the zone "
                f"{self.zone.describe()}; emitters {self.step:.3g} rad apart seen from its "
                f"centre, slabs {self.slab:.3g} m deep")

    @property
    def size(self) -> tuple[float, float]:
        """(width, height) [m] of the sampled plate."""
        return self.shape[1] * self.pitch, self.shape[0] * self.pitch

    def slab_grid(self) -> tuple[int, int]:
        """(rows, cols) of the grid the slabs are propagated on: the objects' box widened by
        the light's spread over their depth (the band's angle), at the plate's pitch."""
        lo, hi = np.asarray(self.bounds)
        spread = (hi[2] - lo[2]) * self.band / math.sqrt(1 - self.band**2) + 8 * self.pitch
        return tuple(math.ceil((hi[i] - lo[i] + 2 * spread) / self.pitch) + 1
                     for i in (1, 0))

    def slabs(self) -> int:
        lo, hi = np.asarray(self.bounds)
        return max(1, math.ceil((hi[2] - lo[2]) / self.slab))

    def memory_bytes(self, channels=CHANNELS) -> float:
        """Host bytes of a recording: the plate's complex channels, and the 2× padded grids
        that carry the last slab's fields to it."""
        n = math.prod(self.shape)
        stored = (8 if self.encoding == "complex" else 12) * channels * n
        return stored + 2 * 8 * 4 * n + 8 * 4 * channels * math.prod(self.slab_grid())

    def record_seconds(self, channels=CHANNELS) -> float:
        """Estimated recording time [s] on a 2-core CPU: per slab and channel a step (two
        FFTs of the slab grid, padded by the step's spread only), per slab its silhouettes
        and emitters, per channel one propagation onto the plate (two FFTs of the 2× padded
        grid that holds the slab grid and the plate)."""
        slab = self.slab_grid()
        union = tuple(max(a, b) for a, b in zip(slab, self.shape))
        return channels * (self.slabs() * 2 * _fft_seconds(slab)
                           + _propagation_seconds(union)) \
            + self.slabs() * MASK_SECONDS * math.prod(slab)


@dataclass(frozen=True, slots=True, kw_only=True)
class ViewPlan:
    """What a camera's view of a plate will be (:func:`plan_view`).

    spot_px : the view's resolution λ/D in pixels (a lens of diameter D; a pinhole's D is
        chosen as in :func:`holo_core.optics.pupil.camera_pupil`)
    sharp : whether spot_px <= SHARP_SPOT (a fine pixel, the camera hologram's resolution)
    sharp_samples : samples along the plate's longer side that make this view sharp
    blur_px : the blur beyond sharp, in pixels (0 when sharp)
    outside_zone : how far [m] the camera's pupil reaches beyond the zone (0: inside)
    seconds : the estimated time of one view [s]
    """

    spot_px: float
    sharp: bool
    sharp_samples: int
    blur_px: float
    outside_zone: float
    seconds: float


def band_towards_zone(bounds, zone: ViewingZone) -> float:
    """sin θ of the widest angle between the plate's normal and a line from a point of the box
    ``bounds`` (2, 3) [m] to a point of ``zone`` (both in the plate's frame). The widest lies
    between corners: the lateral distance is largest, the depth smallest, at corners of both
    boxes."""
    v = zone.corners()[:, None, :] - box_corners(bounds)[None, :, :]
    return float(np.max(np.hypot(v[..., 0], v[..., 1]) / np.linalg.norm(v, axis=-1)))


def plan(plate_size, bounds, *, zone: ViewingZone, resolution=None, encoding="complex",
         wavelength=None, camera=None, max_resolution=8192) -> PlatePlan:
    """The sampling of a plate of ``plate_size`` (width, height) [m] for objects in the box
    ``bounds`` (2, 3) [m] (the plate's frame, z < 0) seen from ``zone``.

    The band covers every object point's wave towards the whole zone; the wavelength follows
    from the pitch and that band (λ = 2·pitch·sin θ for a complex plate, 8· for an intensity
    one), not from a pinhole rule: a lens focused on the objects resolves λ/D.

    resolution : int, optional
        Samples along the plate's longer side; default: what ``camera`` needs for a sharp
        view (:func:`plan_view`), at most ``max_resolution``, else ``DEFAULT_RESOLUTION``.
    wavelength : float, optional
        λ1 [m] instead of the chosen one; the band is then what the pitch carries at it (a
        warning names the zone's need when that is less).
    camera : (position (3,) [m] in the plate's frame, pixel angle [rad], pupil diameter [m]
        or None for a pinhole), optional
    """
    width, height = validate.pair("plate_size", plate_size, "m")
    validate.positive("plate width", width, "m")
    validate.positive("plate height", height, "m")
    validate.choice("encoding", encoding, ENCODINGS)
    if not isinstance(zone, ViewingZone):
        raise InputError(f"zone must be a ViewingZone; got {type(zone).__name__}")
    try:
        box = np.asarray(bounds, np.float64).reshape(2, 3)
    except (TypeError, ValueError):
        box = np.full((2, 3), np.nan)
    if not np.isfinite(box).all() or (box[0] > box[1]).any() or box[1, 2] >= 0:
        raise InputError(f"bounds must be the objects' box (min, max corners [m]) behind the "
                         f"plate (z < 0 in its frame); got {np.asarray(bounds).tolist()!r}"[:300])
    max_resolution = validate.integer("max_resolution", max_resolution, 16)
    if camera is not None:
        camera = _camera(camera)
    needed = min(MAX_BAND, band_towards_zone(box, zone))
    side = max(width, height)
    per_band = 2.0 if encoding == "complex" else 8.0  # λ / (pitch · sin θ)
    if resolution is None:
        resolution = DEFAULT_RESOLUTION
        if camera is not None:
            need = _sharp_samples(side, needed, per_band, camera, box)
            resolution = int(np.clip(need, MIN_RESOLUTION, max_resolution))
    resolution = validate.integer("resolution", resolution, 16)
    pitch = side / resolution
    half_depth = DEPTH_MARGIN * float(np.linalg.norm(box[1] - box[0])) / 2
    if wavelength is None:  # λ2 = ε·λ1 < λ1 is the tighter: it sets the band
        lam2 = per_band * pitch * needed / MARGIN
        _check_sizes(width, height, resolution, pitch, lam2, box, half_depth)
        lam = lam2 / (1 - lam2 / (2 * half_depth))
        band = needed
    else:
        lam = validate.length("wavelength", wavelength)
        _check_sizes(width, height, resolution, pitch, lam, box, half_depth)
        band = min(MARGIN * partner_wavelength(lam, half_depth) / (per_band * pitch), MAX_BAND)
        if band < needed:
            validate.warn_sampling(
                f"a plate of pitch {pitch:.4g} m carries sin θ = {band:.3g} at λ = {lam:.4g} m; "
                f"its viewing zone needs {needed:.3g}: cameras near the zone's edge see the "
                f"objects cut off")
    lam2 = partner_wavelength(lam, half_depth)
    far = float(np.linalg.norm(box.mean(0) - np.asarray(zone.centre)))
    # a pinhole's zone (no pupil): the pinhole at its best, D = √(λ·r) (facts §6)
    aperture = zone.pupil if zone.pupil > 0 else math.sqrt(lam * far)
    step = SPOT_SPACING * lam / aperture
    # a slab seen from the zone's edge shifts its silhouette by (slab/2)·(zone's half width)/r
    half = max(max(zone.half_extents[:2]), 1e-3 * far)
    slab = max(SLAB_SPOT * step * far * far / half, pitch)
    reference = math.asin(min(0.99, 3 * band)) if encoding == "intensity" else 0.0
    return PlatePlan(shape=(max(1, round(height / pitch)), max(1, round(width / pitch))),
                     pitch=pitch, wavelength=lam, depth_wavelength=lam2, band=band,
                     needed_band=needed, encoding=encoding, reference_angle=reference,
                     step=step, distance=far, slab=slab, zone=zone, bounds=box)


def _camera(camera) -> tuple:
    """``camera`` (position (3,) [m] in front of the plate, pixel angle [rad] > 0, pupil
    diameter [m] > 0 or None) checked."""
    try:
        position, pixel, pupil = camera
    except (TypeError, ValueError):
        raise InputError(f"camera must be (position (3,) [m], pixel angle [rad], pupil "
                         f"diameter [m] or None); got {camera!r}"[:300]) from None
    check_in_front("camera position", position)
    return (validate.vector("camera position", position, 3, "m"),
            validate.positive("camera pixel angle", pixel, "rad"),
            None if pupil is None else validate.positive("camera pupil", pupil, "m"))


def check_in_front(name: str, position) -> None:
    """:class:`InputError` unless ``position`` (3,) [m] lies in front of the plate."""
    p = validate.vector(name, position, 3, "m")
    if p[2] <= 0:
        raise InputError(f"{name} must be in front of the plate (z > 0 in its frame: the plate "
                         f"is z = 0, the objects behind it); got ({p[0]:g}, {p[1]:g}, "
                         f"{p[2]:g}) m, {'on' if p[2] == 0 else 'behind'} the plate")


def _check_sizes(width, height, resolution, pitch, wavelength, box, half_depth) -> None:
    """:class:`InputError`, in the user's terms, for a plate whose sampling no hologram holds
    (its pitch or wavelength outside [MIN_LENGTH, MAX_LENGTH]) and for objects too small for
    the depth pair to tell their depths apart (the partner λ2 = ε·λ1 exists only while λ is
    below the depth range, Eq. 30)."""
    lo, hi = validate.MIN_LENGTH, validate.MAX_LENGTH
    if not (lo <= pitch <= hi and lo <= wavelength <= hi):
        raise InputError(f"plate_size {width:g} x {height:g} m cannot be sampled by "
                         f"{resolution} samples along its longer side: the pitch would be "
                         f"{pitch:.3g} m and the wavelength {wavelength:.3g} m, and a hologram "
                         f"holds lengths in [{lo:g}, {hi:g}] m")
    size = " x ".join(f"{d:.3g}" for d in box[1] - box[0])
    if half_depth == 0:
        raise InputError(f"bounds: the objects' box ({size} m) has no size; give the box the "
                         f"objects fill")
    if wavelength >= 2 * half_depth:
        raise InputError(f"bounds: the objects' box ({size} m) is smaller than the wavelength "
                         f"a plate of {width:g} x {height:g} m at {resolution} samples needs "
                         f"(λ = {wavelength:.3g} m), and the depth pair tells depths apart only "
                         f"within a range above it; give the objects' real size or more "
                         f"samples")


def plan_view(p: PlatePlan, *, position, pixel_angle, pupil=None, resolution=(640, 480),
              distance=None) -> ViewPlan:
    """What a camera at ``position`` (3,) [m] in the plate's frame, with pixels of
    ``pixel_angle`` [rad] and an entrance pupil of diameter ``pupil`` [m] (None: a pinhole
    for objects ``distance`` [m] away) sees of the plate planned as ``p``."""
    position = validate.vector("position", position, 3, "m")
    pixel = validate.positive("pixel_angle", pixel_angle, "rad")
    w, h = validate.shape2d("resolution", resolution)
    far = float(np.linalg.norm(np.asarray(p.bounds).mean(0) - position)) \
        if distance is None else validate.positive("distance", distance, "m")
    if pupil is None:  # the plate's pinhole rule: λ/D of two pixels, D <= √(λ·r)
        d = min(p.wavelength / (2 * pixel), math.sqrt(p.wavelength * far))
    else:
        d = validate.positive("pupil", pupil, "m")
    spot = p.wavelength / (d * pixel)
    side = max(p.size)
    per_band = 2.0 if p.encoding == "complex" else 8.0
    sharp = _sharp_samples(side, p.needed_band, per_band, (position, pixel, pupil), p.bounds,
                           far)
    seconds = _view_seconds(p, position, d, pixel, w * h)
    return ViewPlan(spot_px=spot, sharp=spot <= SHARP_SPOT, sharp_samples=sharp,
                    blur_px=0.0 if spot <= SHARP_SPOT else spot,
                    outside_zone=p.zone.distance_outside(position, (d or 0) / 2),
                    seconds=seconds)


def _view_seconds(p: PlatePlan, position, pupil, pixel, pixels) -> float:
    """Estimated time [s] of one look of a view on a 2-core CPU, for a camera at ``position``
    (3,) [m, the plate's frame] looking along the plate's normal, pupil ``pupil`` [m], pixels
    of ``pixel`` [rad], ``pixels`` of them (:mod:`.to_pupil`, its own sizes): per channel the
    window (the cone from the pupil's rim to the objects' box, and its margins) carried to the
    pupil's neighbourhood (two FFTs), the rotation onto the pupil's grid (two), the image (one,
    of the 2× padded pupil); per fine pixel (the intensity's Nyquist rate) the reads and the
    assembly."""
    from .to_pupil import (PUPIL_PADDING, WINDOW_MARGIN, cone_on_plate, neighbourhood,
                           output_padding, pupil_grid)
    axes = np.eye(3)
    rim = np.asarray(position) + np.array([[sx, sy, 0] for sx in (-1, 1) for sy in (-1, 1)]
                                          ) * pupil / 2
    lo, hi = cone_on_plate(p.bounds, rim)
    window = [int(min(n, e)) + 1 for n, e in
              zip(p.shape, (hi - lo)[::-1] * (1 + 2 * WINDOW_MARGIN) / p.pitch)]
    shortest = min(p.wavelength, p.depth_wavelength)
    n, pitch = pupil_grid(p, axes, pupil, None, shortest)
    near = neighbourhood(n, pitch, axes, p.pitch)
    carried = tuple(int(output_padding(window, near) * m) for m in window)
    per_channel = (2 * _fft_seconds(carried) + _fft_seconds((2 * near,) * 2)
                   + _fft_seconds((int(PUPIL_PADDING * n),) * 2) + _fft_seconds((2 * n,) * 2))
    fine = intensity_supersample(pupil, pixel, shortest)
    return VIEW_SECONDS + CHANNELS * per_channel + PIXEL_SECONDS * pixels * fine * fine


def _sharp_samples(side, band, per_band, camera, box, distance=None) -> int:
    """Samples along the longer side ``side`` [m] that make a view of ``camera`` (position,
    pixel angle [rad], pupil [m] or None) resolve SHARP_SPOT pixels; a pinhole's spot is at
    least two pixels whatever the plate (λ = 4Δ²r, :func:`pinhole_wavelength`), so it gets
    the samples of that."""
    position, pixel, pupil = camera
    if pupil is None:
        r = distance or float(np.linalg.norm(np.asarray(box).mean(0) - position))
        lam = pinhole_wavelength(pixel, r)
    else:
        lam = SHARP_SPOT * pupil * pixel
    return math.ceil(side * per_band * band / (MARGIN * lam))


def _fft_seconds(shape) -> float:
    n = math.prod(shape)
    return FFT_SECONDS * n * math.log2(max(n, 2))


def _propagation_seconds(shape) -> float:
    """An angular-spectrum step of a field of ``shape`` zero-padded 2×: two FFTs."""
    return 2 * _fft_seconds(tuple(2 * s for s in shape))
