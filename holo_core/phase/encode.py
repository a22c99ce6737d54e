"""A complex wave at a phase display made into the codes the display shows, one laser at a
time, quantised to its bits through its look-up table.

- ``double-phase``: the wave low-passed to the band the display's Fourier filter passes, then
  checkerboarded double-phase (:func:`holo_core.phase.encoding.double_phase`): the filter
  removes the checkerboard's second term around the Nyquist corner (it needs band <= 0.5).
- ``gradient-descent``: Adam (Kingma & Ba 2015) on the phase, warm-started from
  double-phase, descending L = Σ_k ‖σ·|A_k·u| − a_k‖² / Σ_k ‖a_k‖² over the focal stack's
  planes k (``slices_per_step`` of them drawn at random each step, all when None): A_k the
  exact band-limited angular spectrum through the filter and pupil (:class:`.stack.Optics`),
  a_k the complex wave's own amplitudes there, σ the best scale in closed form. Its gradient
  is exact, 2·Im(G·ū) with G = Σ_k A_kᴴ(σ(σ|v_k| − a_k)·v_k/|v_k|) / Σ‖a_k‖². The last
  ``quantised_steps`` steps see the quantised phase (the codes' response) in the forward
  pass and move the continuous one (a straight-through estimator), so the descent ends on
  what the display can show.
- ``gerchberg-saxton``: the planes visited in turn (one a step), each imposing its amplitude
  a_k on the phase the display's light has there and coming back by A_kᴴ to a phase-only
  field (Gerchberg & Saxton 1972, multi-plane as in Zhang et al. 2017), warm-started from
  double-phase.

Every method ends in :func:`holo_core.phase.levels.quantise`: codes 0 .. 2^b − 1, never
outside the bit depth, through the table for the laser's wavelength when tables are given.
"""

from __future__ import annotations

import logging
import math
import time
from typing import NamedTuple

import numpy as np

from .. import validate
from ..validate import InputError
from . import levels
from .display import Display
from .encoding import double_phase
from .slm import SLMSetup, table_for
from .stack import Optics, fft2, ifft2

log = logging.getLogger(__name__)
METHODS = ("double-phase", "gradient-descent", "gerchberg-saxton")
# Adam's step for a warm start from double-phase [rad]: bench/display.py --quick measured
# 0.02 to 0.05 alike; larger steps leave the warm start's basin
LEARNING_RATE = 0.03
AUTO = "auto"
# the clip fractions double-phase's search spans: 0.4 leaves the bright half of a scene
# unmodulated, beyond the scenes' best (Performance: figures behind the constants)
MOST_CLIPPED = 0.4
# patterns the search makes (the unclipped one among them): the fraction to 0.4·0.618^6 =
# 0.022, where the focal stack's PSNR is flat to 0.05 dB; a trial costs a transform
CLIP_TRIALS = 8
GOLDEN = (math.sqrt(5) - 1) / 2
# the iterative methods' warm start clipped lightly: they mend the checkerboard's leak but
# hardly restore a bright point's clipped amplitude (Performance: figures behind the constants)
WARM_START_CLIP = 0.02


class Pattern(NamedTuple):
    """What :func:`encode` gives.

    codes : (rows, cols) uint16, 0 .. 2^bit_depth − 1: what the driver shows
    phase : (rows, cols) float32 [rad]: the phase those codes show (the response at each)
    wavelength : [m]
    method : the encoding
    table : the table's source ('' for the display's line)
    losses : the descent's or the projections' normalised amplitude error per step
    seconds : the encoding's wall time [s]
    """

    codes: np.ndarray
    phase: np.ndarray
    wavelength: float
    method: str
    table: str
    losses: list
    seconds: float


