"""Image generation: a camera anywhere in front of the hologram (Sect. VII).

Per wavelength: the reconstructed wave (Sect. VI) is carried to the camera's aperture plane by
tilt plus offset propagation (Sect. IV-D); the aperture is cut out as a disc, apodized by the
cosine window of Fig. 9 and, for a thin lens, multiplied by Eq. 24's phase; its angular
spectrum is then read at each pixel's direction cosines (Eq. 22) by bilinear weighting. The
image holds the complex amplitude A(α/λ, β/λ) [field·m²] of the plane wave from each pixel's
direction; the radiance is |A|² / (λ²·∫w²) (power per aperture area and projected solid
angle), so a surface of point emitters of intensity I and density σ shows radiance σ·I.
"""

from __future__ import annotations

import logging
import math
import warnings
from dataclasses import replace

import numpy as np

from .. import jobs, memory, validate
from ..opencl import get_runtime
from ..opencl.arrays import cached, embed, empty
from ..optics import depth as depth_mod
from ..optics import speckle
from ..optics.pupil import PINHOLE_SAMPLES, Pupil, camera_pupil
from ..propagation import grid
from ..propagation.convolution import convolve
from ..propagation.tilt import propagate_to_plane, tilt_reach
from ..scene.camera import Camera
from ..scene.hologram import Hologram
from ..validate import InputError
from ..view import BACKGROUND_DEPTH, RenderResult
from .reconstruct import reconstruct

log = logging.getLogger(__name__)
SPECTRUM_OVERSAMPLING = 4   # spectrum samples per λ/D (the aperture's resolution), at least
MAX_SPECTRUM = 4096         # largest FFT of the aperture per axis
COVERAGE_RADIUS = 1  # the coverage's speckle is averaged over (2r+1)² pixels before alpha


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
    stored object wave (``source='object_wave'``, the ideal reconstruction)."""
    if validate.choice("source", source, ("hologram", "object_wave")) == "object_wave":
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


def image_wave(wave, *, wavelength, pitch, rotation, position, camera: Camera,
               aperture: Pupil) -> tuple[np.ndarray, float]:
    """Complex image (H, W) [field·m²] of a plate wave seen by ``camera``, and the aperture's
    ∫w² [m²] (for radiance).

    ``wave`` is the field on the plate (z = 0) at ``pitch`` [m], ``wavelength`` [m];
    ``rotation``, ``position``: the camera in the plate's frame (see :func:`camera_in_plate`).
    """
    at_camera = camera_field(wave, wavelength=wavelength, pitch=pitch, rotation=rotation,
                             position=position)
    return pupil_image(at_camera, wavelength=wavelength, pitch=pitch, camera=camera,
                       aperture=aperture)


def camera_field(wave, *, wavelength, pitch, rotation, position) -> np.ndarray:
    """The plate wave carried to the camera's aperture plane (tilt plus offset propagation),
    on the host, centred on the aperture."""
    at_camera = propagate_to_plane(wave, wavelength=wavelength, pitch=pitch, rotation=rotation,
                                   position=position)
    return at_camera if isinstance(at_camera, np.ndarray) else at_camera.get()


def pupil_image(at_camera, *, wavelength, pitch, camera: Camera,
                aperture: Pupil) -> tuple[np.ndarray, float]:
    """The image of the field at the camera (:func:`camera_field`) through ``aperture``: its
    angular spectrum read at the pixels' direction cosines (Eq. 22), and ∫w² [m²]."""
    pupil, weight = _pupil(at_camera, wavelength, pitch, aperture)
    return _spectrum_at_pixels(pupil, wavelength, pitch, camera, aperture), weight


def depth_aperture(camera: Camera, hologram: Hologram, wavelength: float,
                   centre: float) -> Pupil:
    """The pupil the depth pair (λ2 = ``wavelength`` [m]) is imaged through: a lens focused on
    the objects' centre ``centre`` [m] away, as
    wide as alias-free sampling of the pixels allows (at most half the plate). Like a
    renderer's Depth pass it ignores the camera's depth of field, and its small spot keeps few
    surface points in each pixel's phase average (Sect. VII-C)."""
    alias_free = wavelength / (PINHOLE_SAMPLES * camera.pixel_angle())
    return Pupil(diameter=min(alias_free, min(hologram.size) / 2), focus=centre)


