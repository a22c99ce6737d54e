"""The camera's entrance pupil, and the pinhole rules of both renderers side by side.

A pupil of diameter D resolves the angle λ/D (Sect. VII-A); a thin lens (Eq. 24) focuses it
on one distance, and defocus then blurs by D·|1/z − 1/focus| (the camera's depth of field).
Without a lens a pinhole also blurs geometrically by D/r at distance r, so each renderer picks
the pinhole that balances the two for its own sampling:

- :func:`camera_pupil` (full-band plates' views): λ/D spans ``PINHOLE_SAMPLES`` pixels,
  D ≤ √(λ·r); a carrier plate's views take the smallest pupil as sharp as the plate's own,
  λ/D a fine pixel (:func:`holo_core.plate.window.pinhole_view_pupil`);
- :func:`pinhole_wavelength` (plate sampling): the λ at which both blurs reach two pixels,
  λ = 4Δ²r;
- :func:`defocus_limited_diameter` (camera holograms): the widest pupil, focused in the middle
  of the depth range in 1/z, that blurs no more than one angle ``b``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .. import validate
from ..scene.camera import Camera

PINHOLE_SAMPLES = 2  # a pinhole's resolution λ/D spans this many pixels (alias-free |A|²)


@dataclass(frozen=True, slots=True, kw_only=True)
class Pupil:
    """The camera's entrance pupil.

    Parameters
    ----------
    diameter : float
        Pupil diameter [m].
    focus : float, optional
        Distance [m] of the plane in focus (thin lens, Eq. 24), or None for a pinhole.
    apodize : bool
        The cosine window of Fig. 9 (1 at the centre, 0 at the rim) instead of a hard edge.
    lens_wavelength : float, optional
        λ [m] the lens is designed for; other wavelengths focus at focus·λ_lens/λ (chromatic
        aberration, Sect. VII-B). None: no aberration.

    Raises
    ------
    InputError
        Where a length is not finite and > 0.

    Examples
    --------
    >>> from holo_core import Pupil
    >>> Pupil(diameter=5e-3, focus=0.5)
    Pupil(diameter=0.005, focus=0.5, apodize=True, lens_wavelength=None)
    """

    diameter: float
    focus: float | None = None
    apodize: bool = True
    lens_wavelength: float | None = None

    def __post_init__(self):
        validate.positive("aperture diameter", self.diameter, "m")
        if self.focus is not None:
            validate.positive("focus distance", self.focus, "m")
        if self.lens_wavelength is not None:
            validate.positive("lens_wavelength", self.lens_wavelength, "m")


def camera_pupil(camera: Camera, wavelength: float, distance: float, *, apodize=True) -> Pupil:
    """The camera's own lens (diameter lens/N, its focus), or a pinhole at ``wavelength`` [m]
    for objects ``distance`` [m] away: as wide as the alias-free size λ/D = PINHOLE_SAMPLES
    pixels (Sect. VII-A, VII-D) allows, but no wider than √(λ·distance), beyond which its own
    geometric blur D/distance outgrows its diffraction λ/D."""
    if camera.fstop is not None:
        return Pupil(
            diameter=camera.aperture_diameter, focus=camera.focus_distance, apodize=apodize
        )
    alias_free = wavelength / (PINHOLE_SAMPLES * camera.pixel_angle())
    return Pupil(diameter=min(alias_free, math.sqrt(wavelength * distance)), apodize=apodize)


def pinhole_wavelength(pixel_angle: float, distance: float) -> float:
    """λ [m] at which a pinhole's diffraction λ/D and its geometric blur D/r both span two
    pixels of ``pixel_angle`` [rad] for objects ``distance`` [m] away: λ = 4Δ²r."""
    return 4 * pixel_angle * pixel_angle * distance


def defocus_limited_diameter(bin_angle: float, near: float, far: float) -> tuple[float, float]:
    """(diameter [m], focus [m]) of the widest pupil whose defocus over planar depths
    ``near`` … ``far`` [m] stays within ``bin_angle`` [rad], focused on their middle in 1/z."""
    focus = 2 / (1 / near + 1 / far)
    defocus = max(1 / near - 1 / focus, 1 / focus - 1 / far, 1e-12)
    return bin_angle / defocus, focus


def intensity_supersample(diameter: float, pixel_angle: float, wavelength: float) -> int:
    """Fine pixels per pixel (per axis) at which an image through a pupil of ``diameter`` [m]
    at ``wavelength`` [m], pixels of ``pixel_angle`` [rad], samples its intensity at the
    Nyquist rate: |A|² carries twice the amplitude's band (directions up to D/λ apart), so a
    fine pixel spans at most λ/(2D); coarser, the speckle's grains alias into the pixels
    instead of averaging in them. At most ``AUTO_SUPERSAMPLE``."""
    need = 2 * diameter * pixel_angle / wavelength
    return int(min(AUTO_SUPERSAMPLE, max(1, math.ceil(need / NYQUIST_SLACK))))


NYQUIST_SLACK = 1.05  # a fine pixel may exceed λ/(2D) by this factor (λ/D = 0.49 px: 4, not 5)
AUTO_SUPERSAMPLE = 4  # at most: finer lenses put 16 and more independent grains in a pixel
