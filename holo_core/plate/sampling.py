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
from ..optics.depth import DEPTH_MARGIN, partner_wavelength
from ..optics.pupil import pinhole_wavelength
from ..validate import InputError
from .point_sum import CONE_RIM

log = logging.getLogger(__name__)
DEFAULT_BAND = 0.25  # sin θ of the viewing zone without a camera
MAX_BAND = 0.9  # the widest cone chosen, sin θ (64°), with a camera or without
MARGIN = 0.95  # the cone stays this fraction inside the off-axis sampling limit
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
        return (
            f"hologram {self.shape[1]}x{self.shape[0]} at pitch {self.pitch:.4g} m, "
            f"λ = {self.wavelength:.4g} m (depth λ2 = {self.depth_wavelength:.6g} m), "
            f"cone sin θ = {self.band:.3g}, reference {math.degrees(self.reference_angle):.2f}°,"
            f" point spacing {self.spacing:.3g} m"
        )


def band_towards(points, camera_position) -> float:
    """sin θ of the widest angle between the plate normal (+z) and the lines from ``points``
    (N, 3) [m] to ``camera_position`` [m], all in the plate's frame."""
    v = np.asarray(camera_position, np.float64) - np.asarray(points, np.float64)
    return float(np.max(np.hypot(v[:, 0], v[:, 1]) / np.linalg.norm(v, axis=1)))


def choose(
    plate_size, points, *, camera=None, resolution=None, max_resolution=2048, wavelength=None
) -> Sampling:
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
        raise InputError(
            "points must be finite (x, y, z) [m] behind the plate (z < 0 in its frame)"
        )
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
    s = Sampling(
        shape=(max(1, round(height / pitch)), max(1, round(width / pitch))),
        pitch=pitch,
        wavelength=lam,
        depth_wavelength=lam2,
        band=band,
        reference_angle=math.asin(min(0.99, 3 * lam2 / (8 * pitch))),
        spacing=max(lam / (2 * band) / math.sqrt(2), footprint / 2),
    )
    log.info("sampling: %s", s.describe())
    if lam_image is not None and lam > 1.5 * lam_image:
        # the spot grows as √λ at the pinhole's best (λ = 4Δ²r gives two pixels), and the
        # sharp λ needs the hologram's side to grow as 1/λ
        log.warning(
            "sampling: this plate's view resolves about %.1f px (2 px at best): the "
            "image needs λ <= %.3g m, a hologram of %d samples allows %.3g m; %d "
            "samples (Max Hologram Size) or the camera mode would make it sharp",
            2 * math.sqrt(lam / lam_image),
            lam_image,
            resolution,
            lam,
            math.ceil(resolution * lam / lam_image),
        )
    return s
