"""Checks at the API boundary: bad input raises :class:`InputError` naming the field (or
file), the problem and the allowed range."""

from __future__ import annotations

import contextvars
import difflib
import functools
import inspect
import math
import warnings
from contextlib import contextmanager

import numpy as np

# Lengths any pitch, wavelength or size may take [m] where the physics, not a person, chose
# them (the plate renderer's scale-free wavelengths, a file it wrote): 0.1 pm to 1 km, far
# enough from float underflow that squares and ratios stay normal (1e-26 in float32's 1e-38)
MIN_LENGTH, MAX_LENGTH = 1e-13, 1e3
MAX_SUPERSAMPLE = 16  # fine pixels per pixel per axis, at most (either renderer, a job, the CLI)
MAX_SAMPLES = 1 << 16  # a camera hologram's looks, at most (the renderer, a job)
MAX_EXPOSURE = 1e20  # linear; with colours up to 1e12 the float32 view stays finite


class InputError(ValueError):
    """Bad input: a setting, an argument or a file the project cannot use.

    A subclass of ``ValueError``. The message names the argument or the file, the problem and
    what is allowed; the command line prints it as one line and exits with status 2.

    Examples
    --------
    >>> from holo_core import InputError, Pupil
    >>> try:
    ...     Pupil(diameter=-1.0)
    ... except InputError as e:
    ...     print(e)
    aperture diameter must be > 0 [m]; got -1.0
    """


class SamplingWarning(UserWarning):
    """A grid cannot represent the requested wave alias-free; the message names the safe limit."""


def shown(value) -> str:
    """``value`` as an error message names it: its repr, NumPy's numbers (alone, or in a list
    or tuple) written as numbers, as NumPy 1 wrote them (NumPy 2's repr is np.float64(633.0)
    where the user passed 633.0; its str is still 633.0)."""
    if isinstance(value, np.generic):
        return str(value)
    if isinstance(value, (list, tuple)) and any(isinstance(v, np.generic) for v in value):
        inner = ", ".join(shown(v) for v in value)
        return (
            f"[{inner}]"
            if isinstance(value, list)
            else f"({inner}{',' if len(value) == 1 else ''})"
        )
    return repr(value)


def warn_sampling(message: str) -> None:
    warnings.warn(message, SamplingWarning, stacklevel=3)


def keywords(function: str, given, allowed) -> None:
    """:class:`InputError` naming ``function`` and the first keyword of ``given`` it does not
    take (with the nearest one it does), before any work: a misspelt setting is the caller's
    mistake, not an inner function's ``TypeError``."""
    allowed = tuple(allowed)
    for name in given:
        if name not in allowed:
            near = difflib.get_close_matches(name, allowed, 1)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            raise InputError(
                f"{function}() takes no keyword {name!r}{hint}; it takes {', '.join(allowed)}"[:400]
            )


def public(function):
    """Decorate a public function so that a keyword it does not take, or a missing or extra
    argument, is an :class:`InputError` naming it (:func:`keywords`), not a ``TypeError``."""
    signature = inspect.signature(function)
    named = [
        p.name
        for p in signature.parameters.values()
        if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)
    ]

    @functools.wraps(function)
    def call(*args, **kwargs):
        keywords(function.__name__, kwargs, named)
        try:
            signature.bind(*args, **kwargs)
        except TypeError as e:
            raise InputError(f"{function.__name__}(): {e}") from None
        return function(*args, **kwargs)

    return call


def positive(name: str, value, unit: str = "") -> float:
    """``value`` as a float, or :class:`InputError` unless it is finite and > 0."""
    v = _finite(name, value, unit)
    if v <= 0:
        raise InputError(f"{name} must be > 0{_unit(unit)}; got {shown(value)}")
    return v


def at_least(name: str, value, minimum: float, unit: str = "") -> float:
    v = _finite(name, value, unit)
    if v < minimum:
        raise InputError(f"{name} must be >= {minimum}{_unit(unit)}; got {shown(value)}")
    return v