def encode(
    field,
    display,
    *,
    wavelength,
    method="double-phase",
    tables=(),
    band=None,
    distances=None,
    pupil=None,
    iterations=100,
    learning_rate=LEARNING_RATE,
    slices_per_step=None,
    quantised_steps=None,
    seed=0,
    clip_fraction=AUTO,
    optics=None,
    targets=None,
) -> Pattern:
    """Encode the complex ``field`` at the display as the codes a phase SLM shows.

    Parameters
    ----------
    field : (rows, cols) complex array
        The wave at the display's plane, on its grid [field units].
    display : Display or SLMSetup
        The SLM (a setup brings its tables, band and focal stack's planes).
    wavelength : float
        The laser's wavelength [m].
    method : {'double-phase', 'gradient-descent', 'gerchberg-saxton'}
    tables : sequence of PhaseTable
        Per wavelength; the one for ``wavelength`` is used (InputError naming it when
        absent). Default: the setup's, or none (the display's line).
    band : float, optional
        The Fourier filter's fraction of Nyquist, (0, 1]; default the setup's, else 0.5.
    distances : sequence of float, optional
        The focal stack's planes [m] the iterative methods fit; default the setup's, else
        the display's plane (0).
    pupil : (x, y, diameter, distance), optional
        The eye's pupil for the fit [m] (:class:`.stack.Optics`); default the whole band.
    iterations : int
        Steps of the iterative methods, in [0, 100000].
    learning_rate : float
        Adam's step [rad].
    slices_per_step : int, optional
        Planes drawn at random per descent step (None: all).
    quantised_steps : int, optional
        The descent's last steps that see the quantised phase (default 10, or every step
        when fewer).
    seed : int
        The generator drawing the planes.
    clip_fraction : float or 'auto'
        The fraction of the band-limited wave's samples, the brightest, whose amplitude
        double-phase may clip to the rest's largest, in [0, 0.5) (0: none, the largest
        amplitude is the pattern's full modulation). ``'auto'`` (default): for
        double-phase the fraction whose pattern the display's filter passes closest to the
        wave (:func:`best_clip_fraction`), the scene's own; for the iterative methods' warm
        start WARM_START_CLIP. Logged.
    optics, targets : optional
        An :class:`.stack.Optics` for this grid and laser and the field's amplitude stack on
        its planes, when the caller has them already (a bench that also simulates).

    Returns
    -------
    Pattern

    Raises
    ------
    InputError
        A field that is not a finite 2-D array of the display's shape, all zero; a method,
        band or table out of range; a wavelength without its table.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.phase.display import Display
    >>> from holo_core.phase.encode import encode
    >>> slm = Display(name="lab", resolution=(64, 48), pitch=8e-6)
    >>> p = encode(np.ones((48, 64), complex), slm, wavelength=520e-9)
    >>> p.codes.dtype, int(p.codes.max()) < 256
    (dtype('uint16'), True)
    """
    start = time.perf_counter()
    setup = display if isinstance(display, SLMSetup) else None
    display = setup.display if setup else display
    if not isinstance(display, Display) or display.kind != "phase":
        raise InputError(
            f"display must be a phase Display or an SLMSetup; got {type(display).__name__}"
        )
    method = validate.choice("method", method, METHODS)
    wavelength = validate.wavelength("wavelength", wavelength)
    table = table_for(tables or (setup.tables if setup else ()), wavelength)
    band = validate.positive("band", band if band is not None else (setup.band if setup else 0.5))
    if distances is None:
        distances = setup.distances() if setup else [0.0]
    u = np.asarray(validate.host_field("field", field))
    if u.shape != display.shape:
        raise InputError(
            f"field must be the display's {display.shape[1]}x{display.shape[0]} "
            f"samples (rows, cols) {display.shape}; got {u.shape}"
        )
    if not np.abs(u).max() > 0:
        raise InputError("field is zero on the display: nothing to encode")
    if optics is None:
        optics = Optics(
            display.shape,
            pitch=display.pitch,
            wavelength=wavelength,
            distances=distances,
            band=band,
            pupil=pupil,
        )
    curve = levels.response(display, table)
    quantise = levels.Quantiser(curve)
    clip = _clip_fraction(clip_fraction)
    if clip == AUTO and method != "double-phase":
        clip = WARM_START_CLIP
    phase = _double_phase(u, optics, clip)
    losses = []
    if method != "double-phase":
        iterations = validate.integer("iterations", iterations, 0, 100_000)
        a = optics.stack(u) if targets is None else np.asarray(targets, np.float32)
        if method == "gradient-descent":
            phase, losses = _descend(
                phase,
                a,
                optics,
                curve,
                quantise,
                iterations,
                validate.positive("learning_rate", learning_rate, "rad"),
                slices_per_step,
                validate.integer(
                    "quantised_steps",
                    min(10, iterations) if quantised_steps is None else quantised_steps,
                    0,
                    iterations,
                ),
                validate.seed(seed),
            )
        else:
            phase, losses = _projections(phase, a, optics, iterations)
    codes = quantise(phase)
    return Pattern(
        codes,
        curve[codes].astype(np.float32),
        wavelength,
        method,
        table.source if table else "",
        losses,
        time.perf_counter() - start,
    )


def low_passed(u, optics: Optics) -> np.ndarray:
    """``u`` through the display's Fourier filter, on its window (complex64)."""
    return optics.window(optics.spectrum(u))


