"""The sideband (Fourier) filter of an acquired off-axis hologram (Cuche, Marquet & Depeursinge
2000; Takeda, Ina & Kobayashi 1982), with the filters and the reference division that
digital-holography tools use (holospy, PyHoloscope, pyDHM).

An off-axis intensity hologram H = |O|² + |R|² + O·R̄ + Ō·R holds the object wave in its +1
order O·R̄ around −f_R (:mod:`.carrier`). Multiplying H by R/|R|² moves that order to
baseband; an :class:`Aperture` around zero frequency keeps it and drops the others (the twin
Ō·R²/|R|² at 2·f_R, the zero order around f_R). With the orders apart (|f_R| >= 3·radius for an
object band of that radius) the result is the object wave inside its band up to the leakage of
the other orders across the window's edges where the carrier falls between the FFT's bins; a
few passes that estimate those orders from the current object wave and take them away remove
that too (3e-2 to 1e-6 on a diffuse object), leaving the recording's own noise.

Around the filter: intensities subtracted first (``subtract``: the reference beam's |R|², the
object beam's |O|², a dark frame), and the result divided by the same filter's output of a
reference (vacuum) hologram (``reference_hologram``, holospy's ``reference``), which takes the
reference wave's own phase and amplitude, and a carrier between bins, away.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import validate
from ..propagation import grid
from ..scene.hologram import Hologram
from ..validate import InputError, shown
from .carrier import Carrier, check_off_axis, intensity_of, locate, sideband_contrast

ITERATIONS = 8  # passes that take the zero order's and the twin's leakage away ...
CONVERGED = 1e-7  # ... until a pass changes the object wave by less than this (relative)
RADIUS_UNITS = {
    "carrier": None,
    "1/m": 1.0,
    "1/mm": 1e3,
    "1/um": 1e6,
    "1/nm": 1e9,
    "mrad": None,
    "rad": None,
}
EDGES = ("hard", "tanh", "cosine")
WINDOWS = ("none", "hann", "hamming", "blackman", "gaussian", "butterworth")
SHAPES = ("disc", "square")
VANISHING = 1e-9  # a reference hologram's wave below this fraction of its rms cannot divide


@dataclass(frozen=True, slots=True, kw_only=True)
class Aperture:
    """The sideband filter: which frequencies around the +1 order are kept, and how.

    Parameters
    ----------
    radius : float, optional
        The aperture's radius R in ``unit``, > 0; None: the hologram's recorded band where it
        states one, else a third of |f_R| (the widest band whose zero order, twice as wide,
        does not reach it).
    unit : {'carrier', '1/m', '1/mm', '1/um', '1/nm', 'mrad', 'rad'}
        'carrier': a fraction of |f_R| (holospy's 0.5 for strong phase objects, 1/3 for weak
        ones); '1/m' … '1/nm': a spatial frequency; 'mrad', 'rad': the scattering angle θ,
        f = sin θ / λ (needs the wavelength).
    shape : {'disc', 'square'}
        'disc' keeps |f| <= R, 'square' max(|fx|, |fy|) <= R.
    edge : {'hard', 'tanh', 'cosine'}
        'tanh' is holospy's, ½·(1 − tanh((r − R)/(w/2))); 'cosine' a raised cosine from
        R − w/2 to R + w/2 (Tukey's).
    width : float
        The edge's width w as a fraction of the radius, in (0, 1] (holospy's default 0.05).
    window : {'none', 'hann', 'hamming', 'blackman', 'gaussian', 'butterworth'}
        An apodisation across the aperture, r/R from 0 to 1: 'gaussian' has σ = R/2,
        'butterworth' is of order 4, 1/(1 + (r/R)⁸).

    Raises
    ------
    InputError
        Where ``radius`` or ``width`` is not > 0 (``width`` above 1), or a choice is unknown.

    See Also
    --------
    holo_core.sideband : the filter applied to a hologram.

    Notes
    -----
    ``Aperture.holospy()`` is holospy's default filter (a disc of half the distance to the zero
    order, a tanh edge over 5 % of the radius); ``radius_per_m(carrier, wavelength, band)``
    the radius [1/m] for a carrier |f_R| [1/m]; ``weights(fx, fy, radius)`` the filter's
    weights at frequencies [1/m] around the order.

    Examples
    --------
    >>> from holo_core.acquired import Aperture
    >>> a = Aperture.holospy()
    >>> a.edge, a.radius_per_m(1e5, 633e-9)
    ('tanh', 50000.0)
    >>> Aperture(radius=2, unit="mrad").radius_per_m(1e5, 633e-9)
    3159.5...
    """

    radius: float | None = None
    unit: str = "carrier"
    shape: str = "disc"
    edge: str = "hard"
    width: float = 0.05
    window: str = "none"

    def __post_init__(self):
        if self.radius is not None:
            validate.positive("aperture radius", self.radius, self.unit)
        validate.choice("aperture unit", self.unit, tuple(RADIUS_UNITS))
        validate.choice("aperture shape", self.shape, SHAPES)
        validate.choice("aperture edge", self.edge, EDGES)
        validate.choice("aperture window", self.window, WINDOWS)
        width = validate.positive("aperture width", self.width)
        if width > 1:
            raise InputError(
                f"aperture width must be in (0, 1] (a fraction of the radius); "
                f"got {shown(self.width)}"
            )

    @classmethod
    def holospy(cls) -> Aperture:
        """holospy's default filter (``reconstruct_phase``): a disc of half the distance to
        the zero order, its edge a tanh over 5 % of the radius.

        Returns
        -------
        Aperture
        """
        return cls(radius=0.5, unit="carrier", edge="tanh", width=0.05)

    def radius_per_m(self, carrier: float, wavelength: float | None, band: float = 0.0) -> float:
        """The aperture's radius in spatial frequency.

        Parameters
        ----------
        carrier : float
            |f_R| [1/m].
        wavelength : float or None
            Wavelength λ [m]; needed for a radius in 'mrad' or 'rad', and for ``band``.
        band : float
            The hologram's recorded band, sin θ, used where no radius is set (0: none).

        Returns
        -------
        float
            The radius [1/m].

        Raises
        ------
        InputError
            Where an angle needs a wavelength that is None, or is not below π/2.
        """
        if self.radius is None:
            return band / wavelength if band and wavelength else carrier / 3
        if self.unit == "carrier":
            return self.radius * carrier
        if self.unit in ("mrad", "rad"):
            if wavelength is None:
                raise InputError(
                    f"an aperture in {self.unit} needs the wavelength: pass a "
                    f"Hologram, or the radius in 1/m"
                )
            angle = self.radius * (1e-3 if self.unit == "mrad" else 1.0)
            if not angle < math.pi / 2:
                raise InputError(
                    f"aperture radius must be an angle below π/2 rad; got "
                    f"{self.radius!r} {self.unit}"
                )
            return math.sin(angle) / wavelength
        return self.radius * RADIUS_UNITS[self.unit]

    def weights(self, fx: np.ndarray, fy: np.ndarray, radius: float) -> np.ndarray:
        """The filter's weights at frequencies around the order (at 0).

        Parameters
        ----------
        fx, fy : ndarray
            Spatial frequencies [1/m], relative to the order; broadcast together.
        radius : float
            The radius R [1/m] (:meth:`radius_per_m`'s).

        Returns
        -------
        ndarray
            The weights in [0, 1], float64, of the broadcast shape.
        """
        r = np.hypot(fx, fy) if self.shape == "disc" else np.maximum(np.abs(fx), np.abs(fy))
        w = self.width * radius
        if self.edge == "hard":
            edge = (r <= radius).astype(np.float64)
        elif self.edge == "tanh":
            edge = 0.5 * (1 - np.tanh((r - radius) / (0.5 * w)))
        else:
            t = np.clip((r - (radius - w / 2)) / w, 0, 1)
            edge = 0.5 * (1 + np.cos(np.pi * t))
        return edge * _window(self.window, r / radius)


def _window(name: str, u: np.ndarray) -> np.ndarray:
    """The apodisation ``name`` at u = r/R (zero beyond u = 1 for the cosine windows)."""
    if name == "none":
        return np.ones_like(u)
    if name == "gaussian":
        return np.exp(-2 * u * u)
    if name == "butterworth":
        return 1 / (1 + u**8)
    c = np.cos(np.pi * np.minimum(u, 1))
    shapes = {
        "hann": 0.5 + 0.5 * c,
        "hamming": 0.54 + 0.46 * c,
        "blackman": 0.42 + 0.5 * c + 0.08 * (2 * c * c - 1),
    }
    return np.where(u <= 1, shapes[name], 0.0)


@validate.public
def sideband(
    hologram,
    colour: int = 0,
    *,
    pitch=None,
    carrier="auto",
    sideband="lower",
    aperture: Aperture | None = None,
    radius=None,
    reference_hologram=None,
    subtract=(),
    reference_amplitude=None,
    iterations=ITERATIONS,
) -> np.ndarray:
    """Filter the object wave out of an off-axis intensity hologram, its +1 order at baseband.

    Parameters
    ----------
    hologram : Hologram or (H, W) real array
        The intensity hologram; an array needs ``pitch`` (and a ``carrier`` other than
        ``'reference'``, which it has no metadata for).
    colour : int
        Index into a Hologram's wavelengths.
    pitch : float or (x, y), optional
        Sample spacing [m] of an array (a Hologram carries its own).
    carrier : 'auto', 'reference', 'spectrum', (fx, fy) [1/m] or Carrier
        The reference wave's carrier: ``'reference'`` from the hologram's reference angle and
        azimuth, ``'spectrum'`` found by :func:`~holo_core.acquired.find_carrier` (in the
        reference hologram where one is given, as holospy does; near the metadata's carrier
        where the hologram has one, which picks the +1 order out of the pair; else by
        ``sideband``), or given. ``'auto'`` is ``'reference'`` for a Hologram with a tilted
        reference, else ``'spectrum'``.
    sideband : 'lower' or 'upper'
        Which of the pair the spectrum search takes (holospy's ``sb``; see
        :mod:`holo_core.acquired.carrier`).
    aperture : Aperture, optional
        The filter (shape, edge, apodisation, radius in physical units); default a hard disc
        of ``radius``.
    radius : float, optional
        The aperture's radius [1/m] (short for ``Aperture(radius=r, unit='1/m')``).
    reference_hologram : Hologram or (H, W) array, optional
        A reference (vacuum) hologram of the same optics without the object: the result is
        divided by its filtered wave, which removes the reference wave's own phase and
        amplitude (holospy's ``reference``).
    subtract : sequence of (H, W) arrays or Holograms
        Intensities taken from the hologram before filtering (the reference beam's, the
        object beam's, a dark frame).
    reference_amplitude : float, optional
        |R| [field units]: the Hologram's stored amplitude, else 1.
    iterations : int
        Passes that estimate the zero order (a disc of twice the radius) and the twin from
        the current object wave and take them away before filtering again (0: the plain
        filter, as holospy's). Where the carrier falls between the FFT's bins, these orders
        are tones the finite window cuts off, and their spectra leak into the band (3e-2 of
        the object wave on a 256² diffuse object); each pass divides that by 5 or more.

    Returns
    -------
    (H, W) complex64 NumPy array: the object wave O on the hologram's pixel centres (divided by
    the reference hologram's where one is given).

    Raises
    ------
    InlineHologramError
        Where no sideband lies at the carrier (an in-line hologram).

    Notes
    -----
    Of the four terms of H = ``|O|² + |R|² + O·R̄ + Ō·R`` (Eq. 20) the filter keeps O·R̄ (the
    virtual image, Eq. 18) and shifts it to baseband.

    Examples
    --------
    Pure fringes hold a plane object wave of amplitude 1:

    >>> import numpy as np
    >>> from holo_core import sideband
    >>> x = (np.arange(64) - 31.5) * 2e-6
    >>> fringes = np.tile(2 + 2 * np.cos(2 * np.pi * 62500 * x), (64, 1))
    >>> o = sideband(fringes, pitch=2e-6, carrier=(62500.0, 0.0), radius=20000.0)
    >>> o.shape, round(float(abs(o[32, 32])), 3)
    ((64, 64), 1.0)
    """
    h, pitch, wavelength = intensity_of(hologram, colour, pitch)
    h = h - _intensities(subtract, h.shape)
    amplitude = _amplitude(hologram, colour, reference_amplitude)
    reference = (
        None if reference_hologram is None else intensity_of(reference_hologram, colour, pitch)[0]
    )
    if reference is not None and reference.shape != h.shape:
        raise InputError(
            f"reference_hologram must have the hologram's shape {h.shape}; got {reference.shape}"
        )
    validate.choice("sideband", sideband, ("lower", "upper"))
    fc = _carrier(
        hologram, h if reference is None else reference, pitch, wavelength, carrier, sideband
    )
    norm = fc.norm
    if norm == 0:
        raise InputError(
            "carrier must be off-axis (a non-zero frequency); an on-axis "
            "hologram's orders overlap and no filter separates them"
        )
    if aperture is not None and radius is not None:
        raise InputError("give the radius in the aperture or as radius=, not both")
    if aperture is None:
        aperture = (
            Aperture()
            if radius is None
            else Aperture(radius=validate.positive("radius", radius, "1/m"), unit="1/m")
        )
    if not isinstance(aperture, Aperture):
        raise InputError(f"aperture must be an Aperture; got {type(aperture).__name__}")
    band = getattr(hologram, "band", 0.0) if isinstance(hologram, Hologram) else 0.0
    r = aperture.radius_per_m(norm, wavelength, band)
    if r > norm:
        raise InputError(
            f"radius must be <= |carrier| = {norm:.6g} 1/m (beyond it the band "
            f"takes in the zero order); got {r:.6g} 1/m"
        )
    if r > norm / 2 * (1 + 1e-9):
        validate.warn_sampling(
            f"sideband: a band of radius {r:.4g} 1/m reaches past half the "
            f"way to the zero order (|carrier|/2 = {norm / 2:.4g} 1/m): the "
            f"zero order (twice the object's band) overlaps it"
        )
    iterations = validate.integer("iterations", iterations, 0, 100)
    fy, fx = grid.freqs(h.shape[0], pitch[1])[:, None], grid.freqs(h.shape[1], pitch[0])[None, :]
    keep = aperture.weights(fx, fy, r)
    if math.isnan(fc.contrast):  # a given carrier: is there a sideband at it?
        spectrum = np.abs(np.fft.fft2(h - h.mean()))
        check_off_axis(
            Carrier(
                fx=fc.fx,
                fy=fc.fy,
                wavelength=wavelength,
                rule=fc.rule,
                contrast=sideband_contrast(spectrum, pitch, fc.frequency, r),
            )
        )
    o = _filtered(h, fc.frequency, pitch, keep, fx, fy, r, amplitude, iterations)
    if reference is not None:
        o_ref = _filtered(reference, fc.frequency, pitch, keep, fx, fy, r, amplitude, iterations)
        small = np.abs(o_ref) <= VANISHING * np.sqrt(np.mean(np.abs(o_ref) ** 2))
        if small.any():
            raise InputError(
                f"reference_hologram's filtered wave vanishes at {int(small.sum())} "
                f"samples (no fringes there): it cannot divide the object's"
            )
        o = o / o_ref
    return o.astype(np.complex64)


def _filtered(h, carrier, pitch, keep, fx, fy, radius, amplitude, iterations) -> np.ndarray:
    """The +1 order of ``h`` at baseband through the weights ``keep``, the zero order's and
    the twin's leakage taken away by ``iterations`` passes (float64)."""
    rows, cols = h.shape
    y, x = grid.coords(rows, pitch[1])[:, None], grid.coords(cols, pitch[0])[None, :]
    t = _tone(carrier[1], y) * _tone(carrier[0], x)  # R/|R|
    half = fx[:, : cols // 2 + 1] if fx.shape[1] == cols else fx  # rfft2's columns: fx >= 0
    zero = half * half + fy * fy <= 4 * radius * radius

    def low_pass(u, weights):
        return np.fft.ifft2(np.fft.fft2(u) * weights)

    def real_low_pass(u, weights):  # a real field's half spectrum: half the work
        return np.fft.irfft2(np.fft.rfft2(u) * weights, s=u.shape)

    o = low_pass((h - h.mean()) * t / amplitude, keep)
    for _ in range(iterations):  # the zero order and the twin, estimated and taken away
        order = amplitude * o * np.conj(t)  # O·R̄
        z = real_low_pass(h - 2 * order.real, zero)
        new = low_pass((h - z - np.conj(order)) * t / amplitude, keep)
        change = np.linalg.norm(new - o) / max(np.linalg.norm(new), 1e-300)
        o = new
        if change < CONVERGED:
            break
    return o


def _carrier(hologram, h, pitch, wavelength, carrier, sideband) -> Carrier:
    """The carrier ``carrier`` asks for: a Carrier or (fx, fy) as given, the metadata's, or
    found in ``h`` (the hologram, or its reference hologram)."""
    if isinstance(carrier, Carrier):
        return carrier
    stated = _stated(hologram)
    if not isinstance(carrier, str):
        fx, fy = validate.pair("carrier", carrier, "1/m")
        nyquist = (1 / (2 * pitch[0]), 1 / (2 * pitch[1]))
        if abs(fx) > nyquist[0] or abs(fy) > nyquist[1]:
            raise InputError(
                f"carrier must be within the Nyquist frequency ±{nyquist[0]:.6g} "
                f"1/m (x), ±{nyquist[1]:.6g} 1/m (y); got {shown(carrier)}"
            )
        return Carrier(fx=fx, fy=fy, wavelength=wavelength, rule="given")
    validate.choice("carrier", carrier, ("auto", "reference", "spectrum"))
    if carrier == "reference" and stated is None:
        raise InputError(
            "carrier 'reference' needs a Hologram with a tilted reference "
            "(reference_angle > 0); use 'spectrum' or give (fx, fy) [1/m]"
        )
    if carrier == "reference" or (carrier == "auto" and stated is not None):
        return Carrier(
            fx=stated[0],
            fy=stated[1],
            wavelength=wavelength,
            rule="the reference angle and azimuth stated",
        )
    return locate(h, pitch, sideband=sideband, near=stated, wavelength=wavelength)


def _stated(hologram):
    """The carrier (fx, fy) [1/m] of a Hologram's stated reference angle, or None."""
    if not isinstance(hologram, Hologram) or not hologram.reference_angle:
        return None
    s, lam = math.sin(hologram.reference_angle), hologram.wavelengths[0]
    return s * math.cos(hologram.reference_azimuth) / lam, s * math.sin(
        hologram.reference_azimuth
    ) / lam


def _amplitude(hologram, colour, given) -> float:
    if given is None and isinstance(hologram, Hologram) and hologram.reference_amplitudes:
        given = hologram.reference_amplitudes[colour]
    return 1.0 if given is None else validate.positive("reference_amplitude", given)


def _intensities(frames, shape) -> np.ndarray | float:
    """The sum of ``frames`` (arrays or Holograms of ``shape``) to subtract, or 0."""
    if isinstance(frames, (np.ndarray, Hologram)):
        frames = (frames,)
    total = 0.0
    for k, frame in enumerate(frames):
        a = frame.intensity[0] if isinstance(frame, Hologram) else frame
        a = validate.host_field(f"subtract[{k}]", a)
        if a.shape != shape or np.iscomplexobj(a):
            raise InputError(
                f"subtract[{k}] must be a real intensity of the hologram's shape "
                f"{shape}; got {a.dtype} {a.shape}"
            )
        total = total + a.astype(np.float64)
    return total


def _tone(f: float, x: np.ndarray) -> np.ndarray:
    """exp(i2π·f·x) with the phase reduced in float64 (f [1/m], x [m])."""
    return np.exp(2j * np.pi * np.remainder(f * x, 1.0))
