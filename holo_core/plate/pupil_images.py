"""Each look's images at the pixels from the plate's light at the camera's pupil: the view's
two routes, both ending in the camera hologram's own pupil → image stage
(:class:`~holo_core.optics.imaging.PupilImage`).

- A carrier plate (:func:`carrier_looks`): the window's samples turned onto the pupil's
  carrier, decimated and summed onto the spectrum's bins
  (:class:`~holo_core.plate.to_pupil.CarrierPupil`), every look and channel in one pass.
- A full-band plate (:func:`full_band_looks`): each channel's window carried to the pupil by
  the angular spectrum and rotated onto the camera's plane
  (:func:`~holo_core.plate.to_pupil.field_at_pupil`); an intensity hologram reconstructed
  first (:func:`plate_wave`).

Radiance is |A|² / (σ·b²), b = λ/L the direction cosines a bin of the pupil's spectrum spans
and σ the emitters per m² of surface, so a surface of emitters of intensity I shows I.
"""

from __future__ import annotations

import math

import numpy as np

from .. import jobs, memory, validate
from ..opencl import get_runtime
from ..opencl.arrays import cached
from ..optics.imaging import IRIS_TAPER, PupilImage, fold_images, iris_power
from ..optics.pupil import Pupil
from ..propagation import grid
from ..propagation.convolution import convolve
from ..scene.camera import Camera
from ..scene.hologram import Hologram
from ..scene.plate import box_corners
from ..validate import InputError
from .composition import same_wavelength
from .reconstruction import reconstruct
from .to_pupil import CarrierPupil, field_at_pupil
from .window import (
    carrier_window,
    image_corners,
    lit_diameter,
    overlaps,
    plate_window,
    pupil_grid,
    window_of,
)

HOLOGRAM_SAMPLE_BYTES = 96  # per hologram sample: its reconstructed and carried complex fields
EDGE_BINS = 8  # the pupil's spectrum reaches this many bins beyond the image and its blur
SPREAD_PLANES = 8  # the looks' channels spread onto a view's bins in one pass, at most


@validate.scale_free()
def plate_wave(hologram: Hologram, channel: int, *, source="hologram"):
    """The object wave leaving the hologram for one channel, complex64 (H, W) (NumPy, or a
    device array that the propagation takes without a host round trip): R'·H' with the
    DC term suppressed and the band outside the recorded cone removed (Sect. VI), or the
    stored object wave (``source='object_wave'``, the ideal reconstruction). A complex
    hologram's samples are the object wave."""
    if (
        validate.choice("source", source, ("hologram", "object_wave")) == "object_wave"
        or hologram.encoding == "complex"
    ):
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