def _clip_fraction(value):
    if isinstance(value, str) and value == AUTO:
        return AUTO
    clip = validate.finite("clip_fraction", value)
    if not 0 <= clip < 0.5:
        raise InputError(f"clip_fraction must be in [0, 0.5) or 'auto'; got {value!r}")
    return clip


def _double_phase(u, optics: Optics, clip) -> np.ndarray:
    """Double-phase phases [rad] of ``u`` band-limited to the filter (float64), the
    brightest ``clip`` of its samples clipped to the others' largest amplitude (``'auto'``:
    the fraction :func:`best_clip_fraction` finds)."""
    if optics.band > 0.5 + 1e-9:
        raise InputError(
            f"double-phase needs the display's filter to stop at half the Nyquist "
            f"frequency or below (band <= 0.5), where its checkerboard term is "
            f"cut; got band {optics.band:g}"
        )
    c = np.asarray(low_passed(u, optics), np.complex128)
    if clip == AUTO:
        clip = best_clip_fraction(c, optics)
    if clip > 0:
        a = np.abs(c)
        top = float(np.quantile(a, 1 - clip))
        if top > 0:
            log.info(
                "double-phase: %.3g %% of the samples clipped from up to %.4g to %.4g "
                "(clip_fraction %.3g)",
                100 * float(np.mean(a > top)),
                float(a.max()),
                top,
                clip,
            )
            c = c / np.maximum(1.0, a / top)
    return double_phase(c)


def best_clip_fraction(c, optics: Optics, *, largest=MOST_CLIPPED, trials=CLIP_TRIALS) -> float:
    """The clip fraction in [0, ``largest``] whose double-phase pattern of the band-limited
    wave ``c`` comes through the display's filter closest to ``c`` (a golden-section search,
    and the unclipped pattern: ``trials`` patterns).

    Closeness is the in-band fidelity |<S_p, S_c>|² / (‖S_p‖²‖S_c‖²) of the pattern's spectrum
    S_p and the wave's S_c on the filter's block (through its pupil): one minus the relative
    error of the pattern's light after the best complex scale. Propagation inside the band is
    unitary, so that error bounds the complex error on every plane of a focal stack, at the
    cost of one transform a trial. Clipping trades the bright samples' amplitude for the
    rest's modulation: unclipped, a few bright points leave the scene at small amplitudes,
    where the checkerboard term sin α·exp(iφ) carries most of the light and its spread leaks
    into the band. The best fraction is the scene's own (Performance: figures behind the
    constants).
    """
    a = np.abs(c).astype(np.float32)
    unit = (c / np.where(a > 0, a, 1)).astype(np.complex64)
    keep = optics.keep.astype(np.float32)
    wanted = optics.spectrum(c.astype(np.complex64)) * keep
    wanted_energy = float(np.vdot(wanted, wanted).real)
    rows, cols = np.indices(c.shape, sparse=True)
    sign = np.where((rows + cols) % 2 == 0, 1j, -1j).astype(np.complex64)

    def fidelity(fraction: float) -> float:
        top = float(np.quantile(a, 1 - fraction))  # as _double_phase clips it
        if not top > 0:
            return 0.0
        amplitude = np.minimum(a / top, 1)
        # exp(i(φ ± α)) = exp(iφ)·(cos α ± i sin α), α = arccos A: no arccos, no exp
        pattern = unit * (amplitude + sign * np.sqrt(1 - amplitude * amplitude))
        s = optics.spectrum(pattern) * keep
        return abs(np.vdot(wanted, s)) ** 2 / (wanted_energy * float(np.vdot(s, s).real))

    best, value = _golden_maximum(fidelity, 0.0, largest, trials - 1)
    return best if value > fidelity(0.0) else 0.0


def _golden_maximum(f, lo: float, hi: float, trials: int) -> tuple[float, float]:
    """Where in [lo, hi] the unimodal ``f`` is largest, to (hi − lo)·0.618^(trials − 1), and
    its value there."""
    x1, x2 = hi - GOLDEN * (hi - lo), lo + GOLDEN * (hi - lo)
    f1, f2 = f(x1), f(x2)
    for _ in range(trials - 2):
        if f1 > f2:
            hi, x2, f2 = x2, x1, f1
            x1 = hi - GOLDEN * (hi - lo)
            f1 = f(x1)
        else:
            lo, x1, f1 = x1, x2, f2
            x2 = lo + GOLDEN * (hi - lo)
            f2 = f(x2)
    return (x1, f1) if f1 > f2 else (x2, f2)


