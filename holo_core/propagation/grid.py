"""Sampling grids: pixel centres, DFT frequencies, padded sizes, and the checks every stage shares.

Column j of a W-wide field lies at x = (j - (W-1)/2)·pitch, row i at y = (i - (H-1)/2)·pitch:
the centre of the array is the optical axis. Frequencies are ``numpy.fft.fftfreq`` of the grid.
"""

from __future__ import annotations

import math

import numpy as np

from .. import validate
from ..validate import InputError, shown


def coords(n: int, pitch: float) -> np.ndarray:
    """Pixel-centre positions [m] of ``n`` samples at ``pitch`` [m], centred on 0."""
    return (np.arange(n) - (n - 1) / 2) * pitch


def freqs(n: int, pitch: float) -> np.ndarray:
    """DFT frequencies [1/m] of ``n`` samples at ``pitch`` [m], in FFT order."""
    return np.fft.fftfreq(n, pitch)


def signed_indices(n: int) -> np.ndarray:
    """The signed index of each position of an FFT-ordered axis of ``n``: 0, 1, …, −1."""
    return np.fft.fftfreq(n, 1 / n)


def embedded(n: int, size: int) -> tuple[tuple[int, int], tuple[int, int]]:
    """Where the ``n`` samples of an FFT-order axis lie once zero-padded to ``size`` in FFT
    order: its non-negative indices at the start, its negative ones at the end (two index
    ranges; the FFTs' ``nonzero``)."""
    return (0, (n + 1) // 2), (size - n // 2, size)


def next_fast_len(n: int) -> int:
    """The smallest 2^a 3^b 5^c 7^d >= n (fast sizes for FFTW and VkFFT)."""
    return smooth_len(n, (2, 3, 5, 7))


def smooth_len(n: int, primes) -> int:
    """The smallest product of powers of ``primes`` that is >= n (the first prime fills up
    each product of the others)."""
    base, others = primes[0], primes[1:]
    best = base ** max(0, math.ceil(math.log(max(n, 1), base)))
    products = [1]  # every product of the other primes below best
    for q in others:
        products = [
            m * q**e for m in products for e in range(int(math.log(best, q)) + 2) if m * q**e < best
        ]
    for m in products:
        while m < n:
            m *= base
        best = min(best, m)
    return best


def padded_shape(shape: tuple[int, int], padding: float) -> tuple[int, int]:
    """Grid size after zero-padding each axis by ``padding`` (>= 1), rounded up to a fast size."""
    return tuple(next_fast_len(math.ceil(padding * n - 1e-9)) for n in shape)


def support(field: np.ndarray):
    """The field cropped to its non-zero bounding box, and the box's (row, col) origin."""
    rows, cols = np.nonzero(field.any(axis=1))[0], np.nonzero(field.any(axis=0))[0]
    if rows.size == 0:
        return field[:1, :1], (0, 0)
    return field[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1], (int(rows[0]), int(cols[0]))


def wave(wavelength, pitch) -> tuple[float, float]:
    """Checked (wavelength [m], pitch [m])."""
    return (validate.wavelength("wavelength", wavelength), validate.pitch("pitch", pitch))


def wave_pair(wavelength, pitch) -> tuple[float, tuple[float, float]]:
    """Checked (wavelength [m], (pitch x, pitch y) [m]): a pitch is a number or a pair."""
    return validate.wavelength("wavelength", wavelength), pitch_pair(pitch)


def pitch_pair(pitch, name: str = "pitch") -> tuple[float, float]:
    """A checked pitch [m] as (x, y): a number for both axes, or a pair (x, y)."""
    if np.ndim(pitch) == 0:
        p = validate.pitch(name, pitch)
        return p, p
    if np.shape(pitch) != (2,):
        raise InputError(f"{name} must be a number or a pair (x, y) [m]; got {shown(pitch)}"[:300])
    return validate.pitch(name, pitch[0]), validate.pitch(name, pitch[1])


def padding_factor(padding) -> float:
    p = validate.at_least("padding", padding, 1.0)
    if p > 16:
        raise InputError(f"padding must be in [1, 16]; got {shown(padding)}")
    return p