def finite(name: str, value, unit: str = "") -> float:
    return _finite(name, value, unit)


def length(name: str, value, unit: str = "m") -> float:
    """A pitch or a wavelength [m]: finite, in [MIN_LENGTH, MAX_LENGTH]."""
    v = _finite(name, value, unit)
    if not MIN_LENGTH <= v <= MAX_LENGTH:
        raise InputError(
            f"{name} must be in [{MIN_LENGTH:g}, {MAX_LENGTH:g}]{_unit(unit)}; got {shown(value)}"
        )
    return v


# The waves holograms are recorded with, and how finely they are sampled [m]. Each bound
# guards against a number typed in another unit, never against real physics:
# - a wavelength from 0.1 pm (electrons of a 1 MV holography microscope: 0.87 pm; 300 kV:
#   1.97 pm; hard X-rays: 10-100 pm) to 1 cm (millimetre-wave and microwave holography);
#   633 (nm typed as metres) lies beyond it and is refused with its likely unit;
# - a pitch from 1 pm (an electron hologram sampled in the object plane: a few pm at atomic
#   resolution) to 1 cm (a coarse antenna array); 8 (µm typed as metres) is refused likewise.
WAVELENGTH_RANGE = (1e-13, 1e-2)
PITCH_RANGE = (1e-12, 1e-2)
_UNITS = (("nanometres", 1e-9), ("micrometres", 1e-6), ("millimetres", 1e-3))
_TYPICAL = {"wavelength": 550e-9, "pitch": 5e-6}  # the likely unit is the one that lands nearest
_SPANS = {
    "wavelength": "MeV electrons to microwaves",
    "pitch": "an electron hologram's pm sampling to a coarse antenna array",
}
# Where a real length that is in range still looks like millimetres typed as metres, a
# UnitWarning says so: a camera's or scanner's pixel is 0.5-50 µm and a film scan's at most
# a few hundred µm, so a pitch of 1 mm or more (0.00345 for 3.45 µm) is more likely in mm.
MILLIMETRE_PITCH = 1e-3


class UnitWarning(UserWarning):
    """A length that is physically possible but looks like a number in another unit (a pitch
    of 0.00345 m for 3.45 µm typed in millimetres); the message names the likely value."""


def warn_millimetres(name: str, value: float, why: str) -> None:
    """Warn (:class:`UnitWarning`) that ``value`` [m] of ``name`` looks like millimetres,
    saying ``why`` and what the value in millimetres would be in metres."""
    warnings.warn(
        f"{name} {value:g} m {why}; if it is in millimetres, pass {value * 1e-3:g}",
        UnitWarning,
        stacklevel=3,
    )


def pitch_typed(name: str, value) -> float:
    """A pitch [m] a person gave for a scan (:func:`pitch`), warned (:class:`UnitWarning`)
    when it is :data:`MILLIMETRE_PITCH` or more."""
    v = pitch(name, value)
    if v >= MILLIMETRE_PITCH and not _SCALE_FREE.get():
        warn_millimetres(
            name, v, f"is {v * 1e3:g} mm, coarser than any camera's or scanner's pixel (0.5-50 µm)"
        )
    return v


_SCALE_FREE = contextvars.ContextVar("holo_scale_free", default=False)


@contextmanager
def scale_free():
    """Within this block (or a function it decorates) wavelengths and pitches are any lengths
    in [MIN_LENGTH, MAX_LENGTH]. Internal: the plate renderer chooses its own wavelength for
    the image (Sect. VII-B, scale-free: 2 cm for a 40-pixel view of a 3 m plate), and a
    hologram it made carries it. Numbers a person types reach :data:`WAVELENGTH_RANGE` and
    :data:`PITCH_RANGE` outside such a block; real waves and samplings all lie inside them."""
    token = _SCALE_FREE.set(True)
    try:
        yield
    finally:
        _SCALE_FREE.reset(token)


