"""The reference wave and the interference of Eq. 4 and 16: R = A·exp(ik(α·x + β·y)) on the
hologram plane z = 0 and H = |O + R|².
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import validate
from ..propagation import grid
from ..validate import InputError, shown


@dataclass(frozen=True, slots=True, kw_only=True)
class Reference:
    """The plane reference wave of Eq. 4 on z = 0.

    Parameters
    ----------
    angle : float
        ϑ [rad], between the reference's direction and the hologram normal (+z), in [0, π/2).
    azimuth : float
        φ [rad], direction of the tilt in the hologram plane, from +x towards +y.
    beam_ratio : float
        |R|² / mean |O|², > 0: the reference's intensity against the object wave's.
    allow_aliasing : bool
        Record even when the pitch violates Eq. 19 (warned; the message names the largest
        safe angle).

    Raises
    ------
    InputError
        Where ``angle`` is outside [0, π/2), ``azimuth`` is not finite or ``beam_ratio`` is
        not > 0.

    Notes
    -----
    R = A·exp(ik(α·x + β·y)) (Eq. 4), (α, β, γ) = (sin ϑ cos φ, sin ϑ sin φ, cos ϑ) the
    direction ``direction()`` returns. ``check(wavelength, pitch)`` holds the carrier's
    fringes to Eq. 19, pitch <= λ / (2 sin ϑ): it raises :class:`~holo_core.InputError`
    (or, with ``allow_aliasing``, warns) naming the largest safe angle.

    Examples
    --------
    >>> from holo_core import InputError
    >>> from holo_core.plate import Reference
    >>> r = Reference(angle=0.1)
    >>> r.direction().round(4)
    array([0.0998, 0.    , 0.995 ])
    >>> try:
    ...     r.check(633e-9, 4e-6)
    ... except InputError as e:
    ...     print(str(e)[:60])
    reference angle 0.1 rad needs a pitch <= 3.17e-06 m at λ = 6
    """

    angle: float = 0.0
    azimuth: float = 0.0
    beam_ratio: float = 4.0
    allow_aliasing: bool = False

    def __post_init__(self):
        a = validate.finite("reference angle", self.angle, "rad")
        if not 0 <= a < math.pi / 2:
            raise InputError(f"reference angle must be in [0, π/2) rad; got {shown(self.angle)}")
        validate.finite("reference azimuth", self.azimuth, "rad")
        validate.positive("reference beam_ratio", self.beam_ratio)

    def direction(self) -> np.ndarray:
        """The unit propagation direction (α, β, γ): the direction cosines of Eq. 4.

        Returns
        -------
        (3,) float64 ndarray
        """
        s = math.sin(self.angle)
        return np.array(
            [s * math.cos(self.azimuth), s * math.sin(self.azimuth), math.cos(self.angle)]
        )

    def check(self, wavelength: float, pitch: float) -> None:
        """Eq. 19: the carrier fringes need pitch <= λ / (2 sin ϑ).

        Parameters
        ----------
        wavelength : float
            λ [m].
        pitch : float
            The hologram's sample spacing [m].

        Raises
        ------
        InputError
            Where the pitch is too coarse for the angle (warned instead with
            ``allow_aliasing``), naming the largest safe angle.
        """
        if self.angle == 0:
            return
        limit = wavelength / (2 * math.sin(self.angle))
        if pitch > limit:
            safe = math.asin(min(1.0, wavelength / (2 * pitch)))
            message = (
                f"reference angle {self.angle:.4g} rad needs a pitch <= {limit:.4g} m "
                f"at λ = {wavelength:.4g} m (Eq. 19); with pitch {pitch:.4g} m the "
                f"largest safe angle is {safe:.4g} rad"
            )
            if not self.allow_aliasing:
                raise InputError(message)
            validate.warn_sampling(message)


def reference_wave(shape, *, wavelength, pitch, reference: Reference, amplitude=1.0):
    """R = A·exp(ik(α·x + β·y)) on the hologram's pixel centres (Eq. 4 on z = 0), complex64.

    ``shape`` (rows, cols); ``wavelength``, ``pitch`` [m]; ``amplitude`` A [field units].
    The phase is formed in float64 and reduced before the cast.
    """
    h, w = validate.shape2d("shape", shape)
    wavelength, pitch = grid.wave(wavelength, pitch)
    alpha, beta, _ = reference.direction()
    k = 2 * np.pi / wavelength
    px = np.remainder(k * alpha * grid.coords(w, pitch), 2 * np.pi)
    py = np.remainder(k * beta * grid.coords(h, pitch), 2 * np.pi)
    return (amplitude * np.exp(1j * py)[:, None] * np.exp(1j * px)[None, :]).astype(np.complex64)


def interfere(object_wave, reference_wave) -> np.ndarray:
    """H = |O + R|² (Eq. 16), float32."""
    u = np.asarray(object_wave, np.complex64) + np.asarray(reference_wave, np.complex64)
    return (u.real * u.real + u.imag * u.imag).astype(np.float32)