def carrier_looks(
    holos,
    camera: Camera,
    fine: Camera,
    pupil: Pupil,
    rotation,
    position,
    colours,
    z_ch,
    *,
    supersample,
    chromatic=True,
    keep_fine=False,
    progress=None,
    plans=None,
):
    """(each look's images at the pixels (:meth:`~holo_core.optics.imaging.PupilImage.fold`),
    the pupil's samples (h, w)) of plates stored against their zone's carrier
    (:class:`~holo_core.plate.to_pupil.CarrierPupil`); (None, None) where the pupil sees the
    objects beside the plate. ``plans`` (a :class:`~holo_core.plate.view_plans.ViewPlans`):
    the spectrum's size and the decimation's taps rounded up with its slack, the pupil's
    plans kept for a camera seen again."""
    first = holos[0]
    window = carrier_window(
        first, position, rotation, pupil.diameter, image_corners(camera, rotation)
    )
    if window is None:
        return None, None
    lam0 = first.wavelengths[colours[0]]
    bin_ = min(camera.pixel_angle() / supersample, lam0 / pupil.diameter)
    shape, middle = _spectrum_box(
        first,
        fine,
        rotation,
        position,
        pupil,
        bin_,
        window,
        fast_len=grid.next_fast_len if plans is None else plans.spectrum_len,
    )
    rt = get_runtime()
    channels = len(colours) + (z_ch is not None)
    batch = max(1, SPREAD_PLANES // channels)  # looks spread onto the bins in one pass
    planes, bins = batch * channels, math.prod(shape)
    # per plane and bin: the spread grid and the padded spectrum (2×2 oversampled), the pupil
    fine_bytes = 8.0 * planes * math.prod(fine.resolution) if keep_fine else 0.0
    memory.check_device(
        rt,
        f"the {shape[1]}x{shape[0]} pupil's spectra of {planes} planes",
        72.0 * planes * bins + fine_bytes,
        32.0 * planes * bins,
    )
    geometry = dict(
        position=position,
        rotation=rotation,
        diameter=pupil.diameter,
        bin=bin_,
        shape=shape,
        window=window,
        centre=middle,
    )
    view = (
        CarrierPupil(rt, first, **geometry)
        if plans is None
        else plans.carrier_pupil(rt, first, geometry)
    )
    hh, ww = shape
    taper = IRIS_TAPER if pupil.apodize else 0.0
    scale = 1 / math.sqrt(
        hh
        * ww
        * iris_power(tuple(shape), (lam0 / (hh * bin_), lam0 / (ww * bin_)), pupil.diameter, taper)
    )
    # the emitters' spacing seen from the zone's centre over the bins': a surface of emitters
    # of intensity I shows I (one emitter per bin is the camera hologram's calibration)
    distance = float(
        np.linalg.norm(np.asarray(first.bounds).mean(0) - np.asarray(first.zone.centre))
    )
    spacing = 1 / (math.sqrt(first.point_density) * distance)
    groups = {}
    for c in colours + ([z_ch] if z_ch is not None else []):
        groups.setdefault(first.wavelengths[c], []).append(c)
    imager = PupilImage(rt, shape, bin=bin_, camera=fine, centre=middle)  # any wavelength's
    for chans in groups.values():
        if max(chans) + 1 - min(chans) != len(chans):
            raise InputError(
                f"a plate's channels at one wavelength must be neighbours; got {chans}"
            )
    # each channel's pupil pitch, lens and scale: a look's planes in the order fields gives
    optics = {
        c: ((lam / (hh * bin_), lam / (ww * bin_)), 2 * np.pi / (lam0 if chromatic else lam), scale)
        for lam, chans in groups.items()
        for c in chans
    }
    looks = []
    for i in range(0, len(holos), batch):
        parts = [
            (h.object_wave, chans, lam)
            for h in holos[i : i + batch]
            for lam, chans in groups.items()
        ]
        waves = view.fields(
            parts,
            amplitude=spacing / bin_,
            progress=jobs.scaled(progress, i / len(holos), min(i + batch, len(holos)) / len(holos)),
        )
        looks += imager.fold(
            waves,
            optics,
            same=same_wavelength(first, colours),
            partner=z_ch,
            supersample=supersample,
            diameter=pupil.diameter,
            focus=pupil.focus,
            taper=taper,
            keep_fine=keep_fine,
        )
    return looks, shape


def _spectrum_box(
    h: Hologram,
    fine: Camera,
    rotation,
    position,
    pupil: Pupil,
    bin_,
    window,
    fast_len=grid.next_fast_len,
):
    """((h, w) bins, (α, β) centre) of the pupil's spectrum: the directions the window's light
    arrives from, within the fine pixels' field of view, widened by the defocus blur of the
    objects' depths and EDGE_BINS; each side ``fast_len`` of the bins it needs."""
    least, greatest = fine.direction_range()
    r0, r1, c0, c1 = window
    x, y = h.carrier.coords(h.pitch, [r0, r1], [c0, c1])
    corners = np.array([[xx, yy, 0.0] for xx in x for yy in y])
    seen = (position - corners) / np.linalg.norm(position - corners, axis=1)[:, None] @ rotation
    lo = np.maximum(seen[:, :2].min(0), least)
    hi = np.minimum(seen[:, :2].max(0), greatest)
    depth = np.clip(-((box_corners(h.bounds) - position) @ rotation)[:, 2], 1e-9, None)
    blur = (
        0.0
        if pupil.focus is None
        else pupil.diameter * float(np.max(np.abs(1 / depth - 1 / pupil.focus)))
    )
    margin = blur + EDGE_BINS * bin_
    lo, hi = lo - margin, hi + margin
    shape = tuple(fast_len(math.ceil((hi[i] - lo[i]) / bin_) + 1) for i in (1, 0))
    return shape, tuple(map(float, (lo + hi) / 2))


def full_band_looks(
    holos,
    camera: Camera,
    fine: Camera,
    pupil: Pupil,
    rotation,
    position,
    colours,
    z_ch,
    *,
    supersample,
    chromatic=True,
    keep_fine=False,
    source="hologram",
    progress=None,
):
    """(each look's images at the pixels, the pupil grid's n) of full-band plates: each
    channel's window (:func:`~holo_core.plate.window.plate_window`, of the part of the pupil
    in light) carried to the pupil (:func:`~holo_core.plate.to_pupil.field_at_pupil`) and
    imaged by the camera hologram's stage; (None, None) where the pupil sees the objects
    beside the plate. ``source`` as for :func:`plate_wave`."""
    first = holos[0]
    lam0 = first.wavelengths[colours[0]]
    lit = lit_diameter(first, position, rotation, pupil.diameter)  # the pupil's part in light
    window = plate_window(first, position, rotation, lit, image_corners(camera, rotation))
    if not overlaps(first, window):
        return None, None
    r0, r1, c0, c1 = window
    memory.check_host(
        f"the plate's {c1 - c0}x{r1 - r0} window", HOLOGRAM_SAMPLE_BYTES * (r1 - r0) * (c1 - c0)
    )
    channels = colours + ([z_ch] if z_ch is not None else [])
    n, d = pupil_grid(
        first, rotation, lit, pupil.focus, min(first.wavelengths[c] for c in channels)
    )
    rt = get_runtime()
    memory.check_device(rt, f"the {n}x{n} pupil's spectrum", 40.0 * n * n, 32.0 * n * n)
    taper = IRIS_TAPER if pupil.apodize else 0.0
    scale = 1 / math.sqrt(n * n * _iris_sum(n, d, pupil.diameter, taper, lit))
    imagers = {
        lam: PupilImage(rt, (n, n), bin=lam / (n * d), camera=fine)
        for lam in {first.wavelengths[c] for c in channels}
    }
    # radiance |A|² / (σ·b²): a surface of emitters of intensity I, σ per m², shows I
    density = first.point_density or 1.0
    looks = []
    same = same_wavelength(first, colours)
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
            at = field_at_pupil(
                u, window, h, wavelength=lam, position=position, rotation=rotation, n=n, pitch=d
            )
            lens = lam0 if chromatic else lam
            images[c] = imagers[lam].image(
                rt.to_device(at, np.complex64),
                pitch=(d, d),
                diameter=pupil.diameter,
                focus=pupil.focus,
                taper=taper,
                lens_k=2 * np.pi / lens,
                scale=scale * n * d / (lam * math.sqrt(density)),
            )
            jobs.report(done, m + 1, len(channels))
        looks.append(
            fold_images(
                images, same=same, partner=z_ch, supersample=supersample, keep_fine=keep_fine
            )
        )
    return looks, n


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
