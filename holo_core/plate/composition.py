"""The view's composition: each look's images at the pixels (:class:`~holo_core.optics.
imaging.Folded`, radiance |A|² calibrated) become one view (:func:`compose`), as the camera
hologram assembles its own (:func:`holo_core.optics.imaging.assemble`): the looks' radiance
combined (Sect. VII-E), the depth partner's coverage giving alpha and the colour as radiance
over coverage, and the depth from the two-wavelength phase (Eq. 26-30), consensus or
brightest. A view of no light is :func:`black_view`.
"""

from __future__ import annotations

import logging
import math
import warnings

import numpy as np

from ..acquired.framing import stated_plane
from ..optics import depth as depth_mod
from ..optics import speckle
from ..optics.imaging import assemble
from ..scene.camera import Camera
from ..scene.hologram import Hologram
from ..validate import InputError, shown
from ..view import BACKGROUND_DEPTH, RenderResult, as_rgb
from .plan import SHARP_SLACK, SUPERSAMPLE
from .window import plane_depth

log = logging.getLogger(__name__)


def compose(
    looks,
    colours,
    z_ch,
    first: Hologram,
    camera,
    pupil,
    *,
    supersample,
    composition,
    depth_estimate,
    centre,
    exposure,
    threshold,
    n,
) -> RenderResult:
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
    depth_of = {
        "same": same_wavelength(first, colours),
        "partner": z_ch,
        "estimate": depth_estimate,
        "wavelengths": pair,
        "centre": centre,
        "camera": camera,
        "supersample": supersample,
    }
    if not first.point_density:  # bare points: no coverage to calibrate; alpha from luminance
        return _finish(
            radiance,
            _depth(looks, cross, **depth_of),
            None,
            first,
            camera,
            pupil,
            exposure,
            threshold,
            lam0,
        )
    exposure = 1.0 if exposure is None else exposure
    colour, alpha, depth, seen, cover = assemble(
        as_rgb(radiance),
        coverage,
        cross,
        camera=camera,
        supersample=1,
        wavelengths=pair,
        centre=centre,
        exposure=exposure,
    )
    if depth_estimate == "brightest":
        depth = np.where(alpha > 0, _depth(looks, cross, **depth_of), BACKGROUND_DEPTH).astype(
            np.float32
        )
    if not (np.isfinite(colour.min(initial=0)) and np.isfinite(colour.max(initial=0))):
        raise InputError(
            f"exposure must keep the view's pixels within float32 (finite); got {shown(exposure)}"
        )
    limit = lam0 / pupil.diameter
    info = {
        "aperture_m": pupil.diameter,
        "focus_m": pupil.focus,
        "resolution_limit_rad": limit,
        "pixel_angle_rad": camera.pixel_angle(),
        "resolution_limit_px": limit / camera.pixel_angle(),
        "wavelengths_m": list(first.wavelengths),
        "exposure": exposure,
        "pupil_samples": list(n) if isinstance(n, tuple) else [n, n],
        "iterations": len(looks),
        "samples": len(looks),
        "speckle_contrast": _spread(looks, colours, z_ch, coverage),
    }
    log.info(
        "render: aperture %.4g m, resolution limit λ/D = %.3g rad = %.2f px",
        pupil.diameter,
        limit,
        info["resolution_limit_px"],
    )
    _check_sharp(first, camera, pupil.diameter, info["resolution_limit_px"])
    return RenderResult(
        rgb=colour, alpha=alpha, depth=depth, info=info, coverage=cover, radiance=seen
    )


def black_view(
    first: Hologram, camera: Camera, pupil, colours, exposure, threshold
) -> RenderResult:
    """The view of no light (the camera sees the objects beside the plate, or out of its
    zone's light), with the settings' exposure and the pupil's figures in its info."""
    return _finish(
        np.zeros(camera.resolution[::-1] + (len(colours),)),
        None,
        None,
        first,
        camera,
        pupil,
        exposure,
        threshold,
        first.wavelengths[colours[0]],
    )


def same_wavelength(h: Hologram, colours) -> list:
    """The colour channels at the first colour's wavelength: the depth pair's first member
    is their sum (Eq. 26)."""
    lam0 = h.wavelengths[colours[0]]
    return [c for c in colours if h.wavelengths[c] == lam0]


class SoftViewWarning(UserWarning):
    """A plate's view resolving less than a sharp view does: the camera's pixels are finer,
    or its pupil narrower, than those the plate was recorded for."""


