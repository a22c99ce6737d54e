"""The carrier a plate's samples are stored against: the spherical wave converging on the
centre of its viewing zone.

The light that reaches a zone of width w at distance L from one plate point leaves it within
about w/L of the direction towards the zone; only that direction changes across the plate.
Stored as B(x) = O(x)·exp(+ik|x − c|), the object wave O times the conjugate of the wave
converging on the zone's centre c, the samples are baseband: their band is the zone's angle,
not the widest angle between the plate's normal and the objects, and their pitch λ/(2·band)
follows what the zone can see (facts §7). The physical field is O = B·exp(−ik|x − c|), exact
at every sample (:func:`modulate`); the phase is formed in float64 and reduced before the
product.
"""

from __future__ import annotations

import numpy as np

from ..scene.plate import Carrier


def modulate(samples, carrier: Carrier, *, wavelength: float, pitch: float, rows=None,
             cols=None) -> np.ndarray:
    """The physical object wave O = B·exp(−ik|x − c|) (complex64) of ``samples`` B
    ((..., rows, cols), the window's ``rows`` and ``cols`` index ranges, default from 0)."""
    b = np.asarray(samples)
    h, w = b.shape[-2:]
    rows = np.arange(h) if rows is None else rows
    cols = np.arange(w) if cols is None else cols
    return (b * np.exp(-1j * carrier.phase(wavelength, pitch, rows, cols))).astype(np.complex64)


def demodulate(field, carrier: Carrier, *, wavelength: float, pitch: float, rows=None,
               cols=None) -> np.ndarray:
    """The stored samples B = O·exp(+ik|x − c|) (complex64) of an object wave ``field`` O on
    the carrier's sample grid (the inverse of :func:`modulate`)."""
    o = np.asarray(field)
    h, w = o.shape[-2:]
    rows = np.arange(h) if rows is None else rows
    cols = np.arange(w) if cols is None else cols
    return (o * np.exp(1j * carrier.phase(wavelength, pitch, rows, cols))).astype(np.complex64)