def wavelength(name: str, value) -> float:
    """A wavelength [m] in :data:`WAVELENGTH_RANGE`; a value outside it is refused with the
    unit it most likely is in ("633 looks like nanometres: pass 633e-9")."""
    return _optical(name, value, WAVELENGTH_RANGE, "wavelength")


def pitch(name: str, value) -> float:
    """A sample pitch [m] in :data:`PITCH_RANGE`, refused like :func:`wavelength` outside."""
    return _optical(name, value, PITCH_RANGE, "pitch")


def _optical(name: str, value, limits: tuple[float, float], kind: str) -> float:
    if _SCALE_FREE.get():
        return length(name, value)
    v = _finite(name, value, "m")
    lo, hi = limits
    if lo <= v <= hi:
        return v
    hint = ""
    fits = [
        (abs(math.log10(v * f / _TYPICAL[kind])), unit, f)
        for unit, f in _UNITS
        if lo <= v * f <= hi
    ]
    if fits and v >= 0.1:  # a number of a smaller unit (below 0.1 m, a real but odd length)
        _, unit, f = min(fits)
        metres = f"{v * f:g}" if "e" in f"{v:g}" else f"{v:g}e{round(math.log10(f))}"
        hint = f" ({v:g} looks like {unit}: pass {metres})"
    raise InputError(
        f"{name} must be in [{lo:g}, {hi:g}] [m] ({_SPANS[kind]}); got {shown(value)}{hint}"
    )


def integer(name: str, value, minimum: int | None = None, maximum: int | None = None) -> int:
    """``value`` as an int: a whole number (not a bool), in [minimum, maximum] when given."""
    allowed = "an integer" + (
        f" >= {minimum}"
        if maximum is None and minimum is not None
        else f" in [{minimum}, {maximum}]"
        if maximum is not None
        else ""
    )
    ok = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
    if isinstance(value, (float, np.floating)) and math.isfinite(value) and value == int(value):
        ok = True  # 2.0 is the integer 2
    if not ok:
        raise InputError(f"{name} must be {allowed}; got {shown(value)}")
    v = int(value)
    if (minimum is not None and v < minimum) or (maximum is not None and v > maximum):
        raise InputError(f"{name} must be {allowed}; got {shown(value)}")
    return v


def digest(name: str, value) -> str:
    """A recording's digest: up to 64 lowercase hexadecimal digits, or '' (none known)."""
    if not isinstance(value, str) or len(value) > 64 or value.strip("0123456789abcdef"):
        raise InputError(
            f"{name} must be the recording's digest (up to 64 hexadecimal digits) "
            f"or ''; got {value!r}"[:200]
        )
    return value


def choice(name: str, value, options: tuple) -> str:
    """One of the strings ``options``."""
    if not isinstance(value, str) or value not in options:
        raise InputError(
            f"{name} must be one of {', '.join(map(repr, options))}; got {shown(value)}"[:300]
        )
    return value


def exposure(value, name: str = "exposure") -> float:
    """A linear factor on the radiance, as a float: in (0, MAX_EXPOSURE]."""
    v = _finite(name, value, "")
    if not 0 < v <= MAX_EXPOSURE:
        raise InputError(
            f"{name} must be in (0, {MAX_EXPOSURE:g}] (a linear factor); got {shown(value)}"
        )
    return v


def seed(value, name: str = "seed") -> int:
    """A random generator's seed: an integer >= 0."""
    return integer(name, value, 0)


def index(name: str, value, count: int) -> int:
    """An index into ``count`` items: an integer in [0, count - 1]."""
    return integer(name, value, 0, count - 1)


def vector(name: str, value, size: int = 3, unit: str = "") -> np.ndarray:
    """``size`` finite numbers as a float64 array."""
    try:
        v = np.asarray(value, np.float64)
    except (TypeError, ValueError):
        v = None
    if v is None or v.shape != (size,) or not np.isfinite(v).all():
        raise InputError(f"{name} must be {size} finite numbers{_unit(unit)}; got {shown(value)}")
    return v


