"""Phase-only encodings of a complex field for a phase-only SLM (facts §7).

Double-phase (Hsueh & Sawchuk 1978; checkerboarded as Maimone, Georgiou & Kollin 2017): a
sample c = A·exp(iφ) with A <= 1 is the mean of two unit phasors, exp(i(φ + α)) and
exp(i(φ − α)) with α = arccos A. Laid out on a checkerboard, the pattern is c plus
(−1)^(i+j)·i·sin α·exp(iφ): the second term sits around the Nyquist corner (1/2p, 1/2p), so a
low-pass (the display's 4f filter, or a band-limited propagation) leaves c where c and
sin α·exp(iφ) are band-limited to under half the Nyquist frequency.
"""

from __future__ import annotations

import numpy as np

from .. import validate
from ..validate import InputError


def double_phase(field, *, max_amplitude=None) -> np.ndarray:
    """Encode a complex field as the checkerboarded double-phase pattern of a phase-only SLM.

    Parameters
    ----------
    field : (H, W) complex array, NumPy or device array
        The field to encode; device arrays are read back.
    max_amplitude : float, optional
        m [field units], normalising the amplitudes (default: the largest ``|c|``).

    Returns
    -------
    (H, W) float64 ndarray
        Phases [rad] in (−π, π], on the host (an SLM's image): φ + α where row + column is
        even, φ − α where odd, α = arccos(``|c|``/m).

    Raises
    ------
    InputError
        Where a sample's amplitude is above ``max_amplitude``: the encoding never clips
        silently.

    Examples
    --------
    Amplitude 0.5 of m = 1 gives ± arccos(0.5) = ± π/3:

    >>> import numpy as np
    >>> from holo_core import double_phase
    >>> double_phase(np.full((2, 2), 0.5 + 0j), max_amplitude=1.0).round(4).tolist()
    [[1.0472, -1.0472], [-1.0472, 1.0472]]
    """
    c = normalised(field, max_amplitude)
    alpha = np.arccos(np.clip(np.abs(c), 0, 1))
    rows, cols = np.indices(c.shape)
    sign = np.where((rows + cols) % 2 == 0, 1.0, -1.0)
    return np.angle(np.exp(1j * (np.angle(c) + sign * alpha)))


def normalised(field, max_amplitude=None) -> np.ndarray:
    """``field`` (a device array is read back) as complex128 divided by m, its largest |c| or
    ``max_amplitude`` (field units); refused when all zero or above m: an encoding never clips
    silently."""
    c = field.get() if hasattr(field, "get") and hasattr(field, "queue") else field
    c = validate.host_field("field", c).astype(np.complex128)
    top = float(np.abs(c).max())
    m = top if max_amplitude is None else validate.positive("max_amplitude", max_amplitude)
    if m == 0:
        raise InputError("field must not be all zero (no amplitude to encode)")
    if top > m * (1 + 1e-12):
        raise InputError(
            f"field's largest amplitude {top:.6g} exceeds max_amplitude {m!r}; "
            f"the encoding would clip it"
        )
    return c / m
