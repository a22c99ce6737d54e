"""A thin lens's phase on a sampled field (the aberration-free lens of Eq. 24).

t(x, y) = exp(−i·k·(√(ρ² + f²) − f)), ρ the distance from the lens's centre: a plane wave of
wavelength λ = 2π/k leaves it as a spherical wave converging to the point at f on the axis
(f < 0: a diverging lens). The phase is formed in float64 and reduced mod 2π before the
complex64 multiply, on the host or on the device where the field is.
"""

from __future__ import annotations

import math

import numpy as np

from .. import validate
from ..opencl import as_device, like_input
from ..opencl.arrays import cached
from ..propagation import grid
from ..propagation.batch import batched
from ..propagation.convolution import multiply


def _thin_lens(field, *, wavelength, pitch, focal_length, centre=(0.0, 0.0)):
    """One plane: see :func:`thin_lens`."""
    wavelength, (px, py) = grid.wave_pair(wavelength, pitch)
    f = validate.within("focal_length", focal_length, validate.MAX_LENGTH)
    if abs(f) < validate.MIN_LENGTH:
        raise validate.InputError(
            f"focal_length must be non-zero [m]; got {validate.shown(focal_length)}"
        )
    cx, cy = validate.pair("centre", centre, "m", validate.MAX_LENGTH)
    rt, dev, from_host = as_device(field)
    h, w = dev.shape

    def make():
        x = grid.coords(w, px)[None, :] - cx
        y = grid.coords(h, py)[:, None] - cy
        rho2 = x * x + y * y
        # √(ρ² + f²) − f without the cancellation: ρ²/(√(ρ² + f²) + |f|), signed by f
        sag = rho2 / (np.sqrt(rho2 + f * f) + abs(f)) * math.copysign(1.0, f)
        phase = np.remainder(-2 * np.pi / wavelength * sag, 2 * np.pi)
        return np.exp(1j * phase), []

    screen, _ = cached(rt, ("thin-lens", (h, w), wavelength, px, py, f, cx, cy), make)
    out = dev.copy()
    multiply(rt, out, screen)
    return like_input(out, from_host)


def _thin_lens_adjoint(field, *, wavelength, pitch, focal_length, centre=(0.0, 0.0)):
    """One plane of :func:`thin_lens`'s adjoint: it multiplies by t̄, the lens of focal length
    −f."""
    f = validate.within("focal_length", focal_length, validate.MAX_LENGTH)
    return _thin_lens(field, wavelength=wavelength, pitch=pitch, focal_length=-f, centre=centre)


thin_lens = batched(_thin_lens)
thin_lens.adjoint = batched(_thin_lens_adjoint)
thin_lens.__doc__ = """Multiply a field by a thin lens's phase: the field just behind the lens.

Parameters
----------
field : (H, W) or (..., H, W) complex array, NumPy or device, or Field
    The field just before the lens. A :class:`~holo_core.scene.field.Field` brings its own
    wavelength and pitch and gets a Field back on the same plane.
wavelength : float
    Wavelength λ [m].
pitch : float or (float, float)
    Sample spacing [m], or (x, y).
focal_length : float
    Focal length f [m], non-zero; f < 0 diverges.
centre : (float, float)
    The lens's centre (x, y) [m] on the grid.

Returns
-------
ndarray, pyopencl.array.Array or Field
    U·exp(−ik(√(ρ² + f²) − f)), complex64, like the input.

Raises
------
InputError
    Where ``focal_length`` is zero or not finite, or ``centre`` is not finite.

Notes
-----
The thin lens of Eq. 24, L(x, y) = exp(−ikr), r = √(x² + y² + f²), with the constant
phase exp(ikf) taken out.

Examples
--------
>>> import numpy as np
>>> from holo_core import thin_lens
>>> v = thin_lens(np.ones((64, 64), complex), wavelength=633e-9, pitch=4e-6,
...               focal_length=0.1)
>>> v.shape, round(float(abs(v[0, 0])), 3)
((64, 64), 1.0)
"""
