"""Image generation: a camera anywhere in the plate's viewing zone (Sect. VII).

A plate's view is the camera hologram's image of the plate's field at the camera's pupil:
per channel, the part of the plate inside the cone from the pupil to the objects is carried to
the pupil's plane and rotated onto it (:mod:`holo_core.plate.to_pupil`), and the camera
hologram's own stage (:mod:`holo_core.optics.imaging`) forms the image: the iris, the thin lens
of Eq. 24, the angular spectrum read at each pixel's direction cosines (Eq. 22) by the ES
kernel of a non-uniform FFT. Radiance is |A|² / (σ·b²), b = λ/L the direction cosines a bin of
the pupil's spectrum spans and σ the emitters per m² of surface, so a surface of emitters of
intensity I shows I. The depth partner (unit emitters) gives each pixel's coverage, hence
alpha and the colour as radiance over coverage, and the depth from the two-wavelength phase
(Eq. 26–30), as the camera hologram does. An intensity hologram is reconstructed first (R'·H,
the DC term suppressed, the twin and |O|² terms filtered off with the band outside the
recorded cone, Sect. VI).
"""

from __future__ import annotations

import logging
import math
import warnings
from dataclasses import replace

import numpy as np

from .. import jobs, memory, validate
from ..acquired.framing import stated_plane
from ..opencl import get_runtime
from ..opencl.arrays import cached
from ..optics import depth as depth_mod
from ..optics import speckle
from ..optics.imaging import IRIS_TAPER, PupilImage, assemble, fold_images, iris_power
from ..optics.pupil import Pupil, camera_pupil, defocus_limited_diameter, intensity_supersample
from ..propagation import grid
from ..propagation.convolution import convolve
from ..propagation.tilt import tilt_reach
from ..scene.camera import Camera
from ..scene.hologram import Hologram
from ..scene.plate import box_corners
from ..validate import InputError, shown
from ..view import BACKGROUND_DEPTH, RenderResult, as_rgb
from .plan import SHARP_SLACK, SUPERSAMPLE
from .reconstruction import reconstruct
from .to_pupil import (
    CarrierPupil,
    cone_on_plate,
    field_at_pupil,
    lit_diameter,
    overlaps,
    plate_window,
    pupil_grid,
    window_of,
)

log = logging.getLogger(__name__)
VIEW_MARGIN = 0.1  # the window reaches this fraction of the image beyond its corners