def _pupil(field, wavelength, pitch, aperture: Pupil):
    """The aperture disc cut from the field at the camera, windowed and lensed (Eq. 24)."""
    n_full = field.shape[0]
    n = min(n_full, math.ceil(aperture.diameter / pitch) + 1)
    n += (n_full - n) % 2  # keep the crop centred on the camera exactly
    if n == n_full and aperture.diameter > n_full * pitch:
        validate.warn_sampling(f"the aperture ({aperture.diameter:.4g} m) is wider than the "
                               f"propagated field ({n_full * pitch:.4g} m); it is cut there")
    r0, c0 = (field.shape[0] - n) // 2, (field.shape[1] - n) // 2
    crop = field[r0:r0 + n, c0:c0 + n].astype(np.complex128)
    x = grid.coords(n, pitch)
    rho = np.hypot(x[None, :], x[:, None])
    radius = aperture.diameter / 2
    w = np.where(rho <= radius, np.cos(np.pi * rho / aperture.diameter)
                 if aperture.apodize else 1.0, 0.0)
    if not w.any():
        raise InputError(f"the camera's aperture ({aperture.diameter:.3g} m) falls between the "
                         f"field's samples ({pitch:.3g} m apart): this view cannot be formed; "
                         f"give the camera more pixels or an f-stop, or record a finer pitch")
    if aperture.focus is not None:
        k = 2 * np.pi / (aperture.lens_wavelength or wavelength)
        f = aperture.focus
        w = w * np.exp(-1j * np.remainder(k * np.sqrt(rho * rho + f * f), 2 * np.pi))
    return crop * w, float(np.sum(np.abs(w) ** 2) * pitch * pitch)


def _spectrum_at_pixels(pupil, wavelength, pitch, camera: Camera, aperture: Pupil):
    """The pupil's continuous Fourier transform at each pixel's frequency (α/λ, β/λ): an FFT
    zero-padded to n×n, fine enough for bilinear reading, read on the device."""
    n_a = pupil.shape[0]
    need = max(SPECTRUM_OVERSAMPLING * aperture.diameter / pitch,
               2 * wavelength / (pitch * camera.pixel_angle()), 2 * n_a)
    n = grid.next_fast_len(min(MAX_SPECTRUM, math.ceil(need)))
    n = max(n, n_a + (n - n_a) % 2)
    c0 = (n - n_a) // 2
    rt = get_runtime()
    work = rt.scratch("image-spectrum", (n, n))
    embed(rt, work, rt.to_device(pupil, np.complex64), c0, c0)
    rt.fft.forward(work, (c0, c0 + n_a))
    alpha, beta, _ = camera.direction_cosines()
    bins = [rt.to_device(a * (n * pitch / wavelength), np.float32) for a in (alpha, beta)]
    out = empty(rt, alpha.shape)
    rt.kernel("spectral", "read_spectrum", rt.real_options)(
        rt.queue, (alpha.size,), None, out.data, work.data, np.int32(n), *(b.data for b in bins),
        rt.real((c0 + (n_a - 1) / 2) / n), np.float32(pitch * pitch))
    return out.get()