def pair(name: str, value, unit: str = "", limit: float | None = None) -> tuple[float, float]:
    """A finite (x, y) pair, each within ±``limit`` when given."""
    try:
        x, y = value
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a pair (x, y){_unit(unit)}; got {shown(value)}") from None
    if limit is None:
        return _finite(name, x, unit), _finite(name, y, unit)
    return within(name, x, limit, unit), within(name, y, limit, unit)


def within(name: str, value, limit: float, unit: str = "m") -> float:
    """A finite number in [-limit, limit] (a distance or an offset: MAX_LENGTH keeps a
    wave's phase k·z meaningful in float64)."""
    v = _finite(name, value, unit)
    if abs(v) > limit:
        raise InputError(
            f"{name} must be in [-{limit:g}, {limit:g}]{_unit(unit)}; got {shown(value)}"
        )
    return v


def array(name: str, value, allowed: str) -> np.ndarray:
    """``value`` as a float64 array, or :class:`InputError` saying what is ``allowed``."""
    a = _matrix(value)
    if not a.size and np.size(value):
        raise InputError(f"{name} must be {allowed}; got {type(value).__name__}")
    return a


def shape2d(name: str, value) -> tuple[int, int]:
    """A (rows, cols) shape of positive integers."""
    try:
        h, w = (int(v) for v in value)
        ok = all(float(v) == int(v) for v in value)
    except (TypeError, ValueError):
        ok = False
    if not ok or h < 1 or w < 1:
        raise InputError(f"{name} must be a pair of integers >= 1 (rows, cols); got {shown(value)}")
    return h, w


def rotation(name: str, value) -> np.ndarray:
    """A proper 3x3 rotation matrix (orthonormal, determinant +1) as float64."""
    m = _matrix(value)
    if m.shape != (3, 3) or not np.isfinite(m).all():
        raise InputError(f"{name} must be a finite 3x3 matrix; got shape {m.shape}")
    if not np.allclose(m.T @ m, np.eye(3), atol=1e-9) or np.linalg.det(m) < 0:
        raise InputError(f"{name} must be a rotation (orthonormal, det +1)")
    return m


def rigid_pose(name: str, value) -> np.ndarray:
    """A finite 4x4 pose of a rotation and a translation [m] (bottom row 0 0 0 1) as float64."""
    m = _matrix(value)
    if m.shape != (4, 4) or not np.isfinite(m).all():
        raise InputError(f"{name} must be a finite 4x4 matrix; got shape {m.shape}")
    rotation(f"{name} rotation", m[:3, :3])
    if not np.array_equal(m[3], [0, 0, 0, 1]):
        raise InputError(
            f"{name} must have the bottom row 0 0 0 1 (a rigid pose); got {m[3].tolist()}"
        )
    return m


def host_field(name: str, field: np.ndarray) -> np.ndarray:
    """A 2-D finite complex NumPy array."""
    a = np.asarray(field)
    if a.ndim != 2:
        raise InputError(f"{name} must be a 2-D array [rows=y, cols=x]; got {a.ndim}-D")
    if not np.issubdtype(a.dtype, np.number):
        raise InputError(f"{name} must be numeric; got dtype {a.dtype}")
    if not a.size:
        raise InputError(f"{name} must hold at least 1x1 samples; got {a.shape[0]}x{a.shape[1]}")
    if not np.isfinite(a).all():
        raise InputError(f"{name} must be finite; it holds NaN or infinite values")
    return a


def _matrix(value) -> np.ndarray:
    """``value`` as a float64 array, or an empty one where it holds no numbers."""
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        return np.zeros(0)


def _finite(name: str, value, unit: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number{_unit(unit)}; got {shown(value)}") from None
    if not math.isfinite(v):
        raise InputError(f"{name} must be finite{_unit(unit)}; got {shown(value)}")
    return v


def _unit(unit: str) -> str:
    return f" [{unit}]" if unit else ""