def _descend(phase, a, optics, curve, quantise, iterations, rate, per_step, quantised, seed):
    rng = np.random.default_rng(seed)
    n = optics.distances.size
    if per_step is not None:
        per_step = validate.integer("slices_per_step", per_step, 1, n)
    # float32 state: Adam's steps are ~rate = 0.03 rad, float32 keeps 1e-7 rad of a phase
    # within a few waves; the moments updated in place (1080p: 2 M samples a pass)
    phase = np.asarray(phase, np.float32)
    m = np.zeros(phase.shape, np.float32)
    v2 = np.zeros(phase.shape, np.float32)
    step = np.empty(phase.shape, np.float32)
    b1, b2, eps = 0.9, 0.999, 1e-8
    losses = []
    for t in range(1, iterations + 1):
        seen = curve[quantise(phase)] if t > iterations - quantised else phase
        u = unit(seen)
        ks = range(n) if per_step is None else rng.choice(n, per_step, replace=False)
        loss, grad = _loss_and_gradient(u, a, optics, ks)
        losses.append(loss)
        m *= b1
        m += (1 - b1) * grad
        grad *= grad
        v2 *= b2
        v2 += (1 - b2) * grad
        np.sqrt(v2 * np.float32(1 / (1 - b2**t)), out=step)
        step += eps
        np.divide(m, step, out=step)
        step *= np.float32(rate / (1 - b1**t))
        phase -= step
    return phase.astype(np.float64), losses


def _loss_and_gradient(u, a, optics: Optics, ks):
    s = optics.spectrum(u)
    vs = {k: optics.to_plane(s, k) for k in ks}
    mags = {k: np.abs(v) for k, v in vs.items()}
    num = sum(float(np.vdot(mags[k], a[k]).real) for k in ks)
    den = sum(float(np.vdot(mags[k], mags[k]).real) for k in ks)
    norm = sum(float(np.vdot(a[k], a[k]).real) for k in ks)
    sigma = num / den if den > 0 else 0.0
    g = np.zeros_like(s)
    loss = 0.0
    for k in ks:
        mag, v = mags[k], vs[k]
        r = np.float32(sigma) * mag - a[k]
        loss += float(np.vdot(r, r).real)
        # σ·r·v/|v| = σ·(σ·v − a·v/|v|): v/|v| is 0 where v is
        np.maximum(mag, np.float32(1e-30), out=mag)
        np.divide(a[k], mag, out=mag)
        w = v * (np.float32(sigma) - mag)
        w *= np.float32(sigma)
        g += optics.from_plane(w, k)
    b = optics.back(g)
    b *= np.conj(u)
    grad = b.imag * np.float32(2 / norm)
    return loss / norm, grad


def unit(phase) -> np.ndarray:
    """exp(i·phase), complex64, formed in float32 (float64 phases are reduced first:
    float32 keeps 1e-7 rad of a phase within ±π; float32 ones, a descent's within a few
    waves, are taken as they are)."""
    t = np.asarray(phase)
    if t.dtype != np.float32:
        t = np.mod(np.asarray(t, np.float64) + np.pi, 2 * np.pi).astype(np.float32) - np.float32(
            np.pi
        )
    out = np.empty(t.shape, np.complex64)
    out.real = np.cos(t)
    out.imag = np.sin(t)
    return out


def _projections(phase, a, optics: Optics, iterations):
    """Gerchberg–Saxton through the filter: each plane's amplitude imposed, its in-band
    spectrum carried back, the stop band's (where double-phase's checkerboard lives) kept."""
    n = optics.distances.size
    losses = []
    u = unit(phase)
    for t in range(iterations):
        k = t % n
        full = fft2(optics.pad(u))
        s = full[optics.block]
        v = optics.to_plane(s, k)
        mag = np.abs(v)
        scale = float(np.linalg.norm(mag)) / max(float(np.linalg.norm(a[k])), 1e-30)
        r = mag / max(scale, 1e-30) - a[k]
        losses.append(float(np.vdot(r, r).real) / float(np.vdot(a[k], a[k]).real))
        target = ((a[k] * scale) * np.exp(1j * np.angle(v))).astype(np.complex64)
        inside = optics.keep > 0  # the pupil's frequencies are imposed, the rest kept
        # the transfer is a pure phase inside the band: its conjugate carries the plane back
        full[optics.block] = np.where(
            inside, optics.spectrum(target) * np.conj(optics.transfer(k)), s
        )
        u = unit(np.angle(optics.crop(ifft2(full))))
    return np.angle(u).astype(np.float64), losses


__all__ = ["METHODS", "Pattern", "encode", "low_passed"]
