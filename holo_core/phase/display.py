"""A complex plate made into what a real display shows: a phase-only SLM's phases or an
amplitude SLM's (or a print's) transmittance, at the display's pitch and resolution.

The plate's object wave is first resampled to the display's grid (band-limited, the window
cut around the centre: :func:`holo_core.propagation.resample`), then encoded:

- phase displays: double-phase (:func:`.encoding.double_phase`, for a 4f filter that keeps
  frequencies below half the Nyquist frequency), or complex error diffusion
  (:func:`error_diffusion`: each sample becomes its unit phasor and the complex error goes to
  its unprocessed neighbours, pushing the noise towards high frequencies);
- amplitude displays: bias (Burckhardt-style) t = (1 + Re(O·R*)/m)/2 or the off-axis
  interference t = |O/m + R|²/4, with R = exp(ik(α·x + β·y)) the reference of Eq. 4.

Both need the object wave band-limited to half the display's Nyquist frequency (a plate of at
least twice the display's pitch, or a recording band that small); otherwise a warning is
logged. Files are written by :mod:`holo_core.io.display`.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass

import numpy as np

from .. import memory, validate
from ..io import display as display_io
from ..io.image import check_writable
from ..propagation import grid, resample
from ..scene.hologram import Hologram
from ..validate import InputError, shown
from .encoding import double_phase, normalised

log = logging.getLogger(__name__)

KINDS = ("phase", "amplitude")
METHODS = {"phase": ("double-phase", "error-diffusion"), "amplitude": ("bias", "interference")}
# Plate samples kept beyond the display's window on each side before resampling: cutting a
# gigapixel plate to the window keeps the resampling's matrices the display's size, not the
# plate's, and the margin holds the band-limited kernel's tail (against resampling the whole
# plate: 3e-5 of the field's norm measured at 128, 5e-4 at 64)
MARGIN = 128
# Floyd–Steinberg weights: right (in scan direction), below-behind, below, below-ahead
AHEAD, BELOW_BEHIND, BELOW, BELOW_AHEAD = 7 / 16, 3 / 16, 5 / 16, 1 / 16


@dataclass(frozen=True, slots=True, kw_only=True)
class Display:
    """A spatial light modulator, or a printer's plate, that a pattern is made for.

    name : a label written into the layout
    resolution : (cols, rows) samples, as data sheets give it
    pitch : sample spacing [m]
    kind : 'phase' (a phase-only SLM: the pattern is a phase [rad]) or 'amplitude' (an
        amplitude SLM, a film or a print: a transmittance in [0, 1])
    bit_depth : the levels it resolves, 2^bit_depth (1 to 16; phase SLMs' drivers take 8,
        10 or 16)
    phase_range : the phase [rad] its codes span without a look-up table, in [2π, 4π]:
        code k shows k·phase_range/2^bit_depth (2π: the levels fill one wave; 3π: the
        range double-phase's φ ± α spans unwrapped). A measured table
        (:class:`holo_core.phase.slm.PhaseTable`) replaces this line.
    inverted : the phase falls as the code rises (code k shows −k·phase_range/2^bit_depth),
        as on SLMs whose driver maps grey to voltage the other way round

    Examples
    --------
    >>> from holo_core.phase import Display
    >>> Display(name="lab", resolution=(1920, 1080), pitch=8e-6).shape
    (1080, 1920)
    """

    name: str
    resolution: tuple
    pitch: float
    kind: str = "phase"
    bit_depth: int = 8
    phase_range: float = 2 * math.pi
    inverted: bool = False

    def __post_init__(self):
        if not isinstance(self.name, str) or not 1 <= len(self.name) <= 100:
            raise InputError(f"display name must be 1 to 100 characters; got {self.name!r}"[:200])
        try:
            cols, rows = self.resolution
        except (TypeError, ValueError):
            raise InputError(
                f"display resolution must be (cols, rows); got {self.resolution!r}"
            ) from None
        rows, cols = validate.shape2d("display resolution", (rows, cols))
        object.__setattr__(self, "resolution", (cols, rows))
        object.__setattr__(self, "pitch", validate.pitch("display pitch", self.pitch))
        validate.choice("display kind", self.kind, KINDS)
        object.__setattr__(
            self,
            "bit_depth",
            validate.integer("display bit_depth", self.bit_depth, 1, display_io.CODE_BITS),
        )
        r = validate.finite("display phase_range", self.phase_range, "rad")
        if not 2 * math.pi * (1 - 1e-9) <= r <= 4 * math.pi * (1 + 1e-9):
            raise InputError(
                f"display phase_range must be in [2π, 4π] rad (6.283 to 12.57; "
                f"2π or 3π on common SLMs); got {shown(self.phase_range)}"
            )
        object.__setattr__(self, "phase_range", r)
        if not isinstance(self.inverted, (bool, np.bool_)):
            raise InputError(f"display inverted must be True or False; got {shown(self.inverted)}")
        object.__setattr__(self, "inverted", bool(self.inverted))

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) of samples, as arrays are indexed."""
        return self.resolution[1], self.resolution[0]


# The common phase SLMs by resolution and pitch (facts.md section 11): 1080p at 8 µm (the
# splatting and Tensor Holography protocols) and 6.4 µm (Neural Holography), 4K at 3.74 µm
# (GAEA class) and 3.6 µm (OpenHolo's default); 8-bit over 2π unless a table says otherwise
PHASE_PRESETS = ("slm-1080p-8um", "slm-1080p-6.4um", "slm-4k-3.74um", "slm-4k-3.6um")
DISPLAYS = {
    d.name: d
    for d in (
        Display(name="slm-1080p-8um", resolution=(1920, 1080), pitch=8.0e-6),
        Display(name="slm-1080p-6.4um", resolution=(1920, 1080), pitch=6.4e-6),
        Display(name="slm-4k-3.74um", resolution=(3840, 2160), pitch=3.74e-6),
        Display(name="slm-4k-3.6um", resolution=(3840, 2160), pitch=3.6e-6),
        Display(
            name="holoeye-gaea-4k",
            resolution=(3840, 2160),
            pitch=3.74e-6,
            kind="phase",
            bit_depth=8,
        ),
        Display(
            name="holoeye-pluto-2", resolution=(1920, 1080), pitch=8.0e-6, kind="phase", bit_depth=8
        ),
        # a film or mask writer's plate: 16.4 mm square at 1 µm, written in grey levels
        Display(
            name="print-1um",
            resolution=(16384, 16384),
            pitch=1.0e-6,
            kind="amplitude",
            bit_depth=16,
        ),
    )
}


def display_preset(name: str, **changes) -> Display:
    """The preset display called ``name`` (one of :data:`DISPLAYS`), with ``changes`` to its
    fields (``bit_depth=10``, ``phase_range=3 * math.pi``, ``inverted=True``, ...): a custom
    display is a :class:`Display` made directly.

    Examples
    --------
    >>> from holo_core.phase import display_preset
    >>> slm = display_preset("slm-1080p-8um", bit_depth=10)
    >>> slm.resolution, slm.pitch, slm.bit_depth
    ((1920, 1080), 8e-06, 10)
    """
    preset = DISPLAYS[validate.choice("display", name, tuple(DISPLAYS))]
    unknown = set(changes) - {f.name for f in dataclasses.fields(Display)}
    if unknown:
        raise InputError(
            f"display_preset takes the fields of Display; got {', '.join(sorted(unknown))}"
        )
    return dataclasses.replace(preset, **changes) if changes else preset


def error_diffusion(field, *, max_amplitude=None) -> np.ndarray:
    """Phase-only pattern of ``field`` (H, W) complex by complex error diffusion, as phases
    [rad] in (−π, π], float64.

    The field is divided by ``max_amplitude`` m (default: its largest |c|) so that |c| <= 1;
    a sample above m is refused. Rows are scanned in a serpentine (even rows left to right,
    odd rows right to left); each sample c becomes exp(i·arg c), and its error
    c − exp(i·arg c) goes 7/16 to the next sample of the row, 3/16, 5/16 and 1/16 to the
    three below it (behind, under, ahead), as Floyd–Steinberg (Eschbach 1991; Tsang & Poon
    2013 for holograms). A low-pass of exp(i·pattern) then approximates c/m.

    Cost: O(H·W), but the in-row recursion is a Python loop over samples (the phasors, the
    errors and the next row's share are NumPy): measured 6.8 s for 3840×2160 (0.8 µs a
    sample) on one core of a shared 2-core x86-64 machine.
    """
    c = normalised(field, max_amplitude)
    h, w = c.shape
    phases = np.empty((h, w))
    carried = np.zeros(w, np.complex128)  # error sent down from the row above
    for i in range(h):
        forward = i % 2 == 0
        row = c[i] + carried
        x = np.asarray(_diffuse_row((row if forward else row[::-1]).tolist()))
        r = np.abs(x)
        down = _down(x - np.where(r > 0, x / np.where(r > 0, r, 1), 1))  # x − its phasor
        phases[i] = np.angle(x if forward else x[::-1])  # arg 0 = 0: a zero becomes 1
        carried = down if forward else down[::-1]
    return phases


def _diffuse_row(values: list) -> list:
    """The values x of one row, scanned in list order, once AHEAD of the error x − x/|x| of
    each has reached the next (plain Python: each sample waits for the one before it; the
    phasors and errors are formed from x afterwards, in NumPy)."""
    xs = []
    append = xs.append
    carry = 0j
    for v in values:
        x = v + carry
        append(x)
        r = abs(x)
        carry = x * (AHEAD - AHEAD / r) if r else (x - 1) * AHEAD  # AHEAD·(x − x/|x|)
    return xs


def _down(errors: np.ndarray) -> np.ndarray:
    """What a row's errors (scan order) send to the row below (same order); shares that fall
    beyond the edge are dropped."""
    out = BELOW * errors
    out[:-1] += BELOW_BEHIND * errors[1:]  # sample j's error reaches j − 1 below
    out[1:] += BELOW_AHEAD * errors[:-1]  # and j + 1
    return out


def amplitude_pattern(
    field, *, pitch, wavelength, angle=None, azimuth=0.0, method="bias", max_amplitude=None
) -> np.ndarray:
    """A transmittance in [0, 1] (float64, the shape of ``field``) encoding ``field`` on an
    off-axis carrier, for an amplitude SLM or a print.

    Parameters
    ----------
    field : (H, W) complex array
        The object wave O on the display's grid [field units].
    pitch : float
        The display's sample spacing [m].
    wavelength : float
        λ [m] of the reference (the illumination that reconstructs O).
    angle : float, optional
        The reference's angle ϑ to the normal [rad]; default sin ϑ = λ/(4·pitch), the carrier
        at half the Nyquist frequency (room for a wave band-limited to the other half).
        Refused beyond sin ϑ = λ/(2·pitch), where the carrier aliases.
    azimuth : float
        The tilt's direction φ [rad] in the display plane, from +x towards +y.
    method : 'bias' or 'interference'
        'bias': (1 + Re(O·R*)/m)/2, no |O|² halo; 'interference': |O/m + R|²/4, the
        hologram a plate records with |R| = m.
    max_amplitude : float, optional
        m [field units], default the largest |O|.
    """
    method = validate.choice("method", method, METHODS["amplitude"])
    pitch = validate.pitch("pitch", pitch)
    wavelength = validate.wavelength("wavelength", wavelength)
    c = normalised(field, max_amplitude)
    r = _carrier(
        c.shape,
        pitch,
        wavelength,
        _sin_angle(angle, pitch, wavelength),
        validate.finite("azimuth", azimuth, "rad"),
    )
    if method == "bias":
        return np.clip((1 + (c * r.conj()).real) / 2, 0, 1)
    return np.clip(np.abs(c + r) ** 2 / 4, 0, 1)


def _sin_angle(angle, pitch: float, wavelength: float) -> float:
    most = wavelength / (2 * pitch)
    if angle is None:
        return most / 2
    a = validate.finite("angle", angle, "rad")
    if not 0 <= a < math.pi / 2 or math.sin(a) > most * (1 + 1e-12):
        limit = math.asin(min(most, 1.0))
        raise InputError(
            f"angle must be in [0, {limit:.6g}] rad (sin ϑ <= λ/(2·pitch), beyond "
            f"which the carrier aliases); got {shown(angle)}"
        )
    return math.sin(a)


def _carrier(shape, pitch: float, wavelength: float, sin_angle: float, azimuth: float):
    """R = exp(ik(α·x + β·y)) on the grid's pixel centres (Eq. 4 on z = 0), phases reduced
    in float64."""
    k = 2 * math.pi / wavelength
    px = np.remainder(k * sin_angle * math.cos(azimuth) * grid.coords(shape[1], pitch), 2 * math.pi)
    py = np.remainder(k * sin_angle * math.sin(azimuth) * grid.coords(shape[0], pitch), 2 * math.pi)
    return np.exp(1j * py)[:, None] * np.exp(1j * px)[None, :]


def display_field(hologram: Hologram, display: Display, *, channel=0) -> np.ndarray:
    """The plate's object wave of ``channel`` on the display's grid, complex64 (rows, cols):
    the plate's window around its centre, resampled band-limited; outside the plate, zero. A
    plate stored against its zone's carrier gives its physical field there
    (:func:`holo_core.plate.carrier.field_at`: its samples interpolated band-limited and
    re-modulated), reading only the samples under the display."""
    display = _display(display)
    wave, channel = _object_wave(hologram, channel)
    if hologram.carrier is not None:
        return _carrier_field(hologram, display, channel)
    window = tuple(
        _window(n, hologram.pitch, n_out, display.pitch)
        for n, n_out in zip(hologram.shape, display.shape)
    )
    _check_memory(display, [w.stop - w.start for w in window])
    _check_band(hologram, channel, display)
    # indexing first: a chunked store reads only the window, not the gigapixel plate
    u = np.asarray(wave[channel, window[0], window[1]], np.complex64)
    return resample(u, pitch=hologram.pitch, out_shape=display.shape, out_pitch=display.pitch)


def _carrier_field(hologram: Hologram, display: Display, channel: int) -> np.ndarray:
    """A carrier plate's physical field on the display's grid, centred on the plate."""
    from ..plate import carrier

    rows, cols = display.shape
    xs, ys = ((np.arange(n) - (n - 1) / 2) * display.pitch for n in (cols, rows))
    region = (xs[0], ys[0], xs[-1], ys[-1])
    reads = [
        min(math.ceil(n * display.pitch / step) + 2 * carrier.TAPS, size)
        for n, step, size in (
            (rows, hologram.row_pitch, hologram.shape[0]),
            (cols, hologram.pitch, hologram.shape[1]),
        )
    ]
    _check_memory(display, reads)
    reach = 1 / (2 * carrier.physical_pitch(hologram, channel, region))
    _warn_band(
        reach,
        display,
        f"a display of pitch <= {1 / (4 * reach):.4g} m holds it (the "
        f"carrier's direction and the zone's band)",
    )
    return carrier.field_at(hologram, channel, xs, ys)


# host bytes per display sample while encoding (measured: 88 for double-phase, 64 for the amplitude
# patterns)
PATTERN_SAMPLE_BYTES = 96


def _check_memory(display: Display, window) -> None:
    """Refuse a pattern the host cannot hold, before the plate is read: the encoding's arrays
    per display sample, the plate's window and the resampling's two matrices (float64 made,
    float32 kept) and its intermediate rows."""
    (rows, cols), (h, w) = display.shape, window
    need = (
        PATTERN_SAMPLE_BYTES * rows * cols
        + 8.0 * h * w
        + 8.0 * rows * w
        + 12.0 * (rows * h + cols * w)
    )
    memory.check_host(f"a {cols}x{rows} pattern for the display {display.name!r}", need)


def _object_wave(hologram, channel):
    if not isinstance(hologram, Hologram):
        raise InputError(f"hologram must be a Hologram; got {type(hologram).__name__}")
    if hologram.object_wave is None:
        raise InputError(
            "hologram has no object_wave (an intensity hologram that did not keep "
            "it): a display's pattern is encoded from the complex plate"
        )
    return hologram.object_wave, validate.index("channel", channel, len(hologram.wavelengths))


def _window(n: int, pitch: float, n_out: int, out_pitch: float) -> slice:
    """The plate's samples under the display's window plus MARGIN each side, centred as the
    plate is (an equal count cut from each end keeps its centre on the axis)."""
    need = math.ceil(n_out * out_pitch / pitch) + 2 * MARGIN
    if need >= n:
        return slice(0, n)
    need += (n - need) % 2
    start = (n - need) // 2
    return slice(start, start + need)


def _check_band(hologram: Hologram, channel: int, display: Display) -> None:
    """Log a warning when the wave may reach past half the display's Nyquist frequency, which
    the encodings' low-pass (a 4f filter or the carrier's room) needs free."""
    wavelength = hologram.wavelengths[channel]
    half = 1 / (4 * display.pitch)
    _warn_band(
        hologram.band / wavelength if hologram.band else 1 / (2 * hologram.pitch),
        display,
        f"record the plate with band <= {half * wavelength:.4g} or a plate "
        f"pitch >= {2 * display.pitch:.4g} m",
    )


def _warn_band(reach: float, display: Display, advice: str) -> None:
    """Log a warning, with ``advice``, when a wave reaching ``reach`` [cycles/m] passes half
    the display's Nyquist frequency."""
    half = 1 / (4 * display.pitch)
    if reach > half * (1 + 1e-9):
        log.warning(
            "the plate's wave reaches %.4g cycles/m, beyond half the display's Nyquist "
            "frequency (%.4g cycles/m): the encoding's low-pass will cut or alias it; "
            "%s",
            reach,
            half,
            advice,
        )


def _display(display) -> Display:
    if isinstance(display, str):
        return display_preset(display)
    if not isinstance(display, Display):
        raise InputError(
            f"display must be a Display or one of {', '.join(DISPLAYS)}; got "
            f"{type(display).__name__}"
        )
    return display


def _method(display: Display, method) -> str:
    """The encoding: ``method`` if it suits the display's kind, else the kind's first."""
    methods = METHODS[display.kind]
    return methods[0] if method is None else validate.choice("method", method, methods)


def for_display(
    hologram: Hologram, display, *, channel=0, method=None, angle=None, azimuth=0.0
) -> np.ndarray:
    """The pattern ``display`` shows for the plate: phases [rad] in (−π, π] on a phase
    display, a transmittance in [0, 1] on an amplitude one, float64 (rows, cols).

    ``display`` is a :class:`Display` or a preset's name; ``channel`` picks the wavelength
    (one display shows one colour); ``method`` one of :data:`METHODS` for the display's kind
    (default: double-phase, or bias); ``angle``, ``azimuth`` [rad] as for
    :func:`amplitude_pattern`.
    """
    display = _display(display)
    method = _method(display, method)
    channel = _object_wave(hologram, channel)[1]
    u = display_field(hologram, display, channel=channel)
    if not np.abs(u).max() > 0:
        raise InputError(
            "the plate's object wave is zero on the display's window: nothing to encode"
        )
    if method == "double-phase":
        return double_phase(u)
    if method == "error-diffusion":
        return error_diffusion(u)
    return amplitude_pattern(
        u,
        pitch=display.pitch,
        wavelength=hologram.wavelengths[channel],
        angle=angle,
        azimuth=azimuth,
        method=method,
    )


def export(
    hologram: Hologram,
    display,
    path,
    *,
    distance,
    channel=0,
    method=None,
    angle=None,
    azimuth=0.0,
    tile=display_io.DEFAULT_TILE,
    fmt="png",
) -> tuple:
    """Encode the plate for ``display`` and write its 16-bit tiles and layout ``path``
    (*.json), atomically; returns (layout path, pattern).

    ``distance`` [m]: the scene's signed distance from the display along its normal
    (negative: behind it, as the plate's frame puts a scene at z < 0), written into the layout
    with the wavelength. ``tile`` (rows, cols) and ``fmt`` ('png' or 'tiff') as for
    :func:`holo_core.io.display.write_tiles`; the rest as for :func:`for_display`.
    """
    display = _display(display)
    check_writable(path, ".json")  # before the work, not after it
    validate.within("distance", distance, validate.MAX_LENGTH)
    validate.shape2d("tile", tile)
    validate.choice("fmt", fmt, display_io.TILE_FORMATS)
    method = _method(display, method)
    channel = _object_wave(hologram, channel)[1]
    pattern = for_display(
        hologram, display, channel=channel, method=method, angle=angle, azimuth=azimuth
    )
    written = display_io.write_tiles(
        path,
        pattern,
        quantity=display.kind,
        pitch=display.pitch,
        wavelength=hologram.wavelengths[channel],
        distance=distance,
        encoding=method,
        bit_depth=display.bit_depth,
        tile=tile,
        fmt=fmt,
        display=display.name,
    )
    return written, pattern


def read_phase_hologram(path) -> tuple[Hologram, dict]:
    """(hologram, layout) of an exported phase-only pattern: its tiles read back as the field
    exp(i·phase) on the display's grid, a complex :class:`Hologram` (one channel at the
    layout's wavelength and pitch) that the core propagates and views like a plate."""
    phase, layout = display_io.read_tiles(path)
    if layout["kind"] != "phase":
        raise InputError(
            f"{path}: holds {layout['kind']} values, not phases: a phase-only "
            f"hologram is read from a phase display's layout"
        )
    wave = np.exp(1j * phase).astype(np.complex64)[None]
    return Hologram(
        encoding="complex",
        object_wave=wave,
        wavelengths=(layout["wavelength"],),
        pitch=layout["pitch"],
    ), layout
