"""The sideband (Fourier) filter of an acquired off-axis hologram (Cuche, Marquet & Depeursinge
2000; Takeda, Ina & Kobayashi 1982).

An off-axis intensity hologram H = |O|² + |R|² + O·R̄ + Ō·R holds the object wave in its
+1 order O·R̄, whose spectrum sits around f_O − f_R, where f_R = (sin ϑ cos φ, sin ϑ sin φ)/λ is
the reference wave's carrier (Eq. 4). Multiplying H by R/|R|² moves that order to baseband; a
disc of radius ``radius`` around zero frequency keeps it and drops the others (the twin Ō·R²/|R|²
at 2·f_R, the zero order around f_R). With the orders apart (|f_R| >= 3·radius for an object
band of that radius), the result is the object wave inside its band up to the leakage of the
other orders across the window's edges where the carrier falls between the FFT's bins; a few
passes that estimate those orders from the current object wave and take them away remove
that too (3e-2 to 1e-6 on a diffuse object), leaving the recording's own noise. :func:`~holo_core.plate.reconstruct` is the same product without the
disc: it keeps the zero order and the twin (1.1 of the object wave's norm on a diffuse object).

The carrier comes from the hologram's reference (its metadata) or from the spectrum
(:func:`find_carrier`): the strongest peak away from zero frequency, refined between the FFT's
bins by a zoomed Fourier transform (a tone's peak lies exactly at its frequency), which finds
the undiffracted light of a transmission sample or the object's brightest direction.
"""

from __future__ import annotations

import math

import numpy as np

from .. import validate
from ..propagation import grid
from ..scene.hologram import Hologram
from ..validate import InputError

DC_EXCLUSION = 0.1  # the search skips |f| below this fraction of the Nyquist frequency ...
MIN_DC_BINS = 4     # ... and at least this many FFT bins around zero
ZOOM = 16           # sub-bin steps per level of the carrier's refinement (3 levels: 1/4096 bin)
ITERATIONS = 8      # passes that take the zero order's and the twin's leakage away ...
CONVERGED = 1e-7    # ... until a pass changes the object wave by less than this (relative)


def sideband(hologram, colour: int = 0, *, pitch=None, carrier="auto", radius=None,
             reference_amplitude=None, iterations=ITERATIONS) -> np.ndarray:
    """The object wave of an off-axis intensity hologram, its +1 order shifted to baseband.

    Parameters
    ----------
    hologram : Hologram or (H, W) real array
        The intensity hologram; an array needs ``pitch`` (and a ``carrier`` other than
        ``'reference'``, which it has no metadata for).
    colour : int
        Index into a Hologram's wavelengths.
    pitch : float, optional
        Sample spacing [m] of an array (a Hologram carries its own).
    carrier : 'auto', 'reference', 'spectrum' or (fx, fy)
        The reference wave's transverse frequency [1/m]: ``'reference'`` from the hologram's
        reference angle and azimuth, ``'spectrum'`` found by :func:`find_carrier` (near the
        reference's carrier when the hologram has a tilted one, which picks the +1 order out of
        the pair; otherwise the +1 order of a reference tilted towards +x), or given. ``'auto'``
        is ``'reference'`` for a Hologram with a tilted reference, else ``'spectrum'``.
    radius : float, optional
        Radius [1/m] of the band kept around the +1 order: by default the hologram's recorded
        band (sin θ/λ) where it has one, else |carrier|/3, the widest band whose zero order
        (twice as wide) does not reach it.
    reference_amplitude : float, optional
        |R| [field units]: the Hologram's stored amplitude, else 1.
    iterations : int
        Passes that estimate the zero order (a disc of twice ``radius``) and the twin from
        the current object wave and take them away before filtering again (0: the plain
        filter). Where the carrier falls between the FFT's bins, these orders are tones the
        finite window cuts off, and their spectra leak into the band (3e-2 of the object wave
        on a 256² diffuse object); each pass divides that by 5 or more.

    Returns
    -------
    (H, W) complex64 NumPy array: the object wave O on the hologram's pixel centres.
    """
    h, pitch, reference, amplitude = _intensity(hologram, colour, pitch, carrier,
                                                reference_amplitude)
    fc = _carrier(h, pitch, carrier, reference)
    norm = math.hypot(*fc)
    if norm == 0:
        raise InputError("carrier must be off-axis (a non-zero frequency); an on-axis "
                         "hologram's orders overlap and no filter separates them")
    if radius is None:
        band = getattr(hologram, "band", 0.0)
        radius = band / hologram.wavelengths[colour] if band else norm / 3
    radius = validate.positive("radius", radius, "1/m")
    if radius > norm:
        raise InputError(f"radius must be <= |carrier| = {norm:.6g} 1/m (beyond it the band "
                         f"takes in the zero order); got {radius!r}")
    if radius > norm / 3 * (1 + 1e-9):
        validate.warn_sampling(f"sideband: a band of radius {radius:.4g} 1/m overlaps the zero "
                               f"order (|O|² reaches twice the object band) unless the object "
                               f"band is <= |carrier|/3 = {norm / 3:.4g} 1/m")
    iterations = validate.integer("iterations", iterations, 0, 100)
    rows, cols = h.shape
    y, x = grid.coords(rows, pitch)[:, None], grid.coords(cols, pitch)[None, :]
    t = _tone(fc[1], y) * _tone(fc[0], x)  # R/|R|
    fy, fx = grid.freqs(rows, pitch)[:, None], grid.freqs(cols, pitch)[None, :]
    f2 = fx * fx + fy * fy
    band, zero = f2 <= radius * radius, f2 <= 4 * radius * radius

    def low_pass(u, keep):
        return np.fft.ifft2(np.fft.fft2(u) * keep)

    o = low_pass((h - h.mean()) * t / amplitude, band)
    for _ in range(iterations):  # the zero order and the twin, estimated and taken away
        order = amplitude * o * np.conj(t)  # O·R̄
        z = low_pass(h - 2 * order.real, zero).real
        new = low_pass((h - z - np.conj(order)) * t / amplitude, band)
        change = np.linalg.norm(new - o) / max(np.linalg.norm(new), 1e-300)
        o = new
        if change < CONVERGED:
            break
    return o.astype(np.complex64)


