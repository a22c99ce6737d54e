"""Reconstruction: U = R'·H with DC-term suppression (Sect. VI, Eq. 17-21).

With the reconstruction wave R' equal to the reference R, U holds the reference term
R(|O|² + |R|²), the virtual image O|R|² and the real image Ō R² (Eq. 18). Subtracting the mean
intensity (H' = H - mean H, Eq. 21) removes most of the reference term; an off-axis reference
moves the real image's spectrum away from the virtual image's. The result is divided by |R|²
so that it estimates the object wave O leaving the hologram towards +z.
"""

from __future__ import annotations

import numpy as np

from .. import validate
from ..scene.hologram import Hologram
from ..validate import InputError
from .carrier import physical_field
from .reference import Reference, reference_wave


@validate.scale_free()
def reconstruct(hologram: Hologram, colour: int = 0, *, dc_suppression=True) -> np.ndarray:
    """Reconstruct the virtual image's wave on z = 0 for one colour of a hologram.

    Parameters
    ----------
    hologram : Hologram
        An intensity or complex hologram.
    colour : int
        Index into ``hologram.wavelengths``.
    dc_suppression : bool
        Subtract the mean intensity first (Eq. 20-21).

    Returns
    -------
    (H, W) complex64 ndarray
        The wave on the plate. A complex hologram holds the object wave itself: its samples (a
        plate without a carrier), or for a plate stored against its zone's carrier the physical
        field re-modulated from them (:func:`holo_core.plate.carrier.physical_field` with its
        defaults: the carrier's window at the finest pitch the field needs there; that function
        returns it as a Field, with its pitch and pose, and takes a region and a pitch).

    Raises
    ------
    InputError
        Where ``colour`` is out of range.

    Notes
    -----
    The reconstruction U = R'·H of Eq. 18, of which the virtual image O·``|R|²`` is kept.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import reconstruct, record_points
    >>> h = record_points(np.array([[0.0, 0.0, -2e-3]]), np.array([[1.0]]), shape=(64, 64),
    ...                   pitch=2e-6, wavelengths=(633e-9,))
    >>> u = reconstruct(h)
    >>> u.shape, str(u.dtype)
    ((64, 64), 'complex64')
    """
    if not isinstance(hologram, Hologram):
        raise InputError(f"hologram must be a Hologram; got {type(hologram).__name__}")
    colour = validate.index("colour", colour, len(hologram.wavelengths))
    if hologram.encoding == "complex":
        return np.asarray(physical_field(hologram, colour).samples, np.complex64)
    h = hologram.intensity[colour].astype(np.float64)
    if dc_suppression:
        h = h - h.mean()
    amplitude = hologram.reference_amplitudes[colour] if hologram.reference_amplitudes else 1.0
    ref = Reference(
        angle=hologram.reference_angle, azimuth=hologram.reference_azimuth, allow_aliasing=True
    )
    r = reference_wave(
        hologram.shape,
        wavelength=hologram.wavelengths[colour],
        pitch=hologram.pitch,
        reference=ref,
        amplitude=amplitude,
    )
    return (r * h / amplitude**2).astype(np.complex64)
