"""Checks at the API boundary: bad input raises ``ValueError`` naming the field and its range."""

from __future__ import annotations

import math
import warnings

import numpy as np


class SamplingWarning(UserWarning):
    """A grid cannot represent the requested wave alias-free; the message names the safe limit."""


def warn_sampling(message: str) -> None:
    warnings.warn(message, SamplingWarning, stacklevel=3)


def positive(name: str, value, unit: str = "") -> float:
    """``value`` as a float, or ``ValueError`` unless it is finite and > 0."""
    v = _finite(name, value, unit)
    if v <= 0:
        raise ValueError(f"{name} must be > 0{_unit(unit)}; got {value!r}")
    return v


def at_least(name: str, value, minimum: float, unit: str = "") -> float:
    v = _finite(name, value, unit)
    if v < minimum:
        raise ValueError(f"{name} must be >= {minimum}{_unit(unit)}; got {value!r}")
    return v


def finite(name: str, value, unit: str = "") -> float:
    return _finite(name, value, unit)


def pair(name: str, value, unit: str = "") -> tuple[float, float]:
    """A finite (x, y) pair."""
    try:
        x, y = value
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair (x, y){_unit(unit)}; got {value!r}") from None
    return _finite(name, x, unit), _finite(name, y, unit)


def shape2d(name: str, value) -> tuple[int, int]:
    """A (rows, cols) shape of positive integers."""
    try:
        h, w = (int(v) for v in value)
        ok = all(float(v) == int(v) for v in value)
    except (TypeError, ValueError):
        ok = False
    if not ok or h < 1 or w < 1:
        raise ValueError(f"{name} must be a pair of integers >= 1 (rows, cols); got {value!r}")
    return h, w


def rotation(name: str, value) -> np.ndarray:
    """A proper 3x3 rotation matrix (orthonormal, determinant +1) as float64."""
    m = np.asarray(value, dtype=np.float64)
    if m.shape != (3, 3) or not np.isfinite(m).all():
        raise ValueError(f"{name} must be a finite 3x3 matrix; got shape {m.shape}")
    if not np.allclose(m.T @ m, np.eye(3), atol=1e-9) or np.linalg.det(m) < 0:
        raise ValueError(f"{name} must be a rotation (orthonormal, det +1)")
    return m


def host_field(name: str, field: np.ndarray) -> np.ndarray:
    """A 2-D finite complex NumPy array."""
    a = np.asarray(field)
    if a.ndim != 2:
        raise ValueError(f"{name} must be a 2-D array [rows=y, cols=x]; got {a.ndim}-D")
    if not np.issubdtype(a.dtype, np.number):
        raise ValueError(f"{name} must be numeric; got dtype {a.dtype}")
    if not np.isfinite(a).all():
        raise ValueError(f"{name} must be finite; it holds NaN or infinite values")
    return a


def _finite(name: str, value, unit: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number{_unit(unit)}; got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite{_unit(unit)}; got {value!r}")
    return v


def _unit(unit: str) -> str:
    return f" [{unit}]" if unit else ""
