"""What a phase display shows: its light carried to the planes of a focal stack, and how
close that stack is to the one the unencoded complex wave would give.

The model (:class:`Optics`), per laser: the display's field u (exp(i·phase) of the shown
codes, or a complex wave) is zero-padded, Fourier transformed, passed through the display's
Fourier filter (a rectangle keeping |fx|, |fy| <= band/(2p): the 4f system's iris; 0.5 is the
half-Nyquist filter double-phase needs), through the eye's pupil where one is given (a disc
in the eye box, whose position x is the frequency x/(λ·D)), multiplied by the exact
band-limited angular spectrum transfer function to each plane
(:func:`holo_core.propagation.transfer.transfer_function`'s formula, Matsushima & Shimobaba's limit on
the padded window), transformed back and cropped to the display's window. The same optics
applied to the complex wave itself is the reference: the stacks differ only by what the
encoding and the quantisation lose.

What an eye (or a camera) in front of the display sees (:class:`EyePupil`, :meth:`Optics.seen`):
its pupil, a disc of diameter a centred at e in the plane at distance D in front of the
display, its lens focused on plane k at depth z_k (L = D − z_k from the pupil). The lens
images plane k with unit magnification onto the retina, referred back to that plane: the
light a point x of the plane sends through the pupil leaves it at the frequencies
(ξ − x)/(λL), ξ in the pupil, so the image is the plane's field v_k times the chirp
exp(iπ|x|²/(λL)) (which turns every such frequency to ξ/(λL), the same for all x), low-passed
to the disc of radius a/(2λL) about e/(λL), and its amplitude taken (Fresnel's approximation
of the path to the pupil and the ideal lens; the retinal image's residual phase is dropped
with the amplitude). In focus a point is the pupil's Airy pattern, first zero 1.22·λL/a;
out of focus by Δz its light fills a disc a·|Δz|/L across. A random-phase wave seen so is
speckle of the Airy pattern's size; a smooth-phase one is a picture.

:func:`compare` gives PSNR and SSIM (:mod:`holo_core.optics.metrics`) of each slice's
amplitude ``|U|``, the simulated stack scaled by the one factor that best fits the whole
reference stack (a display's brightness is its laser's power and the lab's gain), the data
range the reference stack's largest amplitude.

FFTs: scipy.fft in complex64 on all the CPUs when SciPy is installed, else NumPy's pocketfft
(complex128, cast back); float32 fields, transfer functions made in float64.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .. import validate
from ..optics.metrics import psnr, ssim
from ..propagation import grid
from ..propagation.transfer import BAND_EDGE
from ..validate import InputError

try:  # complex64 transforms on every CPU: ~3x NumPy 1's complex128 pocketfft here
    import scipy.fft as _sfft
except ImportError:  # pragma: no cover -- SciPy is optional
    _sfft = None

MARGIN = 16  # padding samples beyond the widest spread of the band over the deepest plane
# the eye's Airy patterns held on the padded grid: this many first-zero radii each side (the
# pattern's rings beyond carry under 0.2 % of its light)
AIRY_RADII = 4


@dataclass(frozen=True, slots=True, kw_only=True)
class EyePupil:
    """An eye (or a camera) looking straight at the display (module docstring).

    diameter : the pupil's diameter [m] (an eye's 2 to 6 mm; display labs judge with 3 to 4)
    distance : the pupil's plane from the display [m], in front of it (the eye box's)
    centre : (x, y) [m] of the pupil in that plane, from the display's axis

    Examples
    --------
    >>> from holo_core.phase.stack import EyePupil
    >>> EyePupil(diameter=4e-3, distance=0.3).centre
    (0.0, 0.0)
    """

    diameter: float
    distance: float
    centre: tuple = (0.0, 0.0)

    def __post_init__(self):
        object.__setattr__(
            self, "diameter", validate.positive("eye pupil diameter", self.diameter, "m")
        )
        object.__setattr__(
            self, "distance", validate.positive("eye pupil distance", self.distance, "m")
        )
        object.__setattr__(self, "centre", validate.pair("eye pupil centre", self.centre, "m"))


def fft(a: np.ndarray, axis: int) -> np.ndarray:
    if _sfft is not None:
        return _sfft.fft(a, axis=axis, workers=os.cpu_count() or 1)
    return np.fft.fft(a, axis=axis).astype(np.complex64)


def ifft(a: np.ndarray, axis: int) -> np.ndarray:
    if _sfft is not None:
        return _sfft.ifft(a, axis=axis, workers=os.cpu_count() or 1)
    return np.fft.ifft(a, axis=axis).astype(np.complex64)


def fft2(a: np.ndarray) -> np.ndarray:
    return fft(fft(a, axis=0), axis=1)


def ifft2(a: np.ndarray) -> np.ndarray:
    return ifft(ifft(a, axis=0), axis=1)


def next_fast(n: int) -> int:
    return _sfft.next_fast_len(n) if _sfft is not None else grid.next_fast_len(n)


class Optics:
    """The display's light from its plane to the focal stack's planes (module docstring).

    Parameters
    ----------
    shape : (rows, cols)
        The display's samples.
    pitch : float
        [m].
    wavelength : float
        [m].
    distances : sequence of float
        The planes [m] (signed: negative behind the display).
    band : float
        The Fourier filter's half-width as a fraction of the Nyquist frequency, in (0, 1].
    pupil : (x, y, diameter, distance), optional
        A pupil in the display's Fourier plane (a near-eye display's eyepiece of focal
        length D): its centre (x, y) [m], its diameter [m] and D [m], a disc of frequencies
        applied to every plane; None: every frequency the filter passes.
    eye : EyePupil, optional
        An eye looking straight at the display, focused on each plane in turn
        (:meth:`seen`; module docstring).

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.phase.stack import EyePupil, Optics
    >>> optics = Optics((64, 64), pitch=8e-6, wavelength=520e-9, distances=[-2e-3, 0.0],
    ...                 eye=EyePupil(diameter=4e-3, distance=0.1))
    >>> optics.seen(np.ones((64, 64), np.complex64)).shape
    (2, 64, 64)
    """

    def __init__(self, shape, *, pitch, wavelength, distances, band=0.5, pupil=None, eye=None):
        self.shape = validate.shape2d("shape", shape)
        self.pitch = validate.pitch("pitch", pitch)
        self.wavelength = validate.wavelength("wavelength", wavelength)
        z = np.atleast_1d(np.asarray(distances, np.float64))
        if z.ndim != 1 or not z.size or not np.isfinite(z).all():
            raise InputError(f"distances must be finite distances [m]; got {distances!r}"[:200])
        self.distances = z
        self.band = validate.positive("band", band)
        if self.band > 1:
            raise InputError(f"band must be in (0, 1]; got {band!r}")
        angle = math.asin(min(1.0, self.band * self.wavelength / (2 * self.pitch)))
        spread = math.ceil(float(np.abs(z).max()) * math.tan(angle) / self.pitch) + MARGIN
        self.padded = tuple(next_fast(n + 2 * spread) for n in self.shape)
        fy = grid.freqs(self.padded[0], self.pitch)
        fx = grid.freqs(self.padded[1], self.pitch)
        cut = self.band / (2 * self.pitch) * (1 + 1e-9)
        self.rows = np.flatnonzero(np.abs(fy) <= cut)  # the filter's rows and columns
        self.cols = np.flatnonzero(np.abs(fx) <= cut)
        self.block = np.ix_(self.rows, self.cols)
        # the filter's rows and columns as runs (FFT order: the low positive frequencies,
        # then the negative ones): copied by slices, 3 times faster than by index arrays
        self._row_runs, self._col_runs = _runs(self.rows), _runs(self.cols)
        keep = np.ones((self.rows.size, self.cols.size))
        if pupil is not None:
            x, y, diameter, focal = (validate.finite("pupil", v, "m") for v in pupil)
            lam_d = self.wavelength * validate.positive("pupil distance", focal, "m")
            r = validate.positive("pupil diameter", diameter, "m") / (2 * lam_d)
            keep = (
                (fy[self.rows][:, None] - y / lam_d) ** 2
                + (fx[self.cols][None, :] - x / lam_d) ** 2
                <= r * r
            ).astype(np.float64)
            if not keep.any():
                raise InputError(
                    f"pupil: a {diameter * 1e3:.3g} mm pupil at ({x * 1e3:.3g}, "
                    f"{y * 1e3:.3g}) mm lies outside the band the display's "
                    f"filter passes"
                )
        self.keep = keep
        self.top = tuple((p - n) // 2 for p, n in zip(self.padded, self.shape))
        self._transfer = {}
        self._adjoint = {}
        if eye is not None and not isinstance(eye, EyePupil):
            raise InputError(f"eye must be an EyePupil or None; got {type(eye).__name__}")
        self.eye = eye
        if eye is not None:
            self._check_eye()

    def _check_eye(self) -> None:
        """Refuse an eye the planes' chirps would alias for: the light of a plane's edge
        turned by the chirp must stay inside the grid's band, or it would fold onto the
        pupil's disc."""
        eye, lam, p = self.eye, self.wavelength, self.pitch
        for z in (float(self.distances.min()), float(self.distances.max())):
            ell = eye.distance - z
            if not ell > 0:
                raise InputError(
                    f"eye: the plane at {z * 1e3:.4g} mm lies at or beyond the "
                    f"eye's pupil ({eye.distance * 1e3:.4g} mm in front of the "
                    f"display)"
                )
            half = max(self.shape) * p / 2
            reach = self.band / (2 * p) + half / (lam * ell)
            room = 1 / p - (eye.diameter / 2 + math.hypot(*eye.centre)) / (lam * ell)
            if reach >= room:
                near = (
                    half / (lam * (room - self.band / (2 * p)))
                    if room > self.band / (2 * p)
                    else math.inf
                )
                raise InputError(
                    f"eye: a pupil {eye.distance * 1e3:.4g} mm from a display "
                    f"{2 * half * 1e3:.3g} mm wide sees its edge at "
                    f"{half / ell:.3g} rad, beyond what a {p * 1e6:.3g} µm grid holds at "
                    f"{lam * 1e9:.4g} nm with the filter's band {self.band:g}: move the eye "
                    f"to >= {(near + z) * 1e3:.4g} mm, or judge through a pupil in the "
                    f"Fourier plane (pupil=)"
                )

    def _eye_grid(self, k: int):
        """(padded shape, rows, cols, disc, chirp) of the eye focused on plane ``k``: the
        window padded by AIRY_RADII Airy radii each side, the pupil's frequencies on it (the
        disc's rows and columns and its mask) and the chirp exp(iπ|x|²/(λL)) on the window,
        x from the display's axis (complex64)."""
        eye, lam, p = self.eye, self.wavelength, self.pitch
        ell = eye.distance - float(self.distances[k])
        airy = 1.22 * lam * ell / eye.diameter
        margin = math.ceil(AIRY_RADII * airy / p) + MARGIN
        padded = tuple(next_fast(n + 2 * margin) for n in self.shape)
        fy = grid.freqs(padded[0], p)
        fx = grid.freqs(padded[1], p)
        r = eye.diameter / (2 * lam * ell)
        cx, cy = (c / (lam * ell) for c in eye.centre)
        rows = np.flatnonzero(np.abs(fy - cy) <= r)
        cols = np.flatnonzero(np.abs(fx - cx) <= r)
        disc = (fy[rows][:, None] - cy) ** 2 + (fx[cols][None, :] - cx) ** 2 <= r * r
        if not disc.any():  # a pupil narrower than the grid's frequency step: its nearest
            rows, cols = rows[:1], cols[:1]
            disc = np.ones((1, 1), bool)
        y = (np.arange(self.shape[0]) - (self.shape[0] - 1) / 2) * p
        x = (np.arange(self.shape[1]) - (self.shape[1] - 1) / 2) * p
        turn = np.pi / (lam * ell)
        chirp = np.exp(1j * np.remainder(turn * y[:, None] ** 2, 2 * np.pi)) * np.exp(
            1j * np.remainder(turn * x[None, :] ** 2, 2 * np.pi)
        )
        return padded, rows, cols, disc.astype(np.complex64), chirp.astype(np.complex64)

    def through_eye(self, v: np.ndarray, k: int) -> np.ndarray:
        """The field ``v`` on plane ``k`` (the display's window) as the eye focused there
        sees it, referred back to the plane (module docstring), complex64: a pruned FFT
        (zero columns and rows off the disc not transformed), the disc, and back."""
        padded, rows, cols, disc, chirp = self._eye_grid(k)
        (h, w), (r0, c0) = self.shape, tuple((q - n) // 2 for q, n in zip(padded, self.shape))
        a = np.zeros((padded[0], w), np.complex64)
        a[r0 : r0 + h] = np.asarray(v, np.complex64) * chirp
        a = fft(a, axis=0)[rows]
        b = np.zeros((rows.size, padded[1]), np.complex64)
        b[:, c0 : c0 + w] = a
        block = fft(b, axis=1)[:, cols] * disc
        b = np.zeros((rows.size, padded[1]), np.complex64)
        b[:, cols] = block
        b = ifft(b, axis=1)[:, c0 : c0 + w]
        a = np.zeros((padded[0], w), np.complex64)
        a[rows] = b
        return ifft(a, axis=0)[r0 : r0 + h]

    def seen(self, u) -> np.ndarray:
        """The amplitude the eye sees on every plane, float32 (N, rows, cols): |U| through
        :meth:`through_eye` (the planes' own amplitudes, :meth:`stack`, without an eye)."""
        if self.eye is None:
            return self.stack(u)
        s = self.spectrum(u)
        return np.stack(
            [np.abs(self.through_eye(self.to_plane(s, k), k)) for k in range(self.distances.size)]
        )

    def transfer(self, k: int) -> np.ndarray:
        """The filter, pupil and transfer function to plane ``k`` on the filter's block,
        complex64 (cached)."""
        t = self._transfer.get(k)
        if t is None:
            full_rows = grid.freqs(self.padded[0], self.pitch)[self.rows]
            full_cols = grid.freqs(self.padded[1], self.pitch)[self.cols]
            # the transfer function's formula on the block's frequencies only: the same
            # values as transfer_function on the padded grid, at band² of its cost
            h = _block_transfer(
                self.padded,
                full_rows,
                full_cols,
                self.wavelength,
                self.pitch,
                float(self.distances[k]),
            )
            t = (h * self.keep).astype(np.complex64)
            self._transfer[k] = t
        return t

    def pad(self, u: np.ndarray) -> np.ndarray:
        out = np.zeros(self.padded, np.complex64)
        (r, c), (h, w) = self.top, self.shape
        out[r : r + h, c : c + w] = u
        return out

    def crop(self, v: np.ndarray) -> np.ndarray:
        (r, c), (h, w) = self.top, self.shape
        return v[r : r + h, c : c + w]

    def spectrum(self, u) -> np.ndarray:
        """The filter's block of the padded field's spectrum, complex64: fft2 of the padded
        field, pruned (rows of zeros are not transformed, columns outside the filter not
        kept), the same values at about 3/4 of the work. The rows (contiguous) first: the
        strided column pass then runs over the filter's columns alone (1080p: 20 % less
        time than columns first)."""
        (r, c), (h, w) = self.top, self.shape
        rows = np.zeros((h, self.padded[1]), np.complex64)
        rows[:, c : c + w] = u
        rows = fft(rows, axis=1)
        cols = np.zeros((self.padded[0], self.cols.size), np.complex64)
        for full, part in self._col_runs:
            cols[r : r + h, part] = rows[:, full]
        cols = fft(cols, axis=0)
        out = np.empty((self.rows.size, self.cols.size), np.complex64)
        for full, part in self._row_runs:
            out[part] = cols[full]
        return out

    def window(self, block: np.ndarray) -> np.ndarray:
        """ifft2 of a spectrum that is zero outside the filter's block, on the display's
        window (complex64), pruned like :meth:`spectrum`."""
        (r, c), (h, w) = self.top, self.shape
        cols = np.zeros((self.padded[0], self.cols.size), np.complex64)
        for full, part in self._row_runs:
            cols[full] = block[part]
        cols = ifft(cols, axis=0)
        rows = np.zeros((h, self.padded[1]), np.complex64)
        for full, part in self._col_runs:
            rows[:, full] = cols[r : r + h, part]
        return ifft(rows, axis=1)[:, c : c + w]

    def to_plane(self, spectrum_block: np.ndarray, k: int) -> np.ndarray:
        """The field (display's window, complex64) on plane ``k`` of a spectrum's block."""
        return self.window(spectrum_block * self.transfer(k))

    def from_plane(self, v: np.ndarray, k: int) -> np.ndarray:
        """The adjoint of :meth:`to_plane`: a field on plane ``k``'s window back to a spectrum
        block (conj of the transfer; FFT then ifft's 1/N, as NumPy's pair is adjoint)."""
        t = self._adjoint.get(k)
        if t is None:  # cached: the descent carries a plane back every step
            t = (np.conj(self.transfer(k)) / (self.padded[0] * self.padded[1])).astype(np.complex64)
            self._adjoint[k] = t
        return self.spectrum(v) * t

    def back(self, spectrum_block: np.ndarray) -> np.ndarray:
        """A spectrum block back to the display's window (the adjoint of :meth:`spectrum`
        up to NumPy's 1/N, which :meth:`from_plane` has taken)."""
        return self.window(spectrum_block) * (self.padded[0] * self.padded[1])

    def stack(self, u) -> np.ndarray:
        """The amplitude |U| on every plane, float32 (N, rows, cols)."""
        s = self.spectrum(u)
        return np.stack([np.abs(self.to_plane(s, k)) for k in range(self.distances.size)])


def _runs(index) -> list[tuple[slice, slice]]:
    """(slice of the full axis, slice of the block) for each run of consecutive ``index``."""
    breaks = np.flatnonzero(np.diff(index) != 1) + 1
    out, first = [], 0
    for run in np.split(index, breaks):
        out.append((slice(int(run[0]), int(run[-1]) + 1), slice(first, first + run.size)))
        first += run.size
    return out


def _block_transfer(padded, fy, fx, wavelength, pitch, distance) -> np.ndarray:
    """transfer_function's values (band limit included) at the frequencies fy × fx of the
    padded grid."""
    f2 = fx[None, :] ** 2 + fy[:, None] ** 2
    fz2 = 1.0 / wavelength**2 - f2
    keep = fz2 > 0
    fz = np.sqrt(np.where(keep, fz2, 1.0))
    carrier = math.remainder(2 * math.pi * distance / wavelength, 2 * math.pi)
    phase = carrier - 2 * np.pi * distance * f2 / (1.0 / wavelength + fz)
    weight = np.ones_like(f2)
    for n, f in ((padded[1], fx[None, :]), (padded[0], fy[:, None])):
        u = np.abs(distance * f / fz) / (n * pitch / 2)
        t = np.clip((u - (1 - BAND_EDGE)) / BAND_EDGE, 0, 1)
        weight = weight * np.where(u <= 1, np.cos(np.pi / 2 * t) ** 2, 0)
    return keep * weight * np.exp(1j * phase)


class Comparison(NamedTuple):
    """Per slice: ``psnr_db`` and ``ssim`` of the amplitudes (module docstring), and the
    ``scale`` fitted to the whole stack; ``mean_psnr_db``, ``mean_ssim`` over the slices."""

    psnr_db: list
    ssim: list
    scale: float

    @property
    def mean_psnr_db(self) -> float:
        return float(np.mean(self.psnr_db))

    @property
    def mean_ssim(self) -> float:
        return float(np.mean(self.ssim))


def fitted(stack, reference) -> tuple[np.ndarray, float]:
    """``stack`` scaled by the least-squares factor onto ``reference`` (one for all slices)."""
    s = np.asarray(stack, np.float64)
    r = np.asarray(reference, np.float64)
    den = float(np.sum(s * s))
    scale = float(np.sum(s * r)) / den if den > 0 else 0.0
    return s * scale, scale


def compare(stack, reference) -> Comparison:
    """PSNR [dB] and SSIM of each slice of the amplitude ``stack`` (N, H, W) against
    ``reference`` (module docstring).

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.phase import compare
    >>> reference = np.random.default_rng(0).uniform(0, 1, (2, 32, 32))
    >>> c = compare(3 * reference, reference)   # one brightness factor: the same picture
    >>> round(c.scale, 6), round(c.mean_ssim, 6)
    (0.333333, 1.0)
    """
    s, scale = fitted(stack, reference)
    r = np.asarray(reference, np.float64)
    peak = float(r.max())
    if not peak > 0:
        raise InputError("reference stack is dark: nothing to compare against")
    return Comparison(
        [psnr(a / peak, b / peak, data_range=1.0) for a, b in zip(s, r)],
        [ssim(a / peak, b / peak, data_range=1.0) for a, b in zip(s, r)],
        scale,
    )