def camera_in_plate(hologram: Hologram, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """The camera's axes (columns) and aperture centre [m] in the hologram's frame."""
    plate = np.asarray(hologram.plate, np.float64)
    axes = plate[:3, :3] / np.linalg.norm(plate[:3, :3], axis=0)
    rotation = axes.T @ camera.rotation
    u, _, vt = np.linalg.svd(rotation)  # re-orthonormalise what float round-off bent
    rotation = u @ vt
    position = axes.T @ (camera.position - plate[:3, 3])
    if position[2] <= 0:
        raise InputError(f"the camera must be in front of the hologram (z > 0 in the plate's "
                         f"frame); it is at z = {position[2]:.4g} m")
    if rotation[2, 2] <= 0:
        raise InputError("the camera must look towards the hologram (its view axis has to "
                         "point to −z of the plate)")
    return rotation, position


@validate.scale_free()
def plate_wave(hologram: Hologram, channel: int, *, source="hologram"):
    """The object wave leaving the hologram for one channel, complex64 (H, W) (NumPy, or a
    device array that the propagation takes without a host round trip): R'·H' with the
    DC term suppressed and the band outside the recorded cone removed (Sect. VI), or the
    stored object wave (``source='object_wave'``, the ideal reconstruction). A complex
    hologram's samples are the object wave."""
    if validate.choice("source", source, ("hologram", "object_wave")) == "object_wave" or \
            hologram.encoding == "complex":
        if hologram.object_wave is None:
            raise InputError("source 'object_wave' needs a hologram that stores the object wave")
        return hologram.object_wave[channel]
    u = reconstruct(hologram, channel)
    if not hologram.band:
        return u
    rt = get_runtime()
    lam, shape = hologram.wavelengths[channel], u.shape

    def make():
        fy, fx = (grid.freqs(n, hologram.pitch) for n in shape)
        keep = (fx[None, :] ** 2 + fy[:, None] ** 2) * lam**2 <= hologram.band**2
        return (keep / keep.size).astype(np.complex64), ()

    mask, _ = cached(rt, ("band", shape, hologram.pitch, lam, hologram.band), make)
    return convolve(rt, rt.to_device(u), mask)


@validate.scale_free()
@np.errstate(over="ignore", invalid="ignore")  # an overflow is refused at the end (_finish)
def render_view(holograms, camera: Camera, *, aperture: Pupil | None = None, apodize=True,
                chromatic=True, composition="mean", supersample="auto", exposure=None,
                opacity_threshold=0.5, source="hologram", depth_estimate="consensus",
                progress: jobs.Progress = None) -> RenderResult:
    """Render a view of one hologram, or several of the same scene recorded with independent
    random phases (temporal composition, Sect. VII-C and VII-E).

    Parameters
    ----------
    holograms : Hologram or sequence of Hologram
        Same wavelengths, pitch and pose; each one an iteration.
    camera : Camera
        Blender camera; its lens (``fstop``, ``focus_distance``) or a pinhole.
    aperture : Pupil, optional
        Overrides the camera's pupil (see :func:`camera_pupil`).
    apodize : bool
        Cosine-window the aperture (Fig. 9).
    chromatic : bool
        A lens designed for the first colour's wavelength focuses the others at f·λ/λ₀
        (Sect. VII-B); False makes it perfect for every wavelength.
    composition : {'mean', 'max'}
        How the iterations' intensities combine (Sect. VII-E).
    supersample : int or 'auto'
        Render at this many times the resolution, then average blocks (speckle reduction by
        spatial low-pass and downsampling, Sect. VII-E). 'auto' (:func:`nyquist_supersample`):
        the fine pixels sample the image's intensity at its Nyquist rate.
    exposure : float, optional
        Radiance to pixel value [m²: 1/(emitters per m²)]; default 1/point density (a surface shows its emitters'
        colour), or when that is unknown, the 99.5th percentile maps to 1.
    opacity_threshold : float
        Alpha is 1 where the surfaces cover more than this fraction of a pixel (0.5 puts the
        silhouette at the geometric edge), seen in the depth partner's image, whose emitters
        all have unit intensity. Holograms of bare points (no known emitter density): where
        the luminance exceeds this fraction of its 99.5th percentile.
    source : {'hologram', 'object_wave'}
        Reconstruct from the intensity hologram (default) or use the stored object wave.
    depth_estimate : {'consensus', 'brightest'}
        Depth from the phase of u1·conj(u2) summed over iterations and supersamples (the
        intensity-weighted consensus), or per pixel from the brightest iteration (Fig. 11c).
        Either way the depth pair is imaged through :func:`depth_aperture`.
    """
    try:
        holos = [holograms] if isinstance(holograms, Hologram) else list(holograms)
    except TypeError:
        holos = []
    if not holos:
        raise InputError(f"holograms must be a Hologram or a non-empty list of them; got "
                         f"{type(holograms).__name__}")
    if not isinstance(camera, Camera):
        raise InputError(f"camera must be a Camera; got {type(camera).__name__}")
    if aperture is not None and not isinstance(aperture, Pupil):
        raise InputError(f"aperture must be a Pupil or None; got {type(aperture).__name__}")
    first = holos[0]
    validate.choice("composition", composition, ("mean", "max"))
    validate.choice("depth_estimate", depth_estimate, ("consensus", "brightest"))
    validate.choice("source", source, ("hologram", "object_wave"))
    if isinstance(supersample, str) and supersample == "auto":
        supersample = nyquist_supersample(first, camera)
    supersample = validate.integer("supersample", supersample, 1, MAX_SUPERSAMPLE)
    _check_settings(holos, camera, supersample, exposure, opacity_threshold)
    fine = _supersampled(camera, supersample)
    colours, z_ch = first.colour_channels(), first.depth_channel()
    keep_fine = composition == "max" or depth_estimate == "brightest"  # else the pixels' means
    if z_ch is None and stated_plane(first) is None:
        warnings.warn("the hologram has no depth channel (record it with depth=True): the "
                      f"view's depth is the background ({BACKGROUND_DEPTH:g} m) everywhere, so a "
                      "Z-combine puts it behind every surface", NoDepthWarning, stacklevel=2)
    lam0 = first.wavelengths[colours[0]]
    centre = _centre_distance(first, camera)
    pupil = aperture or camera_pupil(fine, lam0, centre, apodize=apodize)
    rotation, position = camera_in_plate(first, camera)
    _check_zone(first, camera, position, pupil.diameter)
    if first.carrier is not None:
        if aperture is None and camera.fstop is None:  # a pinhole: the camera hologram's rule
            depth = -((box_corners(first.bounds) - position) @ rotation)[:, 2]
            diameter, focus = defocus_limited_diameter(camera.pixel_angle() / supersample,
                                                       float(depth.min()), float(depth.max()))
            if first.zone is not None:  # ... within the zone, where the plate sends light
                room = np.asarray(first.zone.half_extents[:2]) - np.abs(
                    position[:2] - np.asarray(first.zone.centre[:2]))
                diameter = min(diameter, max(2 * float(room.min()), 1e-3 * diameter))
            pupil = Pupil(diameter=diameter, focus=focus, apodize=apodize)
        looks, shape = carrier_looks(holos, camera, fine, pupil, rotation, position, colours,
                                     z_ch, supersample=supersample, chromatic=chromatic,
                                     keep_fine=keep_fine, progress=progress)
        if looks is None:
            warnings.warn("the view is black: the camera sees the objects beside the plate, "
                          "not through it", EmptyViewWarning, stacklevel=2)
            return _finish(np.zeros(camera.resolution[::-1] + (len(colours),)), None, None,
                           first, camera, pupil, exposure, opacity_threshold, lam0)
        return _compose(looks, colours, z_ch, first, camera, fine, pupil,
                        supersample=supersample, composition=composition,
                        depth_estimate=depth_estimate, centre=centre, exposure=exposure,
                        threshold=opacity_threshold, n=shape)
    lit = lit_diameter(first, position, rotation, pupil.diameter)  # the pupil's part in light
    window = plate_window(first, position, rotation, lit, _corners(camera, rotation))
    unseen = _unseen(first, rotation, position) or (None if overlaps(first, window) else (
        "the camera sees the objects beside the plate, not through it"))
    if unseen:  # a black view, said aloud (an animation's camera may pass out of the zone)
        warnings.warn(f"the view is black: {unseen}", EmptyViewWarning, stacklevel=2)
        return _finish(np.zeros(camera.resolution[::-1] + (len(colours),)), None, None, first,
                       camera, pupil, exposure, opacity_threshold, lam0)
    r0, r1, c0, c1 = window
    memory.check_host(f"the plate's {c1 - c0}x{r1 - r0} window", HOLOGRAM_SAMPLE_BYTES *
                      (r1 - r0) * (c1 - c0))
    channels = colours + ([z_ch] if z_ch is not None else [])
    n, d = pupil_grid(first, rotation, lit, pupil.focus,
                      min(first.wavelengths[c] for c in channels))
    rt = get_runtime()
    memory.check_device(rt, f"the {n}x{n} pupil's spectrum", 40.0 * n * n, 32.0 * n * n)
    taper = IRIS_TAPER if pupil.apodize else 0.0
    scale = 1 / math.sqrt(n * n * _iris_sum(n, d, pupil.diameter, taper, lit))
    imagers = {lam: PupilImage(rt, (n, n), bin=lam / (n * d), camera=fine)
               for lam in {first.wavelengths[c] for c in channels}}
    # radiance |A|² / (σ·b²): a surface of emitters of intensity I, σ per m², shows I
    density = first.point_density or 1.0
    looks = []
    same = _same(first, colours)
    for i, h in enumerate(holos):
        done = jobs.scaled(progress, i / len(holos), (i + 1) / len(holos))
        images = {}
        for m, c in enumerate(channels):
            lam = h.wavelengths[c]
            if h.encoding == "complex":  # the samples are the wave: read the window only
                u = window_of(h.object_wave, window, c)
            else:
                wave = plate_wave(h, c, source=source)
                u = window_of(wave if isinstance(wave, np.ndarray) else wave.get(), window)
            at = field_at_pupil(u, window, h, wavelength=lam, position=position,
                                rotation=rotation, n=n, pitch=d)
            lens = lam0 if chromatic else lam
            images[c] = imagers[lam].image(
                rt.to_device(at, np.complex64), pitch=(d, d), diameter=pupil.diameter,
                focus=pupil.focus, taper=taper, lens_k=2 * np.pi / lens,
                scale=scale * n * d / (lam * math.sqrt(density)))
            jobs.report(done, m + 1, len(channels))
        looks.append(fold_images(images, same=same, partner=z_ch, supersample=supersample,
                                 keep_fine=keep_fine))
    return _compose(looks, colours, z_ch, first, camera, fine, pupil, supersample=supersample,
                    composition=composition, depth_estimate=depth_estimate, centre=centre,
                    exposure=exposure, threshold=opacity_threshold, n=n)


def _iris_sum(n, d, diameter, taper, lit) -> float:
    """Σ w² of the iris over the pupil's grid (n×n, ``d`` [m] apart), which calibrates the
    view's radiance. A grid cut to the lit part of a larger iris (``lit`` < ``diameter``
    [m]) counts the whole iris, its area over d² (the rim's raised cosine integrated
    radially), so that the part beyond the light dims the view as it would the camera's."""
    if lit >= diameter:
        return iris_power((n, n), (d, d), diameter, taper)
    radius = diameter / 2
    inner = (1 - taper) * radius
    rho = np.linspace(inner, radius, 4097)
    rim = (0.5 * (1 + np.cos(np.pi * (rho - inner) / max(radius - inner, 1e-300)))) ** 2
    ring = rim * 2 * math.pi * rho  # by the trapezoid rule, written out (NumPy 2 renamed trapz)
    area = math.pi * inner**2 + float(np.sum((ring[1:] + ring[:-1]) * np.diff(rho)) / 2)
    return area / (d * d)


EDGE_BINS = 8  # the pupil's spectrum reaches this many bins beyond the image and its blur
SPREAD_PLANES = 8  # the looks' channels spread onto a view's bins in one pass, at most


def carrier_looks(holos, camera: Camera, fine: Camera, pupil: Pupil, rotation, position,
                  colours, z_ch, *, supersample, chromatic=True, keep_fine=False,
                  progress=None):
    """(each look's images at the pixels (:meth:`~holo_core.optics.imaging.PupilImage.fold`),
    the pupil's samples (h, w)) of plates stored against their zone's carrier
    (:class:`~holo_core.plate.to_pupil.CarrierPupil`); (None, None) where the pupil sees the
    objects beside the plate."""
    first = holos[0]
    window = carrier_window(first, camera, rotation, position, pupil.diameter)
    if window is None:
        return None, None
    lam0 = first.wavelengths[colours[0]]
    bin_ = min(camera.pixel_angle() / supersample, lam0 / pupil.diameter)
    shape, middle = _spectrum_box(first, fine, rotation, position, pupil, bin_, window)
    rt = get_runtime()
    channels = len(colours) + (z_ch is not None)
    batch = max(1, SPREAD_PLANES // channels)  # looks spread onto the bins in one pass
    planes, bins = batch * channels, math.prod(shape)
    # per plane and bin: the spread grid and the padded spectrum (2×2 oversampled), the pupil
    fine_bytes = 8.0 * planes * math.prod(fine.resolution) if keep_fine else 0.0
    memory.check_device(rt, f"the {shape[1]}x{shape[0]} pupil's spectra of {planes} planes",
                        72.0 * planes * bins + fine_bytes, 32.0 * planes * bins)
    view = CarrierPupil(rt, first, position=position, rotation=rotation,
                        diameter=pupil.diameter, bin=bin_, shape=shape, window=window,
                        centre=middle)
    hh, ww = shape
    taper = IRIS_TAPER if pupil.apodize else 0.0
    scale = 1 / math.sqrt(hh * ww * iris_power(
        tuple(shape), (lam0 / (hh * bin_), lam0 / (ww * bin_)), pupil.diameter, taper))
    # the emitters' spacing seen from the zone's centre over the bins': a surface of emitters
    # of intensity I shows I (one emitter per bin is the camera hologram's calibration)
    distance = float(np.linalg.norm(np.asarray(first.bounds).mean(0)
                                    - np.asarray(first.zone.centre)))
    spacing = 1 / (math.sqrt(first.point_density) * distance)
    groups = {}
    for c in colours + ([z_ch] if z_ch is not None else []):
        groups.setdefault(first.wavelengths[c], []).append(c)
    imager = PupilImage(rt, shape, bin=bin_, camera=fine, centre=middle)  # any wavelength's
    for chans in groups.values():
        if max(chans) + 1 - min(chans) != len(chans):
            raise InputError(f"a plate's channels at one wavelength must be neighbours; got "
                             f"{chans}")
    # each channel's pupil pitch, lens and scale: a look's planes in the order fields gives
    optics = {c: ((lam / (hh * bin_), lam / (ww * bin_)), 2 * np.pi / (lam0 if chromatic
                                                                     else lam), scale)
              for lam, chans in groups.items() for c in chans}
    looks = []
    for i in range(0, len(holos), batch):
        parts = [(h.object_wave, chans, lam) for h in holos[i:i + batch]
                 for lam, chans in groups.items()]
        waves = view.fields(parts, amplitude=spacing / bin_, progress=jobs.scaled(
            progress, i / len(holos), min(i + batch, len(holos)) / len(holos)))
        looks += imager.fold(waves, optics, same=_same(first, colours), partner=z_ch,
                             supersample=supersample, diameter=pupil.diameter,
                             focus=pupil.focus, taper=taper, keep_fine=keep_fine)
    return looks, shape


def _same(h: Hologram, colours) -> list:
    """The colour channels at the first colour's wavelength: the depth pair's first member
    is their sum (Eq. 26)."""
    lam0 = h.wavelengths[colours[0]]
    return [c for c in colours if h.wavelengths[c] == lam0]


def carrier_window(h: Hologram, camera: Camera, rotation, position, diameter):
    """(row0, row1, col0, col1) of a carrier plate's samples the pupil sees the objects
    through (the cone from its rim to the objects' box, cut to the camera's field of view),
    or None where that misses the samples."""
    r = diameter / 2
    rim = np.array([position + s * r * rotation[:, a] for a in (0, 1) for s in (-1, 1)]
                   + [position])
    lo, hi = cone_on_plate(h.bounds, rim)
    d = _corners(camera, rotation)
    t = -rim[:, None, 2:3] / np.minimum(d[None, :, 2:3], -1e-12)
    seen = (rim[:, None, :2] + t * d[None, :, :2]).reshape(-1, 2)
    lo, hi = np.maximum(lo, seen.min(0)), np.minimum(hi, seen.max(0))
    o, step = np.asarray(h.carrier.origin), np.array([h.pitch, h.carrier.row_pitch])
    c0, r0 = np.floor((lo - o) / step).astype(int) - 1
    c1, r1 = np.ceil((hi - o) / step).astype(int) + 2
    rows, cols = h.shape
    r0, r1, c0, c1 = max(r0, 0), min(r1, rows), max(c0, 0), min(c1, cols)
    return None if r1 <= r0 or c1 <= c0 else (int(r0), int(r1), int(c0), int(c1))


def _spectrum_box(h: Hologram, fine: Camera, rotation, position, pupil: Pupil, bin_, window):
    """((h, w) bins, (α, β) centre) of the pupil's spectrum: the directions the window's light
    arrives from, within the fine pixels' field of view, widened by the defocus blur of the
    objects' depths and EDGE_BINS."""
    least, greatest = fine.direction_range()
    r0, r1, c0, c1 = window
    x, y = h.carrier.coords(h.pitch, [r0, r1], [c0, c1])
    corners = np.array([[xx, yy, 0.0] for xx in x for yy in y])
    seen = (position - corners) / np.linalg.norm(position - corners, axis=1)[:, None] @ rotation
    lo = np.maximum(seen[:, :2].min(0), least)
    hi = np.minimum(seen[:, :2].max(0), greatest)
    depth = np.clip(-((box_corners(h.bounds) - position) @ rotation)[:, 2], 1e-9, None)
    blur = 0.0 if pupil.focus is None else \
        pupil.diameter * float(np.max(np.abs(1 / depth - 1 / pupil.focus)))
    margin = blur + EDGE_BINS * bin_
    lo, hi = lo - margin, hi + margin
    shape = tuple(grid.next_fast_len(math.ceil((hi[i] - lo[i]) / bin_) + 1) for i in (1, 0))
    return shape, tuple(map(float, (lo + hi) / 2))


def nyquist_supersample(h: Hologram, camera: Camera) -> int:
    """The supersampling at which a view of ``h`` through ``camera``'s lens samples its
    intensity at the Nyquist rate (:func:`holo_core.optics.pupil.intensity_supersample`;
    measured on the plate scene: 2 → 4 raises the PSNR by 1.6 dB at one look, 0.8 dB at
    four). A pinhole's pupil is sized to that already (λ/D is two fine pixels): 1."""
    if camera.fstop is None:
        return 1
    return intensity_supersample(camera.aperture_diameter, camera.pixel_angle(),
                                 min(h.wavelengths))


def _compose(looks, colours, z_ch, first: Hologram, camera, fine, pupil, *, supersample,
             composition, depth_estimate, centre, exposure, threshold, n) -> RenderResult:
    """The view from each iteration's images at the pixels (``looks``: :class:`~holo_core.
    optics.imaging.Folded`, radiance |A|² calibrated): with the depth partner and a known
    emitter density, as the camera hologram assembles it (:func:`holo_core.optics.imaging.
    assemble`, here of the pixels' means: the box filter is linear)."""
    lam0 = first.wavelengths[colours[0]]
    radiance = _radiance(looks, colours, composition, supersample)
    if z_ch is None:
        return _finish(radiance, None, None, first, camera, pupil, exposure, threshold, lam0)
    pair = (lam0, first.wavelengths[z_ch])
    cross = _summed([look.cross for look in looks])
    coverage = _summed([look.power[z_ch] for look in looks])
    coverage *= coverage.dtype.type(1 / len(looks))
    depth_of = {"same": _same(first, colours), "partner": z_ch, "estimate": depth_estimate,
                "wavelengths": pair, "centre": centre, "camera": camera,
                "supersample": supersample}
    if not first.point_density:  # bare points: no coverage to calibrate; alpha from luminance
        return _finish(radiance, _depth(looks, cross, **depth_of), None, first, camera, pupil,
                       exposure, threshold, lam0)
    exposure = 1.0 if exposure is None else exposure
    colour, alpha, depth, seen, cover = assemble(
        as_rgb(radiance), coverage, cross, camera=camera, supersample=1, wavelengths=pair,
        centre=centre, exposure=exposure)
    if depth_estimate == "brightest":
        depth = np.where(alpha > 0, _depth(looks, cross, **depth_of),
                         BACKGROUND_DEPTH).astype(np.float32)
    if not (np.isfinite(colour.min(initial=0)) and np.isfinite(colour.max(initial=0))):
        raise InputError(f"exposure must keep the view's pixels within float32 (finite); got "
                         f"{shown(exposure)}")
    limit = lam0 / pupil.diameter
    info = {"aperture_m": pupil.diameter, "focus_m": pupil.focus,
            "resolution_limit_rad": limit, "pixel_angle_rad": camera.pixel_angle(),
            "resolution_limit_px": limit / camera.pixel_angle(),
            "wavelengths_m": list(first.wavelengths), "exposure": exposure,
            "pupil_samples": list(n) if isinstance(n, tuple) else [n, n],
            "iterations": len(looks), "samples": len(looks),
            "speckle_contrast": _spread(looks, colours, z_ch, coverage)}
    log.info("render: aperture %.4g m, resolution limit λ/D = %.3g rad = %.2f px",
             pupil.diameter, limit, info["resolution_limit_px"])
    _check_sharp(first, camera, pupil.diameter, info["resolution_limit_px"])
    return RenderResult(rgb=colour, alpha=alpha, depth=depth, info=info, coverage=cover,
                        radiance=seen)


class SoftViewWarning(UserWarning):
    """A plate's view resolving less than a sharp view does: the camera's pixels are finer,
    or its pupil narrower, than those the plate was recorded for."""


def _check_sharp(h: Hologram, camera: Camera, diameter: float, spot_px: float) -> None:
    """Warn (:class:`SoftViewWarning`) when a view of the plate ``h`` through a pupil of
    ``diameter`` [m] resolves ``spot_px`` pixels, more than the half pixel of a sharp view."""
    if spot_px * SUPERSAMPLE <= 1 + SHARP_SLACK:
        return
    made = "" if h.zone is None or not h.zone.pixel else (
        f"; the plate was recorded for pixels of {h.zone.pixel:.3g} rad"
        + (f" through a pupil of {h.zone.pupil:.3g} m" if h.zone.pupil else ""))
    warnings.warn(f"this view resolves {spot_px:.2g} px where a sharp view resolves "
                  f"{1 / SUPERSAMPLE:g}: its pixels are {camera.pixel_angle():.3g} rad through "
                  f"a pupil of {diameter:.3g} m{made}; it looks soft: record the plate for "
                  f"this camera's pixels and pupil", SoftViewWarning, stacklevel=3)


def _radiance(looks, colours, composition, supersample) -> np.ndarray:
    """(H, W, colours) radiance at the pixels: the looks' mean of the pixels' means, or the
    pixels' mean of the looks' maximum at the fine pixels (Sect. VII-E)."""
    if composition == "mean":
        first = looks[0].power[colours[0]]
        radiance = np.empty(first.shape + (len(colours),), first.dtype)
        for i, c in enumerate(colours):  # summed where it is kept: no stacked copies
            _summed([look.power[c] for look in looks], out=radiance[..., i])
        radiance *= radiance.dtype.type(1 / len(looks))
        return radiance
    return speckle.downsample(speckle.compose(
        [np.stack([np.abs(look.fine[c]) ** 2 for c in colours], -1) for look in looks],
        composition), supersample)


def _summed(images, out=None) -> np.ndarray:
    """The sum of ``images`` (each (H, W)), added in place into ``out`` or a copy of the first."""
    if out is None:
        out = np.copy(images[0])
    else:
        np.copyto(out, images[0])
    for image in images[1:]:
        out += image
    return out


def _spread(looks, colours, z_ch, coverage) -> float:
    """The speckle contrast of the mean colour over the iterations: the spread of each
    iteration's colour (radiance over coverage) over √n, median over the pixels whose mean
    ``coverage`` is 0.75 or more; NaN for a single iteration."""
    n = len(looks)
    solid = np.flatnonzero(coverage >= 0.75)
    if n < 2 or not solid.size:
        return float("nan")
    lum = np.empty((n, solid.size), np.float32)  # each look's colour at the solid pixels
    for k, look in enumerate(looks):
        colour = np.take(look.power[colours[0]], solid)
        for c in colours[1:]:
            colour += np.take(look.power[c], solid)
        lum[k] = colour / (len(colours) * np.maximum(np.take(look.power[z_ch], solid), 0.05))
    mean, spread = lum.mean(0), lum.std(0) / np.float32(math.sqrt(n))
    return float(np.median(spread / np.maximum(mean, 1e-30)))


class OutsideZoneWarning(UserWarning):
    """A camera outside the plate's viewing zone: its view may be cut off or soft (the
    message names the zone)."""


def _check_zone(h: Hologram, camera: Camera, position, diameter) -> None:
    """Warn (:class:`OutsideZoneWarning`) when the pupil (``position`` [m] in the plate's
    frame, ``diameter`` [m]) reaches beyond the hologram's viewing zone, naming the zone."""
    if h.zone is None:
        return
    beyond = h.zone.distance_outside(position, diameter / 2)
    if beyond > 1e-9:
        world = (np.asarray(h.plate) @ np.append(h.zone.centre, 1.0))[:3]
        warnings.warn(f"the camera's pupil reaches {beyond:.3g} m beyond the plate's viewing "
                      f"zone, {h.zone.describe()} (centred at ({world[0]:.4g}, {world[1]:.4g}, "
                      f"{world[2]:.4g}) m in the world): the plate was recorded for views from "
                      f"there, and this one may be cut off or soft; record the plate for a zone "
                      f"that holds the camera", OutsideZoneWarning, stacklevel=3)


class NoDepthWarning(UserWarning):
    """A view of a hologram without the depth partner: its depth pass is the background."""


class EmptyViewWarning(UserWarning):
    """No light of the hologram reaches the camera: the view is black (the message says why)."""


MAX_SUPERSAMPLE = 16  # render_view's largest supersampling factor per axis


def _unseen(h: Hologram, rotation, position) -> str | None:
    """Why no light of ``h`` can reach a camera at ``position`` [m] with axes ``rotation``
    (both in the plate's frame, :func:`camera_in_plate`), or None. The light leaves every
    plate point within the object wave's cone (sin θ = band, else the pitch's Nyquist
    angle), and the spectrum rotation to the camera's plane bridges a limited tilt."""
    wavelength = max(h.wavelengths)
    nyquist = min(1.0, wavelength / (2 * h.pitch))
    zone = math.asin(min(h.band, nyquist) if h.band else nyquist)
    width, height = h.size
    lateral = np.maximum(np.abs(position[:2]) - [width / 2, height / 2], 0)
    angle = math.atan2(float(np.hypot(*lateral)), position[2])  # from the nearest plate point
    if angle > zone:
        return (f"the camera is {math.degrees(angle):.1f}° off the plate's normal, seen from "
                f"the plate's nearest point; the hologram's light leaves within "
                f"{math.degrees(zone):.1f}° of it")
    tilt = math.acos(float(np.clip(rotation[2, 2], -1, 1)))
    reach = tilt_reach(wavelength, h.pitch, h.pitch)
    if tilt >= reach:
        return (f"the camera's view axis is {math.degrees(tilt):.1f}° off the plate's normal; "
                f"its sampling (pitch {h.pitch:.3g} m, λ = {wavelength:.3g} m) carries light "
                f"to planes tilted by less than {math.degrees(reach):.1f}°")
    return None


PIXEL_BYTES = 96  # host bytes per fine pixel and iteration while rendering (fields, images)
HOLOGRAM_SAMPLE_BYTES = 96  # per hologram sample: its reconstructed and carried complex fields


def _check_settings(holos, camera: Camera, supersample, exposure, threshold) -> None:
    """:class:`InputError` for settings out of range, holograms that are not of one scene, or
    a view too large for the memory."""
    if not all(isinstance(h, Hologram) for h in holos):
        raise InputError("holograms must be Hologram objects (read_hologram, record_points)")
    if exposure is not None:
        validate.positive("exposure", exposure)
    threshold = validate.finite("opacity_threshold", threshold)
    if not 0 <= threshold <= 1:
        raise InputError(f"opacity_threshold must be in [0, 1]; got {shown(threshold)}")
    first = holos[0]
    for i, h in enumerate(holos[1:], 1):
        for name in ("wavelengths", "pitch", "shape", "channels"):
            if getattr(h, name) != getattr(first, name):
                raise InputError(f"holograms[{i}] has {name} {getattr(h, name)!r}, holograms[0] "
                                 f"{getattr(first, name)!r}: iterations must be of one recording")
        if not np.allclose(h.plate, first.plate, rtol=0, atol=1e-9):
            raise InputError(f"holograms[{i}] lies on another plate pose than holograms[0]: "
                             f"iterations must be of one recording")
    w, h = camera.resolution
    memory.check_host(f"a {w}x{h} view at supersample {supersample}",
                      PIXEL_BYTES * w * h * supersample**2 * (len(first.wavelengths) + 1))
    if first.encoding != "complex":  # reconstructed whole; a complex plate's window: below
        memory.check_host(f"the hologram's {first.shape[1]}x{first.shape[0]} fields",
                          HOLOGRAM_SAMPLE_BYTES * np.prod(first.shape))


def _depth(looks, cross, *, same, partner, estimate, wavelengths, centre, camera: Camera,
           supersample) -> np.ndarray:
    """Planar depth [m] from the depth pair's cross image u1·conj(u2): of the pixels' means
    summed over the iterations (``cross``: the intensity-weighted consensus), or per fine
    pixel from the brightest iteration (their ``fine`` images, ``same`` summed into u1)."""
    def ranges(c):
        return depth_mod.from_cross_spectrum(c, wavelengths=wavelengths, centre=centre,
                                             focus=None)

    def planar(ray, cam):
        tx, ty = cam.pixel_tangents()
        return ray / np.sqrt(1 + tx * tx + ty * ty)

    if estimate == "consensus":
        return planar(ranges(cross), camera)
    first = [sum(look.fine[c] for c in same) for look in looks]
    ray, bright = depth_mod.keep_brightest(
        [ranges(u * np.conj(look.fine[partner])) for u, look in zip(first, looks)],
        [np.abs(u) for u in first])
    return speckle.pick_brightest(planar(ray, _supersampled(camera, supersample)), bright,
                                  supersample)


def plane_depth(h: Hologram, camera: Camera, z: float) -> np.ndarray:
    """The planar depth [m] (along the view axis, as Blender's Depth pass) at which each
    pixel's ray meets the plane ``z`` [m] of the hologram's frame; the background's where it
    never does."""
    rotation, position = camera_in_plate(h, camera)
    tx, ty = camera.pixel_tangents()
    direction = np.stack([tx, ty, -np.ones_like(tx)], -1) @ np.asarray(rotation).T
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (z - position[2]) / direction[..., 2]
    return np.where(np.isfinite(t) & (t > 0), t, BACKGROUND_DEPTH)


def _supersampled(camera: Camera, s: int) -> Camera:
    if s == 1:
        return camera
    w, h = camera.resolution
    return replace(camera, resolution=(w * s, h * s))


def _corners(camera: Camera, rotation, margin=VIEW_MARGIN) -> np.ndarray:
    """The directions (4, 3) [plate frame] of the image's corners, ``margin`` of its size
    beyond them (a defocused pixel gathers light from around its ray)."""
    w, h = camera.resolution
    rows, cols = np.array([-1, -1, 1, 1]) * margin * h, np.array([-1, 1, -1, 1]) * margin * w
    tx, ty = camera.pixel_tangents(rows=rows + np.array([0, 0, h, h]),
                                   cols=cols + np.array([0, w, 0, w]))
    return np.stack([tx, ty, -np.ones(4)], -1) @ np.asarray(rotation).T


def _centre_distance(h: Hologram, camera: Camera) -> float:
    """Distance [m] from the camera to the objects' bounding-box centre (the depth range's
    centre, Eq. 30)."""
    centre = np.asarray(h.plate, np.float64) @ np.append(np.asarray(h.bounds).mean(0), 1.0)
    return float(np.linalg.norm(centre[:3] - camera.position))


def _finish(radiance, ray, coverage, h: Hologram, camera, pupil, exposure, threshold, lam0):
    if not np.isfinite(radiance).all() or (ray is not None and not np.isfinite(ray).all()):
        peak = float(h.intensity.max() if h.intensity is not None else  # never a NaN view:
                     np.abs(h.object_wave).max() ** 2)  # say which numbers overflowed
        scale = min(h.reference_amplitudes, default=1.0) ** 2
        raise InputError(f"intensity must stay within float32 arithmetic through the view: "
                         f"this hologram's reaches {peak:.3g}, {peak / scale:.3g} times its "
                         f"reference intensity |R|² (a recording holds far less than 1e12 "
                         f"times), and the view overflowed")
    lum = radiance.mean(-1)
    ref = float(np.percentile(lum, 99.5))
    if exposure is None:
        exposure = 1 / h.point_density if h.point_density else (1 / ref if ref > 0 else 1.0)
    rgb = radiance * exposure
    if np.abs(rgb).max(initial=0) > np.finfo(np.float32).max:  # a view of inf pixels
        raise InputError(f"exposure must keep the view's pixels within float32: at most "
                         f"{np.finfo(np.float32).max / np.abs(radiance).max():.3g} for this "
                         f"view; got {shown(exposure)}")
    rgb = as_rgb(rgb)  # one, two, four or more channels: the stated colours
    if coverage is not None:  # geometric: half covered at a silhouette edge, whatever the colour
        alpha = (coverage > threshold).astype(np.float32)
    else:  # unknown emitter density: relative to the brightest pixels
        alpha = (lum > threshold * ref).astype(np.float32) if ref > 0 else np.zeros_like(lum)
    depth = np.full(lum.shape, BACKGROUND_DEPTH, np.float32)
    plane = stated_plane(h)
    if ray is None and plane is not None:  # an acquired hologram's objects: one plane
        ray = plane_depth(h, camera, plane)
    if ray is not None:
        depth = np.where(alpha > 0, ray, BACKGROUND_DEPTH).astype(np.float32)
    limit = lam0 / pupil.diameter
    info = {"aperture_m": pupil.diameter, "focus_m": pupil.focus,
            "resolution_limit_rad": limit, "pixel_angle_rad": camera.pixel_angle(),
            "resolution_limit_px": limit / camera.pixel_angle(),
            "wavelengths_m": list(h.wavelengths), "exposure": exposure}
    log.info("render: aperture %.4g m, resolution limit λ/W = %.3g rad = %.2f px",
             pupil.diameter, limit, info["resolution_limit_px"])
    return RenderResult(rgb=rgb.astype(np.float32), alpha=alpha, depth=depth, info=info)


