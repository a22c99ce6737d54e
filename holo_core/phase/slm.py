"""A phase SLM as a lab drives it: its lasers, its phase look-up tables, its eye box, the
volume the scene is shown in, and the checks a scene must pass before any work.

- :class:`Laser`: one light source, wavelength [m] and power [W]; field-sequential colour
  shows one pattern per laser.
- :class:`PhaseTable`: the phase [rad] each code shows at one wavelength (a measured
  calibration curve), read from a file by :func:`read_phase_table`.
- :class:`EyeBox`: where the viewer's eye (or a camera) may sit: a rectangle of ``size`` at
  ``distance`` from the display, in the Fourier plane of its eyepiece of that focal length (a
  near-eye display) or an eye at that distance (the same for the small angles a pixel pitch
  diffracts: sin θ and tan θ differ by 0.08 % at 2.3°). A position x there is the spatial
  frequency x/(λ·distance) of the display's light.
- :class:`SLMSetup`: the display with the above, the volume ``depth_range`` (signed distances
  [m] along the display's normal: negative behind it, as the plate's frame puts a scene at
  z < 0) and the ``band`` its Fourier filter passes.
- :func:`check_scene`: refuses, before any work and with the numbers and what to change, an
  eye box beyond the display's diffraction angle asin(λ/2p) and objects whose light cannot
  reach the eye box inside the band the display passes.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import validate
from ..validate import InputError, shown
from .display import Display, display_preset

TABLE_SUFFIXES = (".npy", ".csv", ".txt")
MAX_TABLE_BYTES = 16 * 2**20  # 65536 codes as text take under 2 MB
# a table of radians spans about 2π to 4π; one of waves (~1) or units of π (~2) spans less
# than this, which is how a table in another unit is told apart
MIN_TABLE_SPAN, MAX_TABLE_SPAN = 2 * math.pi, 4 * math.pi * (1 + 1e-6)


@dataclass(frozen=True, slots=True, kw_only=True)
class Laser:
    """One laser of a field-sequential display: ``wavelength`` [m] and ``power`` [W] (what
    its driver is set to; the patterns are encoded per laser and the powers written beside
    them, so a colour balance is the lab's, not the encoding's).

    Examples
    --------
    >>> from holo_core.phase import Laser
    >>> Laser(wavelength=520e-9, power=0.02).power
    0.02
    """

    wavelength: float
    power: float = 1.0

    def __post_init__(self):
        object.__setattr__(
            self, "wavelength", validate.wavelength("laser wavelength", self.wavelength)
        )
        object.__setattr__(self, "power", validate.positive("laser power", self.power, "W"))


@dataclass(frozen=True, slots=True, kw_only=True)
class PhaseTable:
    """The phase each code shows at one wavelength.

    wavelength : [m]
    phases : (2^bit_depth,) float64 [rad], phases[k] the phase code k shows (any order: an
        inverted or non-monotonic response is taken as measured)
    source : where it came from (a file's name), written into the layout

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.phase import PhaseTable
    >>> PhaseTable(wavelength=520e-9, phases=np.linspace(0, 2 * np.pi, 256)).bit_depth
    8
    """

    wavelength: float
    phases: np.ndarray
    source: str = ""

    def __post_init__(self):
        object.__setattr__(
            self, "wavelength", validate.wavelength("table wavelength", self.wavelength)
        )
        where = self.source or "phase table"
        object.__setattr__(self, "phases", _checked_phases(self.phases, where, None))

    @property
    def bit_depth(self) -> int:
        return int(self.phases.size).bit_length() - 1


def _checked_phases(values, where: str, bit_depth: int | None) -> np.ndarray:
    """``values`` as the float64 (2^b,) phases of a table, or InputError naming ``where``."""
    try:
        a = np.array(values, np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{where}: a phase table holds numbers (radians)") from None
    if a.ndim != 1:
        raise InputError(
            f"{where}: a phase table is one column of phases [rad] (or two: code, "
            f"phase); got shape {a.shape}"
        )
    n = a.size
    if bit_depth is not None and n != 2**bit_depth:
        raise InputError(
            f"{where}: {n} entries; a {bit_depth}-bit display's table has "
            f"{2**bit_depth} (one phase per code)"
        )
    if n < 2 or n & (n - 1) or n > 2**16:
        raise InputError(
            f"{where}: {n} entries; a table has 2^bits entries (2 to 65536), one phase per code"
        )
    if not np.isfinite(a).all():
        raise InputError(f"{where}: holds NaN or infinite phases")
    span = float(a.max() - a.min())
    # the codes must reach every phase of a wave to within one step of a linear table
    least = MIN_TABLE_SPAN * (1 - 1.5 / n)
    if not least <= span <= MAX_TABLE_SPAN or abs(a).max() > 4 * math.pi:
        raise InputError(
            f"{where}: its phases span {span:.4g} rad (from {a.min():.4g} to "
            f"{a.max():.4g}); a table's must span {least:.4g} to {MAX_TABLE_SPAN:.4g}"
            f" rad (2π to 4π, within ±4π): radians, not waves (~1) or units of π "
            f"(~2), and one that reaches a whole wave"
        )
    return a


def read_phase_table(path, *, wavelength, bit_depth) -> PhaseTable:
    """The phase table in ``path`` for ``wavelength`` [m] and a display of ``bit_depth``.

    Files: ``.npy`` (a 1-D float array of 2^bit_depth phases [rad]), ``.csv`` or ``.txt``
    (one phase [rad] per line, or two columns ``code, phase`` with the codes 0, 1, … in
    order; a first line of names is skipped). Refused, naming the file, when missing,
    unreadable, of the wrong size (not 2^bit_depth codes) or shape, or of the wrong range
    (not finite, spanning less than a wave or more than 4π: a table in waves or units of π).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> from holo_core.phase import read_phase_table
    >>> path = Path(tempfile.mkdtemp()) / "green.npy"
    >>> np.save(path, np.linspace(0, 2.2 * np.pi, 256))
    >>> read_phase_table(path, wavelength=520e-9, bit_depth=8).source
    'green.npy'
    """
    path = Path(path)
    wavelength = validate.wavelength("wavelength", wavelength)
    bits = validate.integer("bit_depth", bit_depth, 1, 16)
    if not path.is_file():
        raise InputError(f"{path}: no such phase table")
    if path.suffix.lower() not in TABLE_SUFFIXES:
        raise InputError(f"{path}: a phase table is one of {', '.join(TABLE_SUFFIXES)}")
    if path.stat().st_size > MAX_TABLE_BYTES:
        raise InputError(
            f"{path}: {path.stat().st_size} bytes; a table of 65536 codes takes "
            f"under {MAX_TABLE_BYTES}"
        )
    try:
        if path.suffix.lower() == ".npy":
            a = np.load(path, allow_pickle=False)
        else:
            a = _text_table(path)
    except InputError:
        raise
    except (OSError, ValueError, UnicodeDecodeError) as e:
        raise InputError(
            f"{path}: not a readable phase table ({type(e).__name__}: {e})"[:400]
        ) from None
    a = np.asarray(a)
    if a.ndim == 2 and a.shape[1] == 2:
        if not np.array_equal(a[:, 0], np.arange(len(a))):
            raise InputError(
                f"{path}: its first column must be the codes 0, 1, ..., {len(a) - 1} in order"
            )
        a = a[:, 1]
    elif a.ndim == 2 and 1 in a.shape:
        a = a.ravel()
    return PhaseTable(
        wavelength=wavelength, phases=_checked_phases(a, str(path), bits), source=path.name
    )


def _text_table(path: Path) -> np.ndarray:
    rows = []
    with path.open(newline="") as f:
        for i, row in enumerate(
            csv.reader(
                f, delimiter="," if path.suffix.lower() == ".csv" else " ", skipinitialspace=True
            )
        ):
            row = [c for c in row if c.strip()]
            if not row:
                continue
            try:
                rows.append([float(c) for c in row])
            except ValueError:
                if i == 0 and not rows:
                    continue  # a header
                raise InputError(f"{path}: line {i + 1} is not numbers: {row!r}"[:300]) from None
    widths = {len(r) for r in rows}
    if len(widths) != 1:
        raise InputError(
            f"{path}: its lines have {sorted(widths)} columns; a table has one "
            f"(phase) or two (code, phase)"
        )
    return np.array(rows)


@dataclass(frozen=True, slots=True, kw_only=True)
class EyeBox:
    """Where the eye (or a camera) may sit (module docstring: a Fourier plane at
    ``distance``).

    size : (width, height) [m] of the eye box
    distance : [m] from the display (the eyepiece's focal length in a near-eye display)
    pupil : the eye's or camera's pupil diameter [m] (a focal stack is seen through it)
    centre : (x, y) [m] of the eye box's centre, from the display's axis

    Examples
    --------
    >>> from holo_core.phase import EyeBox
    >>> round(EyeBox(size=(4e-3, 4e-3), distance=0.3).half_angle(), 5)
    0.00943
    """

    size: tuple
    distance: float
    pupil: float = 4e-3
    centre: tuple = (0.0, 0.0)

    def __post_init__(self):
        w, h = validate.pair("eye box size", self.size, "m")
        validate.positive("eye box width", w, "m")
        validate.positive("eye box height", h, "m")
        object.__setattr__(self, "size", (w, h))
        object.__setattr__(
            self, "distance", validate.positive("eye box distance", self.distance, "m")
        )
        object.__setattr__(self, "pupil", validate.positive("eye box pupil", self.pupil, "m"))
        object.__setattr__(self, "centre", validate.pair("eye box centre", self.centre, "m"))

    def half_angle(self) -> float:
        """The largest angle [rad] from the display's axis to a point of the eye box."""
        (w, h), (cx, cy) = self.size, self.centre
        return math.atan(math.hypot(abs(cx) + w / 2, abs(cy) + h / 2) / self.distance)


@dataclass(frozen=True, slots=True, kw_only=True)
class SLMSetup:
    """A phase SLM with its lasers, tables, eye box and volume.

    display : a :class:`~holo_core.phase.display.Display` (kind 'phase') or a preset's name
    lasers : one or more :class:`Laser`; one pattern is encoded per laser
    tables : :class:`PhaseTable` per wavelength; empty: every laser on the display's linear
        response (``phase_range``, ``inverted``); given: every laser needs its own
    eye_box : an :class:`EyeBox`, or None (the whole band the filter passes)
    depth_range : (near, far) signed distances [m] of the scene's volume along the
        display's normal (negative behind the display), near <= far
    band : the fraction of the Nyquist frequency 1/(2p) the display's Fourier filter passes
        on each axis, in (0, 1]: 0.5 is the 4f filter double-phase needs
    slices : the focal stack's planes over ``depth_range`` (what the display is judged by)

    Examples
    --------
    >>> from holo_core.phase import Laser, SLMSetup
    >>> setup = SLMSetup(display="slm-1080p-8um", lasers=[Laser(wavelength=520e-9)],
    ...                  depth_range=(-5e-3, 5e-3), slices=3)
    >>> setup.distances()
    array([-0.005,  0.   ,  0.005])
    """

    display: Display
    lasers: tuple
    tables: tuple = ()
    eye_box: EyeBox | None = None
    depth_range: tuple = (-5e-3, 5e-3)
    band: float = 0.5
    slices: int = 30

    def __post_init__(self):
        display = display_preset(self.display) if isinstance(self.display, str) else self.display
        if not isinstance(display, Display) or display.kind != "phase":
            raise InputError(
                f"display must be a phase Display or a preset's name; got {shown(self.display)}"
            )
        object.__setattr__(self, "display", display)
        lasers = tuple(self.lasers) if isinstance(self.lasers, (list, tuple)) else (self.lasers,)
        if not lasers or not all(isinstance(x, Laser) for x in lasers):
            raise InputError("lasers must be one or more Laser (wavelength [m], power [W])")
        object.__setattr__(self, "lasers", lasers)
        tables = tuple(self.tables)
        if not all(isinstance(t, PhaseTable) for t in tables):
            raise InputError("tables must be PhaseTable objects (read_phase_table reads a file)")
        for t in tables:
            if t.phases.size != 2**display.bit_depth:
                raise InputError(
                    f"{t.source or 'phase table'} ({t.wavelength:.4g} m): "
                    f"{t.phases.size} entries; the {display.bit_depth}-bit "
                    f"display needs {2**display.bit_depth}"
                )
        object.__setattr__(self, "tables", tables)
        if tables:
            for laser in lasers:
                self.table_for(laser.wavelength)
        if self.eye_box is not None and not isinstance(self.eye_box, EyeBox):
            raise InputError(f"eye_box must be an EyeBox or None; got {shown(self.eye_box)}")
        near, far = validate.pair("depth_range", self.depth_range, "m", validate.MAX_LENGTH)
        if near > far:
            raise InputError(
                f"depth_range must be (near, far) with near <= far [m]; got "
                f"{shown(self.depth_range)}"
            )
        object.__setattr__(self, "depth_range", (near, far))
        b = validate.positive("band", self.band)
        if b > 1:
            raise InputError(
                f"band must be in (0, 1] (a fraction of the Nyquist frequency); "
                f"got {shown(self.band)}"
            )
        object.__setattr__(self, "band", b)
        object.__setattr__(self, "slices", validate.integer("slices", self.slices, 1, 1000))

    @property
    def wavelengths(self) -> tuple:
        return tuple(x.wavelength for x in self.lasers)

    def table_for(self, wavelength) -> PhaseTable | None:
        """The table for ``wavelength`` [m] (to a relative 1e-6), None when the setup has no
        tables; InputError naming the wavelength when tables are given but none is for it."""
        return table_for(self.tables, wavelength)

    def distances(self) -> np.ndarray:
        """The focal stack's planes [m]: ``slices`` evenly over ``depth_range``."""
        near, far = self.depth_range
        return (
            np.linspace(near, far, self.slices) if self.slices > 1 else np.array([(near + far) / 2])
        )


def table_for(tables, wavelength) -> PhaseTable | None:
    """The table of ``tables`` for ``wavelength`` [m] (relative 1e-6), None for no tables;
    InputError naming the wavelength and those the tables are for when none matches."""
    tables = tuple(tables or ())
    if not tables:
        return None
    wavelength = validate.wavelength("wavelength", wavelength)
    for t in tables:
        if abs(t.wavelength - wavelength) <= 1e-6 * wavelength:
            return t
    have = ", ".join(f"{t.wavelength * 1e9:.6g} nm ({t.source or 'table'})" for t in tables)
    raise InputError(
        f"no phase table for the wavelength {wavelength * 1e9:.6g} nm; the tables "
        f"given are for {have}: give one per laser (or none, for the display's "
        f"linear response)"
    )


def diffraction_angle(wavelength: float, pitch: float, band: float = 1.0) -> float:
    """asin(band·λ/(2p)) [rad]: the largest angle to the normal a display of pitch ``pitch``
    [m] sends ``wavelength`` [m] into with its Fourier filter passing ``band`` of Nyquist."""
    return math.asin(min(1.0, band * wavelength / (2 * pitch)))


def check_scene(setup: SLMSetup, *, extent=None, depth_range=None) -> list[str]:
    """Refuse a scene the display cannot show, before any work; returns notes (warnings).

    Parameters
    ----------
    setup : SLMSetup
    extent : (x, y) [m], optional
        The scene's half-width and half-height about the display's axis (default: the
        display's own half-size).
    depth_range : (near, far) [m], optional
        The scene's signed depths (default the setup's volume).

    Raises
    ------
    InputError
        - the eye box beyond the diffraction angle asin(λ/(2p)) of the shortest wavelength:
          the eye box's edge, the angles, and the eye box, distance or pitch that fits;
        - objects too close for the pitch: a point of the scene whose rays into the eye box
          leave the display beyond the angle the filter passes, asin(band·λ/(2p)) (a point
          in front of the display nearing the eye, or far off the axis), with the depth that
          fits;
        - a scene at or beyond the eye box.

        Without an eye box (a camera behind the display's filter takes every direction it
        passes) there is nothing to check.

    Examples
    --------
    >>> from holo_core.phase import EyeBox, Laser, SLMSetup, check_scene
    >>> check_scene(SLMSetup(display="slm-1080p-8um", lasers=[Laser(wavelength=520e-9)],
    ...                      eye_box=EyeBox(size=(2e-3, 2e-3), distance=0.7)))
    []
    """
    if not isinstance(setup, SLMSetup):
        raise InputError(f"setup must be an SLMSetup; got {type(setup).__name__}")
    d = setup.display
    width, height = d.resolution[0] * d.pitch, d.resolution[1] * d.pitch
    ex, ey = (width / 2, height / 2) if extent is None else validate.pair("extent", extent, "m")
    near, far = (
        setup.depth_range
        if depth_range is None
        else validate.pair("depth_range", depth_range, "m", validate.MAX_LENGTH)
    )
    lam = min(setup.wavelengths)
    full = diffraction_angle(lam, d.pitch)
    passed = diffraction_angle(lam, d.pitch, setup.band)
    notes = []
    eye = setup.eye_box
    if eye is None:
        return notes
    reach = eye.half_angle()
    if reach > full:
        room = 2 * eye.distance * math.tan(full)
        raise InputError(
            f"eye box: {eye.size[0] * 1e3:.3g} x {eye.size[1] * 1e3:.3g} mm at "
            f"{eye.distance * 1e3:.4g} mm reaches {math.degrees(reach):.3g}° from the axis, "
            f"beyond the {math.degrees(full):.3g}° a pitch of {d.pitch * 1e6:.4g} µm diffracts "
            f"{lam * 1e9:.4g} nm into (asin(λ/2p)): shrink it to a diagonal of "
            f"{room * 1e3:.3g} mm, move it to >= {eye.distance * math.tan(reach) / math.tan(full) * 1e3:.4g} mm, "
            f"or use a display of pitch <= {lam / (2 * math.sin(reach)) * 1e6:.3g} µm"
        )
    if reach > passed:
        notes.append(
            f"eye box reaches {math.degrees(reach):.3g}°, beyond the "
            f"{math.degrees(passed):.3g}° the filter passes (band {setup.band:g}): its "
            f"edge sees no light at {lam * 1e9:.4g} nm"
        )
    if far >= eye.distance:
        raise InputError(
            f"depth_range: the scene reaches {far * 1e3:.4g} mm in front of the "
            f"display, at or beyond the eye box ({eye.distance * 1e3:.4g} mm)"
        )
    (w, h), (cx, cy) = eye.size, eye.centre
    # the widest ray: from the scene's farthest corner to the eye box's opposite edge
    lateral = math.hypot(ex + abs(cx) + w / 2, ey + abs(cy) + h / 2)
    for z in (near, far):
        angle = math.atan(lateral / (eye.distance - z))
        if angle > passed * (1 + 1e-9):
            fits = eye.distance - lateral / math.tan(passed)
            raise InputError(
                f"objects too close for the pitch: the scene's corner (±{ex * 1e3:.3g}, "
                f"±{ey * 1e3:.3g} mm) at z = {z * 1e3:.4g} mm sends light into the eye box's "
                f"edge at {math.degrees(angle):.3g}° from the display's normal, beyond the "
                f"{math.degrees(passed):.3g}° a pitch of {d.pitch * 1e6:.4g} µm passes at "
                f"{lam * 1e9:.4g} nm (asin(band·λ/2p), band {setup.band:g}): keep the scene at "
                f"z <= {fits * 1e3:.4g} mm, make it or the eye box smaller, or use a pitch <= "
                f"{setup.band * lam / (2 * math.sin(angle)) * 1e6:.3g} µm"
            )
    return notes
