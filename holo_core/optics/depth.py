"""Depth from the phase difference of two wavelengths (Sect. VII-C, Eq. 26-30).

An image at λ1 and one at λ2 = ε·λ1 of the same scene (same emitter phases) differ in phase by
Δφ = (k1 − k2)(r − f) at a pixel whose light comes from distance r (f: the lens's focus
distance, Eq. 28-29; 0 for a pinhole). Δφ is known modulo 2π, so r is known modulo
r_max = 1/(1/λ2 − 1/λ1) (Eq. 26); it is unwrapped around the scene's centre distance, so the
range is that centre ± r_max/2 = ± d_max (Eq. 30). Where several emitters interfere, the
iteration with the brightest λ1 image gives a depth between theirs (Fig. 11).
"""

from __future__ import annotations

import numpy as np

from .. import validate
from ..validate import InputError

DEPTH_MARGIN = 1.25  # the depth pair's unambiguous range over the objects' depth extent


def partner_wavelength(wavelength, half_range) -> float:
    """λ2 = ε_l·λ1 with ε_l = 1 / (1 + λ1 / (2·d_max)) (Eq. 30): depths within ± ``half_range``
    d_max [m] of the centre are unambiguous. ``wavelength`` λ1 [m]."""
    lam = validate.positive("wavelength", wavelength, "m")
    d_max = validate.positive("depth half_range", half_range, "m")
    return lam / (1 + lam / (2 * d_max))


def from_phase_difference(u1, u2, *, wavelengths, centre, focus=None) -> np.ndarray:
    """Distance r [m] along each pixel's ray from the complex images ``u1`` at λ1 and ``u2`` at
    λ2 (Eq. 26-29), unwrapped around ``centre`` [m]; ``focus`` f [m] of a thin lens (r = r_f
    in the paper's notation, Eq. 29), None for a pinhole."""
    return from_cross_spectrum(
        np.asarray(u1) * np.conj(u2), wavelengths=wavelengths, centre=centre, focus=focus
    )


def from_cross_spectrum(cross, *, wavelengths, centre, focus=None) -> np.ndarray:
    """As :func:`from_phase_difference`, from u1·conj(u2) summed over looks (iterations,
    neighbouring samples): the phase of the sum is the intensity-weighted consensus, which
    dark speckles, whose phase is noise, barely move."""
    lam1, lam2 = (validate.positive("wavelengths", w, "m") for w in wavelengths)
    if lam1 == lam2:
        raise InputError("the depth pair needs two different wavelengths")
    dk = 2 * np.pi * (1 / lam1 - 1 / lam2)
    f = 0.0 if focus is None else focus
    x_c = centre - f
    # the phase less dk·x_c, wrapped: the angle of the sum turned by the one factor
    # exp(-i·dk·x_c), not a per-pixel exponential (a transcendental a pixel, a pass of its own)
    cross = np.asarray(cross)
    turn = np.exp(-1j * np.remainder(dk * x_c, 2 * np.pi)).astype(
        np.complex64 if cross.dtype == np.complex64 else np.complex128
    )
    ray = np.angle(cross * turn)  # then in place: the steps of a 1280×720 view cost passes
    ray /= ray.dtype.type(dk)  # over memory, not arithmetic
    ray += ray.dtype.type(f + x_c)
    return ray


def keep_brightest(ranges, magnitudes) -> tuple[np.ndarray, np.ndarray]:
    """Per pixel, the depth of the iteration whose λ1 image is brightest (Fig. 11c), and that
    magnitude."""
    r, m = np.stack(ranges), np.stack(magnitudes)
    best = np.argmax(m, axis=0)[None]
    return np.take_along_axis(r, best, 0)[0], np.take_along_axis(m, best, 0)[0]