def find_carrier(hologram, colour: int = 0, *, pitch=None, near=None) -> tuple[float, float]:
    """The reference wave's carrier (fx, fy) [1/m] of an off-axis intensity hologram, from the
    peak of its +1 order.

    The peak of |FFT| of the Hann-windowed, mean-free hologram outside the zero order
    (|f| >= ``DC_EXCLUSION`` of Nyquist, at least ``MIN_DC_BINS`` bins) is refined between
    bins by three levels of a zoomed Fourier transform to 1/4096 bin. The peak p of the +1
    order O·R̄ lies at −f_R; the twin's peak at +f_R has the same height, so the pair is told
    apart by ``near`` (fx, fy) [1/m] (a carrier it should be close to, e.g. from the reference
    angle; then only the half of the spectrum around −near is searched) or, without it, by
    taking the reference tilted towards +x (fx > 0, or fy > 0 when fx = 0).

    ``hologram`` is a Hologram (``colour`` picks the wavelength) or an (H, W) real array with
    its ``pitch`` [m].
    """
    h, pitch, _, _ = _intensity(hologram, colour, pitch, "spectrum", None)
    if near is not None:
        near = validate.pair("near", near, "1/m")
    return _find(h, pitch, near)


def _intensity(hologram, colour, pitch, carrier, amplitude):
    """(float64 intensity, pitch, the metadata's carrier or None, |R|)."""
    if isinstance(hologram, Hologram):
        colour = validate.index("colour", colour, len(hologram.wavelengths))
        if getattr(hologram, "intensity", None) is None:
            raise InputError("hologram must be an intensity hologram (a complex one holds its "
                             "object wave already: hologram.object_wave)")
        h = np.asarray(hologram.intensity[colour], np.float64)
        if pitch is not None and validate.pitch("pitch", pitch) != hologram.pitch:
            raise InputError(f"pitch {pitch!r} differs from the hologram's {hologram.pitch!r} m; "
                             f"leave it out for a Hologram")
        pitch, lam = hologram.pitch, hologram.wavelengths[colour]
        s = math.sin(hologram.reference_angle)
        reference = None if s == 0 else (s * math.cos(hologram.reference_azimuth) / lam,
                                         s * math.sin(hologram.reference_azimuth) / lam)
        if amplitude is None and hologram.reference_amplitudes:
            amplitude = hologram.reference_amplitudes[colour]
    else:
        h = validate.host_field("hologram", hologram)
        if np.iscomplexobj(h):
            raise InputError("hologram must be a real intensity array (H, W) or a Hologram; "
                             "got a complex array")
        h = h.astype(np.float64)
        if pitch is None:
            raise InputError("pitch must be given [m] for a hologram passed as an array")
        pitch, reference = validate.pitch("pitch", pitch), None
    if isinstance(carrier, str):
        validate.choice("carrier", carrier, ("auto", "reference", "spectrum"))
        if carrier == "reference" and reference is None:
            raise InputError("carrier 'reference' needs a Hologram with a tilted reference "
                             "(reference_angle > 0); use 'spectrum' or give (fx, fy) [1/m]")
    amplitude = 1.0 if amplitude is None else validate.positive("reference_amplitude",
                                                                amplitude)
    return h, pitch, reference, amplitude


