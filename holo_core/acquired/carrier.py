"""The carrier of an off-axis hologram, found in its spectrum by a stated rule.

An off-axis intensity hologram H = |O|² + |R|² + O·R̄ + Ō·R holds the object wave in its +1
order O·R̄, whose spectrum sits around −f_R, and the twin Ō·R around +f_R, where
f_R = (sin ϑ cos φ, sin ϑ sin φ)/λ is the reference wave's carrier (Eq. 4). The two peaks have
the same height (H is real), so the spectrum alone cannot say which is the +1 order: a rule
must, and this is it (:func:`find_carrier`):

1. The peak of |FFT| of the mean-free, Hann-windowed hologram outside the zero order
   (|f| >= max(10 % of the Nyquist frequency, 4 bins)), in the half of the spectrum the rule
   names: ``sideband='lower'`` (the default, holospy's ``sb='lower'``) takes the carrier
   f_R with f_y > 0, or f_y = 0 and f_x >= 0, i.e. the peak in the rows [0, N/2) of the
   unshifted FFT, as holospy searches; ``'upper'`` the other half. Given a carrier to be near
   (``near``, e.g. the reference angle of the file's metadata), the half around it.
2. The peak's bin, refined between bins by three levels of a zoomed Fourier transform to
   1/4096 bin (a tone's peak lies at its frequency); ``refine=False`` keeps the bin, as
   holospy does.
3. The hologram is off-axis only if the disc around the carrier holds at least
   :data:`OFF_AXIS_CONTRAST` times the energy of the same disc turned by 90° about the zero
   order: an in-line hologram's orders overlap at zero frequency and spread evenly around it,
   so it fails this test and is refused (:class:`InlineHologramError`), not filtered into
   nonsense.

Where the object's distance is known, the order can be decided by physics instead
(:func:`holo_core.acquired.scan.object_hologram`): the +1 order is the one that comes into
focus behind the hologram.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import validate
from ..propagation import grid
from ..scene.hologram import Hologram
from ..validate import InputError

DC_EXCLUSION = 0.1  # the search skips |f| below this fraction of the Nyquist frequency ...
MIN_DC_BINS = 4  # ... and at least this many FFT bins around zero
ZOOM = 16  # sub-bin steps per level of the carrier's refinement (3 levels: 1/4096 bin)
OFF_AXIS_CONTRAST = 4.0  # sideband energy over the same disc turned by 90°, at least
SIDEBANDS = ("lower", "upper")


class InlineHologramError(InputError):
    """A hologram whose spectrum has no sideband apart from the zero order.

    It is in-line (or its fringes are lost in noise): no sideband filter separates its orders.
    A subclass of :class:`~holo_core.InputError`, raised by :func:`find_carrier` and
    :func:`~holo_core.acquired.sideband` where the disc around the strongest peak holds less
    than ``OFF_AXIS_CONTRAST`` (4) times the energy of the same disc turned by 90°.

    Examples
    --------
    A hologram without fringes (a constant with a little noise) has no carrier:

    >>> import numpy as np
    >>> from holo_core.acquired import InlineHologramError, find_carrier
    >>> flat = 1 + 1e-3 * np.random.default_rng(0).standard_normal((64, 64))
    >>> try:
    ...     find_carrier(flat, pitch=2e-6)
    ... except InlineHologramError:
    ...     print("in-line")
    in-line
    """


@dataclass(frozen=True, slots=True, kw_only=True)
class Carrier:
    """The reference wave's carrier f_R of an off-axis hologram and how it was found.

    Parameters
    ----------
    fx, fy : float
        The carrier's spatial frequency [1/m]; the +1 order O·R̄ lies at −(fx, fy).
    wavelength : float, optional
        Wavelength λ [m], for the angles (None: unknown, and ``angle`` is None).
    rule : str
        How it was found ('the spectrum's peak, lower sideband', 'given', ...).
    contrast : float
        The sideband's energy over the same disc turned by 90° (NaN: not measured).
    half : {'lower', 'upper'}, optional
        The half of the spectrum it was found in (None: by the sign of its components).

    Notes
    -----
    Its properties: ``frequency`` (fx, fy) [1/m]; ``norm`` |f_R| [1/m]; ``sideband``, 'lower'
    (f_y > 0, or f_y = 0 and f_x >= 0) or 'upper', as holospy names them; ``angle``, the
    reference's angle ϑ [rad] to the hologram's normal, asin(λ·|f_R|) (Eq. 4), None without a
    wavelength or where λ·|f_R| >= 1; ``azimuth``, φ [rad] from +x towards +y, atan2(fy, fx).

    See Also
    --------
    find_carrier : the carrier found in a hologram's spectrum.

    Examples
    --------
    >>> from holo_core.acquired import Carrier
    >>> c = Carrier(fx=3e4, fy=4e4, wavelength=633e-9)
    >>> c.norm, c.sideband, round(c.angle, 5)
    (50000.0, 'lower', 0.03166)
    >>> c.describe()
    'carrier (30000, 40000) 1/m, reference at 1.814° (31.66 mrad), azimuth 53.13°, ...'
    """

    fx: float
    fy: float
    wavelength: float | None = None
    rule: str = "given"
    contrast: float = float("nan")
    half: str | None = None

    @property
    def frequency(self) -> tuple[float, float]:
        """(fx, fy) [1/m]."""
        return self.fx, self.fy

    @property
    def norm(self) -> float:
        """|f_R| [1/m]."""
        return math.hypot(self.fx, self.fy)

    @property
    def sideband(self) -> str:
        """'lower' (f_y > 0, or f_y = 0 and f_x >= 0) or 'upper', as holospy names them (the
        half it was found in: a refined carrier on the f_x axis may stray across it)."""
        if self.half is not None:
            return self.half
        return "lower" if self.fy > 0 or (self.fy == 0 and self.fx >= 0) else "upper"

    @property
    def angle(self) -> float | None:
        """The reference's angle ϑ [rad] to the hologram's normal: asin(λ·|f_R|)."""
        if self.wavelength is None or self.wavelength * self.norm >= 1:
            return None
        return math.asin(self.wavelength * self.norm)

    @property
    def azimuth(self) -> float:
        """The reference's azimuth φ [rad] from +x towards +y: atan2(fy, fx)."""
        return math.atan2(self.fy, self.fx)

    def describe(self) -> str:
        """One line: the carrier [1/m], the angles [°, mrad], the sideband and the rule.

        Returns
        -------
        str
        """
        angle = self.angle
        tilt = (
            ""
            if angle is None
            else (f", reference at {math.degrees(angle):.4g}° ({angle * 1e3:.4g} mrad)")
        )
        contrast = (
            ""
            if math.isnan(self.contrast)
            else f", sideband {self.contrast:.3g}x the disc turned by 90°"
        )
        return (
            f"carrier ({self.fx:.6g}, {self.fy:.6g}) 1/m{tilt}, azimuth "
            f"{math.degrees(self.azimuth):.4g}°, the {self.sideband} sideband ({self.rule})"
            f"{contrast}"
        )


@validate.public
def find_carrier(
    hologram, colour: int = 0, *, pitch=None, sideband="lower", near=None, refine=True
) -> Carrier:
    """Find the reference wave's carrier of an off-axis intensity hologram.

    The rule is the one of this module's docstring.

    Parameters
    ----------
    hologram : Hologram or (H, W) real array
        The intensity hologram; an array needs ``pitch``.
    colour : int
        Index into a Hologram's wavelengths.
    pitch : float or (x, y), optional
        Sample spacing [m] of an array (a Hologram carries its own).
    sideband : 'lower' or 'upper'
        Which of the pair is the carrier (holospy's ``sb``): 'lower' f_y > 0 (f_y = 0:
        f_x >= 0), 'upper' the other half.
    near : (fx, fy) [1/m], optional
        A carrier it should be close to (e.g. from the reference angle): the half of the
        spectrum around it is searched instead of ``sideband``'s.
    refine : bool
        Refine the peak between bins (to 1/4096 bin); False keeps the peak's bin.

    Returns
    -------
    Carrier (with the hologram's wavelength, for its angle).

    Raises
    ------
    InlineHologramError
        Where the found peak is no sideband (an in-line hologram).

    Notes
    -----
    The hologram H = ``|O|² + |R|² + O·R̄ + Ō·R`` (Eq. 20) holds the virtual image's order O·R̄
    around −f_R and the twin around +f_R; the carrier f_R is the sideband's peak.

    Examples
    --------
    Fringes of 62.5 mm⁻¹ (8 samples a period at 2 µm):

    >>> import numpy as np
    >>> from holo_core import find_carrier
    >>> x = (np.arange(64) - 31.5) * 2e-6
    >>> fringes = np.tile(2 + 2 * np.cos(2 * np.pi * 62500 * x), (64, 1))
    >>> c = find_carrier(fringes, pitch=2e-6)
    >>> round(c.fx, -2), round(c.fy, -2)
    (62500.0, 0.0)
    """
    h, pitch, wavelength = intensity_of(hologram, colour, pitch)
    validate.choice("sideband", sideband, SIDEBANDS)
    if near is not None:
        near = validate.pair("near", near, "1/m")
    return locate(h, pitch, sideband=sideband, near=near, refine=refine, wavelength=wavelength)


def intensity_of(hologram, colour, pitch):
    """(float64 intensity (H, W), pitch (x, y) [m], wavelength [m] or None) of a Hologram
    or an array with its pitch."""
    if isinstance(hologram, Hologram):
        colour = validate.index("colour", colour, len(hologram.wavelengths))
        if getattr(hologram, "intensity", None) is None:
            raise InputError(
                "hologram must be an intensity hologram (a complex one holds its "
                "object wave already: hologram.object_wave)"
            )
        if pitch is not None and grid.pitch_pair(pitch) != (hologram.pitch,) * 2:
            raise InputError(
                f"pitch {pitch!r} differs from the hologram's {hologram.pitch!r} m; "
                f"leave it out for a Hologram"
            )
        return (
            np.asarray(hologram.intensity[colour], np.float64),
            (hologram.pitch,) * 2,
            hologram.wavelengths[colour],
        )
    h = validate.host_field("hologram", hologram)
    if np.iscomplexobj(h):
        raise InputError(
            "hologram must be a real intensity array (H, W) or a Hologram; got a complex array"
        )
    if pitch is None:
        raise InputError("pitch must be given [m] for a hologram passed as an array")
    return h.astype(np.float64), grid.pitch_pair(pitch), None


def locate(
    h: np.ndarray, pitch, *, sideband="lower", near=None, refine=True, wavelength=None
) -> Carrier:
    """:func:`find_carrier` of a checked float64 intensity ``h`` with ``pitch`` (x, y) [m]."""
    rows, cols = h.shape
    if min(rows, cols) < 4 * MIN_DC_BINS:
        raise InputError(
            f"hologram must be at least {4 * MIN_DC_BINS}x{4 * MIN_DC_BINS} "
            f"samples to find its carrier; got {rows}x{cols}"
        )
    w = (h - h.mean()) * np.outer(np.hanning(rows), np.hanning(cols))
    spectrum = np.abs(np.fft.fft2(w))
    ky, kx = grid.signed_indices(rows)[:, None], grid.signed_indices(cols)[None, :]
    fy, fx = ky / (rows * pitch[1]), kx / (cols * pitch[0])
    nyquist = min(1 / (2 * pitch[0]), 1 / (2 * pitch[1]))
    dc = max(DC_EXCLUSION * nyquist, MIN_DC_BINS / min(rows * pitch[1], cols * pitch[0]))
    allowed = fx * fx + fy * fy >= dc * dc
    if near is not None:  # the carrier's side: the half of the spectrum around near
        allowed &= fx * near[0] + fy * near[1] > 0
        rule = "the spectrum's peak nearest the stated reference"
    else:
        lower = (ky > 0) | ((ky == 0) & (kx >= 0))
        allowed &= lower if sideband == "lower" else ~lower
        rule = f"the spectrum's peak, {sideband} sideband"
    if not allowed.any() or not spectrum[allowed].any():
        raise InlineHologramError(
            "hologram has no fringes to find a carrier in (its spectrum "
            "is empty outside the zero order)"
        )
    i, j = np.unravel_index(np.argmax(np.where(allowed, spectrum, -1.0)), spectrum.shape)
    py, px = float(ky[i, 0]), float(kx[0, j])
    half = "lower" if py > 0 or (py == 0 and px >= 0) else "upper"
    if refine:
        py, px = _refine(w, py, px)
        rule += ", refined to 1/4096 bin"
    carrier = (px / (cols * pitch[0]), py / (rows * pitch[1]))
    contrast = sideband_contrast(spectrum, pitch, carrier)
    found = Carrier(
        fx=carrier[0], fy=carrier[1], wavelength=wavelength, rule=rule, contrast=contrast, half=half
    )
    check_off_axis(found)
    return found


def sideband_contrast(spectrum: np.ndarray, pitch, carrier, radius=None) -> float:
    """The energy of |``spectrum``|² (FFT order) in the disc of ``radius`` [1/m] (default
    |carrier|/4) around ``carrier`` and its twin, over that in the same discs turned by 90°
    about the zero order. An off-axis hologram's sideband makes it large; an in-line one's
    even spread makes it about 1."""
    rows, cols = spectrum.shape
    fy = grid.freqs(rows, pitch[1])[:, None]
    fx = grid.freqs(cols, pitch[0])[None, :]
    cx, cy = carrier
    r2 = (radius or math.hypot(cx, cy) / 4) ** 2
    power = spectrum * spectrum

    def energy(x, y):
        near = ((fx - x) ** 2 + (fy - y) ** 2 <= r2) | ((fx + x) ** 2 + (fy + y) ** 2 <= r2)
        return float(power[near].sum())

    turned = energy(-cy, cx)
    return energy(cx, cy) / turned if turned > 0 else float("inf")


def check_off_axis(carrier: Carrier) -> None:
    """:class:`InlineHologramError` when ``carrier``'s contrast says there is no sideband."""
    if carrier.contrast < OFF_AXIS_CONTRAST:
        raise InlineHologramError(
            f"hologram looks in-line: around its strongest peak away from zero frequency, "
            f"{carrier.describe()}, the spectrum holds {carrier.contrast:.3g} times the energy "
            f"of the same disc turned by 90° (an off-axis hologram's sideband holds "
            f">= {OFF_AXIS_CONTRAST:g} times); an in-line hologram's orders overlap at zero "
            f"frequency and no sideband filter separates them: propagate (H - mean)/|R| with "
            f"holo_core.acquired.refocus for its in-line reconstruction (twin included)"
        )


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
