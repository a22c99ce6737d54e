"""A phase SLM's codes: the phase each code shows (its response), and the code nearest a
wanted phase.

Without a table, code k of a ``b``-bit display shows k·R/2^b, R its ``phase_range`` (2π: the
2^b levels fill one wave, code 2^b being code 0 again; 3π: the top codes repeat the bottom
ones a wave higher), negated when the display is ``inverted``. A
:class:`~holo_core.phase.slm.PhaseTable` replaces that line with the measured phase of each
code. A wanted phase θ (any real number) inside the codes' span takes the code nearest θ
itself, so that a pattern whose phases lie inside a 3π range (double-phase's φ ± α) keeps
them unwrapped; one outside it, the code nearest θ modulo 2π.
"""

from __future__ import annotations

import math

import numpy as np

from ..validate import InputError


def response(display, table=None) -> np.ndarray:
    """The phase [rad] each code of ``display`` shows, float64 (2^bit_depth,): ``table``'s
    phases when given (a :class:`~holo_core.phase.slm.PhaseTable`), else the display's line
    (module docstring).

    Examples
    --------
    >>> import math
    >>> from holo_core.phase import Display, response
    >>> slm = Display(name="lab", resolution=(4, 1), pitch=8e-6, bit_depth=2, inverted=True)
    >>> response(slm) / math.pi
    array([-0. , -0.5, -1. , -1.5])
    """
    n = 2**display.bit_depth
    if table is not None:
        if table.phases.size != n:
            raise InputError(
                f"{table.source or 'phase table'}: {table.phases.size} entries; "
                f"the {display.bit_depth}-bit display needs {n}"
            )
        return table.phases.copy()
    line = np.arange(n) * (display.phase_range / n)
    return -line if display.inverted else line


class Quantiser:
    """The code nearest each wanted phase on a given response (module docstring).

    ``curve``: (2^b,) phases [rad] of the codes. A wanted phase inside the curve's span takes
    the code nearest it among the codes themselves (within half a step on a line); one
    outside is brought into [min, min + 2π) and takes the nearest among the codes and their
    copies a wave below and above (a 2π line's top code is a step from its bottom one). Both
    are found by bisection in the sorted phases, or (the same codes, 6 times faster at
    1080p) looked up in :class:`_Bins` over each span, bisection left to the phases in a bin
    that holds a change of code."""

    def __init__(self, curve):
        c = np.asarray(curve, np.float64)
        self.curve = c
        self.low, self.high = float(c.min()), float(c.max())
        order = np.argsort(c, kind="stable")
        self.inside = (c[order], order)
        shifted = np.concatenate([c - 2 * math.pi, c, c + 2 * math.pi])
        codes = np.tile(np.arange(c.size), 3)
        order = np.argsort(shifted, kind="stable")
        self.around = (shifted[order], codes[order])
        self._bins = (
            _Bins(self.low, self.high, *self.inside),
            _Bins(self.low, self.low + 2 * math.pi, *self.around),
        )

    def __call__(self, phase) -> np.ndarray:
        """uint16 codes of ``phase`` [rad] (finite, any shape)."""
        t = np.asarray(phase, np.float64)
        if not np.isfinite(t).all():
            raise InputError("phase must be finite; it holds NaN or infinite values")
        inside = (t >= self.low) & (t <= self.high)
        out = np.empty(t.shape, np.uint16)
        if inside.all():
            return self._bins[0](t.ravel()).reshape(t.shape)
        out[inside] = self._bins[0](t[inside])
        outside = ~inside
        out[outside] = self._bins[1](self.low + np.mod(t[outside] - self.low, 2 * math.pi))
        return out


class _Bins:
    """The code nearest each phase in [lo, hi] (:func:`_nearest` of ``values``, ``codes``)
    looked up by bins: a bin whose edges, and its neighbours' edges, have one nearest code
    is that code throughout (the nearest-code regions are intervals; the neighbours cover a
    phase rounded into the next bin); the phases in the other bins are bisected."""

    COUNT = 1 << 16  # bins: a 256-code line changes code in under 1.2 % of them

    def __init__(self, lo: float, hi: float, values, codes):
        self.lo, self.values, self.codes = lo, values, codes
        n = self.COUNT
        self.scale = n / (hi - lo) if hi > lo else 0.0
        edges = lo + np.arange(n + 1) / self.scale if hi > lo else np.full(n + 1, lo)
        at = _nearest(edges, values, codes)
        same = at[:-1] == at[1:]
        sure = same.copy()
        sure[1:] &= same[:-1]
        sure[:-1] &= same[1:]
        self.table = at[:-1]
        self.sure = sure

    def __call__(self, t) -> np.ndarray:
        i = ((t - self.lo) * self.scale).astype(np.int64)
        np.clip(i, 0, self.COUNT - 1, out=i)
        out = self.table[i]
        doubt = ~self.sure[i]
        if doubt.any():
            out[doubt] = _nearest(t[doubt], self.values, self.codes)
        return out


def _nearest(t, values, codes) -> np.ndarray:
    """The code of the value nearest each of ``t`` among sorted ``values``."""
    if not t.size:
        return np.zeros(0, np.uint16)
    i = np.clip(np.searchsorted(values, t), 1, values.size - 1)
    pick = np.where(t - values[i - 1] <= values[i] - t, i - 1, i)
    return codes[pick].astype(np.uint16)


def quantise(phase, display, table=None) -> np.ndarray:
    """The uint16 codes (0 .. 2^bit_depth − 1) of ``phase`` [rad] on ``display`` through
    ``table`` (or its line): the nearest code modulo 2π.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.phase import Display, quantise
    >>> slm = Display(name="lab", resolution=(4, 1), pitch=8e-6, bit_depth=8)
    >>> quantise(np.array([0.0, np.pi, -np.pi / 2, 2 * np.pi]), slm)
    array([  0, 128, 192,   0], dtype=uint16)
    """
    return Quantiser(response(display, table))(phase)


def shown(codes, display, table=None) -> np.ndarray:
    """The phase [rad] the ``codes`` show, float64: the response at each code."""
    c = np.asarray(codes)
    n = 2**display.bit_depth
    if c.size and (c.min() < 0 or c.max() >= n):
        raise InputError(
            f"codes must be in 0..{n - 1} for a {display.bit_depth}-bit display; "
            f"got {c.min()}..{c.max()}"
        )
    return response(display, table)[c.astype(np.int64)]