def _carrier(h, pitch, carrier, reference) -> tuple[float, float]:
    if not isinstance(carrier, str):
        fx, fy = validate.pair("carrier", carrier, "1/m")
        nyquist = 1 / (2 * pitch)
        if max(abs(fx), abs(fy)) > nyquist:
            raise InputError(f"carrier must be within the Nyquist frequency ±{nyquist:.6g} 1/m "
                             f"per axis; got {carrier!r}")
        return fx, fy
    if carrier == "reference" or (carrier == "auto" and reference is not None):
        return reference
    return _find(h, pitch, reference)


def _find(h, pitch, near) -> tuple[float, float]:
    rows, cols = h.shape
    if min(rows, cols) < 4 * MIN_DC_BINS:
        raise InputError(f"hologram must be at least {4 * MIN_DC_BINS}x{4 * MIN_DC_BINS} "
                         f"samples to find its carrier; got {rows}x{cols}")
    w = (h - h.mean()) * np.outer(np.hanning(rows), np.hanning(cols))
    mag = np.abs(np.fft.fft2(w))
    ky, kx = grid.signed_indices(rows)[:, None], grid.signed_indices(cols)[None, :]
    fy, fx = ky / (rows * pitch), kx / (cols * pitch)
    f2 = fx * fx + fy * fy
    dc = max(DC_EXCLUSION / (2 * pitch), MIN_DC_BINS / (min(rows, cols) * pitch))
    allowed = f2 >= dc * dc
    if near is not None:  # the half of the spectrum around the +1 order at -near
        allowed &= fx * near[0] + fy * near[1] < 0
    if not allowed.any() or not mag[allowed].any():
        raise InputError("hologram has no fringes to find a carrier in (its spectrum is empty "
                         "outside the zero order)")
    i, j = np.unravel_index(np.argmax(np.where(allowed, mag, -1.0)), mag.shape)
    py, px = _refine(w, float(ky[i, 0]), float(kx[0, j]))
    carrier = (-px / (cols * pitch), -py / (rows * pitch))  # the +1 order lies at -f_R
    if near is None and (carrier[0] < 0 or (carrier[0] == 0 and carrier[1] < 0)):
        carrier = (-carrier[0], -carrier[1])  # the twin's reading: take the reference's +x tilt
    return carrier


def _refine(w, ky: float, kx: float) -> tuple[float, float]:
    """The peak of |DTFT(w)| near bin (ky, kx), in fractional bins: three zoom levels of
    ``ZOOM`` steps over ±1, ±1/ZOOM and ±1/ZOOM² bins."""
    rows, cols = w.shape
    y, x = np.arange(rows), np.arange(cols)
    span = 1.0
    for _ in range(3):
        d = np.linspace(-span, span, 2 * ZOOM + 1)
        ey = np.exp(-2j * np.pi * np.outer(ky + d, y) / rows)
        ex = np.exp(-2j * np.pi * np.outer(x, kx + d) / cols)
        a = np.abs(ey @ w @ ex)
        i, j = np.unravel_index(np.argmax(a), a.shape)
        ky, kx = ky + d[i], kx + d[j]
        span /= ZOOM
    return ky, kx


def _tone(f: float, x: np.ndarray) -> np.ndarray:
    """exp(i2π·f·x) with the phase reduced in float64 (f [1/m], x [m])."""
    return np.exp(2j * np.pi * np.remainder(f * x, 1.0))