def _check_sharp(h: Hologram, camera: Camera, diameter: float, spot_px: float) -> None:
    """Warn (:class:`SoftViewWarning`) when a view of the plate ``h`` through a pupil of
    ``diameter`` [m] resolves ``spot_px`` pixels, more than the half pixel of a sharp view."""
    if spot_px * SUPERSAMPLE <= 1 + SHARP_SLACK:
        return
    made = (
        ""
        if h.zone is None or not h.zone.pixel
        else (
            f"; the plate was recorded for pixels of {h.zone.pixel:.3g} rad"
            + (f" through a pupil of {h.zone.pupil:.3g} m" if h.zone.pupil else "")
        )
    )
    warnings.warn(
        f"this view resolves {spot_px:.2g} px where a sharp view resolves "
        f"{1 / SUPERSAMPLE:g}: its pixels are {camera.pixel_angle():.3g} rad through "
        f"a pupil of {diameter:.3g} m{made}; it looks soft: record the plate for "
        f"this camera's pixels and pupil",
        SoftViewWarning,
        stacklevel=3,
    )


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
    return speckle.downsample(
        speckle.compose(
            [np.stack([np.abs(look.fine[c]) ** 2 for c in colours], -1) for look in looks],
            composition,
        ),
        supersample,
    )


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


def _depth(
    looks, cross, *, same, partner, estimate, wavelengths, centre, camera: Camera, supersample
) -> np.ndarray:
    """Planar depth [m] from the depth pair's cross image u1·conj(u2): of the pixels' means
    summed over the iterations (``cross``: the intensity-weighted consensus), or per fine
    pixel from the brightest iteration (their ``fine`` images, ``same`` summed into u1)."""

    def ranges(c):
        return depth_mod.from_cross_spectrum(c, wavelengths=wavelengths, centre=centre, focus=None)

    def planar(ray, cam):
        tx, ty = cam.pixel_tangents()
        return ray / np.sqrt(1 + tx * tx + ty * ty)

    if estimate == "consensus":
        return planar(ranges(cross), camera)
    first = [sum(look.fine[c] for c in same) for look in looks]
    ray, bright = depth_mod.keep_brightest(
        [ranges(u * np.conj(look.fine[partner])) for u, look in zip(first, looks)],
        [np.abs(u) for u in first],
    )
    return speckle.pick_brightest(
        planar(ray, camera.supersampled(supersample)), bright, supersample
    )


def _finish(radiance, ray, coverage, h: Hologram, camera, pupil, exposure, threshold, lam0):
    if not np.isfinite(radiance).all() or (ray is not None and not np.isfinite(ray).all()):
        peak = float(
            h.intensity.max()
            if h.intensity is not None
            # never a NaN view:
            else np.abs(h.object_wave).max() ** 2
        )  # say which numbers overflowed
        scale = min(h.reference_amplitudes, default=1.0) ** 2
        raise InputError(
            f"intensity must stay within float32 arithmetic through the view: "
            f"this hologram's reaches {peak:.3g}, {peak / scale:.3g} times its "
            f"reference intensity |R|² (a recording holds far less than 1e12 "
            f"times), and the view overflowed"
        )
    lum = radiance.mean(-1)
    ref = float(np.percentile(lum, 99.5))
    if exposure is None:
        exposure = 1 / h.point_density if h.point_density else (1 / ref if ref > 0 else 1.0)
    rgb = radiance * exposure
    if np.abs(rgb).max(initial=0) > np.finfo(np.float32).max:  # a view of inf pixels
        raise InputError(
            f"exposure must keep the view's pixels within float32: at most "
            f"{np.finfo(np.float32).max / np.abs(radiance).max():.3g} for this "
            f"view; got {shown(exposure)}"
        )
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
    info = {
        "aperture_m": pupil.diameter,
        "focus_m": pupil.focus,
        "resolution_limit_rad": limit,
        "pixel_angle_rad": camera.pixel_angle(),
        "resolution_limit_px": limit / camera.pixel_angle(),
        "wavelengths_m": list(h.wavelengths),
        "exposure": exposure,
    }
    log.info(
        "render: aperture %.4g m, resolution limit λ/W = %.3g rad = %.2f px",
        pupil.diameter,
        limit,
        info["resolution_limit_px"],
    )
    return RenderResult(rgb=rgb.astype(np.float32), alpha=alpha, depth=depth, info=info)