@validate.scale_free()
@np.errstate(over="ignore", invalid="ignore")  # an overflow is refused at the end (_finish)
def render_view(holograms, camera: Camera, *, aperture: Pupil | None = None, apodize=True,
                chromatic=True, composition="mean", supersample=1, exposure=None,
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
    supersample : int
        Render at this many times the resolution, then average blocks (speckle reduction by
        spatial low-pass and downsampling, Sect. VII-E).
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
    supersample = validate.integer("supersample", supersample, 1, MAX_SUPERSAMPLE)
    _check_settings(holos, camera, supersample, exposure, opacity_threshold)
    fine = _supersampled(camera, supersample)
    colours, z_ch = first.colour_channels(), first.depth_channel()
    if z_ch is None:
        warnings.warn("the hologram has no depth channel (record it with depth=True): the "
                      f"view's depth is the background ({BACKGROUND_DEPTH:g} m) everywhere, so a "
                      "Z-combine puts it behind every surface", NoDepthWarning, stacklevel=2)
    lam0 = first.wavelengths[colours[0]]
    centre = _centre_distance(first, camera)
    pupil = aperture or camera_pupil(fine, lam0, centre, apodize=apodize)
    chromatic_pupil = replace(pupil, lens_wavelength=lam0) if chromatic and pupil.focus else pupil
    rotation, position = camera_in_plate(first, camera)
    unseen = _unseen(first, rotation, position)
    if unseen:  # a black view, said aloud (an animation's camera may pass out of the zone)
        warnings.warn(f"the view is black: {unseen}", EmptyViewWarning, stacklevel=2)
        return _finish(np.zeros(camera.resolution[::-1] + (len(colours),)), None, None, first,
                       camera, pupil, exposure, opacity_threshold, lam0)
    depth_pupil = None
    if z_ch is not None:
        depth_pupil = depth_aperture(fine, first, first.wavelengths[z_ch], centre)
        pair_wavelengths = (lam0, first.wavelengths[z_ch])
        depth_sources = [c for c in colours if first.wavelengths[c] == lam0] + [z_ch]
    channels = colours + ([z_ch] if z_ch is not None else [])
    intensities, crosses, brightness, coverage = [], [], [], []
    for i, h in enumerate(holos):
        done = jobs.scaled(progress, i / len(holos), (i + 1) / len(holos))
        planes, depth_fields = [], {}
        for n, c in enumerate(channels):
            lam = h.wavelengths[c]
            at = camera_field(plate_wave(h, c, source=source), wavelength=lam, pitch=h.pitch,
                              rotation=rotation, position=position)
            if c != z_ch:
                u, area = pupil_image(at, wavelength=lam, pitch=h.pitch, camera=fine,
                                      aperture=chromatic_pupil)
                planes.append(np.abs(u) ** 2 / (lam * lam * area))
            if depth_pupil is not None and c in depth_sources:  # imaging is linear: sum first
                pair = int(c == z_ch)
                depth_fields[pair] = depth_fields.get(pair, 0) + at
            jobs.report(done, n + 1, len(channels))
        intensities.append(np.stack(planes, -1))
        if depth_pupil is not None:
            (u1, _), (u2, area) = (pupil_image(depth_fields[p], wavelength=pair_wavelengths[p],
                                               pitch=h.pitch, camera=fine, aperture=depth_pupil)
                                   for p in (0, 1))
            crosses.append(u1 * np.conj(u2))
            brightness.append(np.abs(u1))
            # the depth partner's emitters have unit intensity: radiance = density × coverage
            coverage.append(np.abs(u2) ** 2 / (pair_wavelengths[1] ** 2 * area))
    radiance = speckle.compose(intensities, composition)
    ray = None
    if crosses:
        ray = _depth(crosses, brightness, estimate=depth_estimate, wavelengths=pair_wavelengths,
                     centre=centre, focus=depth_pupil.focus, camera=camera, supersample=supersample)
    radiance = speckle.downsample(radiance, supersample)
    if coverage and first.point_density:
        coverage = speckle.downsample(np.mean(coverage, 0)[..., None], supersample)[..., 0]
        coverage = speckle.box_mean(coverage, COVERAGE_RADIUS) / first.point_density
    else:
        coverage = None
    return _finish(radiance, ray, coverage, first, camera, pupil, exposure, opacity_threshold,
                   lam0)


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
        raise InputError(f"opacity_threshold must be in [0, 1]; got {threshold!r}")
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
    memory.check_host(f"the hologram's {first.shape[1]}x{first.shape[0]} fields",
                      HOLOGRAM_SAMPLE_BYTES * np.prod(first.shape))


def _depth(crosses, brightness, *, estimate, wavelengths, centre, focus, camera: Camera,
           supersample) -> np.ndarray:
    """Planar depth [m] from the per-iteration cross images u1·conj(u2) of the depth pair."""
    def ranges(cross):
        return depth_mod.from_cross_spectrum(cross, wavelengths=wavelengths, centre=centre,
                                             focus=focus)

    def planar(ray, cam):
        tx, ty = cam.pixel_tangents()
        return ray / np.sqrt(1 + tx * tx + ty * ty)

    if estimate == "consensus":
        return planar(ranges(speckle.downsample(sum(crosses), supersample)), camera)
    ray, bright = depth_mod.keep_brightest([ranges(c) for c in crosses], brightness)
    return speckle.pick_brightest(planar(ray, _supersampled(camera, supersample)), bright,
                                  supersample)


def _supersampled(camera: Camera, s: int) -> Camera:
    if s == 1:
        return camera
    w, h = camera.resolution
    return replace(camera, resolution=(w * s, h * s))


def _centre_distance(h: Hologram, camera: Camera) -> float:
    """Distance [m] from the camera to the objects' bounding-box centre (the depth range's
    centre, Eq. 30)."""
    centre = np.asarray(h.plate, np.float64) @ np.append(np.asarray(h.bounds).mean(0), 1.0)
    return float(np.linalg.norm(centre[:3] - camera.position))


def _finish(radiance, ray, coverage, h: Hologram, camera, pupil, exposure, threshold, lam0):
    if not np.isfinite(radiance).all() or (ray is not None and not np.isfinite(ray).all()):
        peak = float(h.intensity.max())  # never a NaN view: say which numbers overflowed
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
    if rgb.shape[-1] == 1:
        rgb = np.repeat(rgb, 3, -1)
    if np.abs(rgb).max(initial=0) > np.finfo(np.float32).max:  # a view of inf pixels
        raise InputError(f"exposure must keep the view's pixels within float32: at most "
                         f"{np.finfo(np.float32).max / np.abs(radiance).max():.3g} for this "
                         f"view; got {exposure!r}")
    if coverage is not None:  # geometric: half covered at a silhouette edge, whatever the colour
        alpha = (coverage > threshold).astype(np.float32)
    else:  # unknown emitter density: relative to the brightest pixels
        alpha = (lum > threshold * ref).astype(np.float32) if ref > 0 else np.zeros_like(lum)
    depth = np.full(lum.shape, BACKGROUND_DEPTH, np.float32)
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


