"""Direct Rayleigh-Sommerfeld integration (Eq. 7): the slow, exact reference.

Each input sample is a secondary source of area pitch² radiating the first-kind impulse
response h = z/(2π r²)·(1/r - ik)·exp(ikr); for k·r >> 1 this is Eq. 7 with the factor 1/(iλ)
(the paper's i/λ belongs to the opposite sign convention). For a negative distance the
conjugate response carries the field backwards, as the angular spectrum does.
"""

from __future__ import annotations

import math

import numpy as np
from numpy import int32

from .. import validate
from ..opencl import as_device, associated, is_device_array, like_input
from ..opencl.arrays import empty
from ..opencl.kernel import BUFFER, REAL, kernel
from ..validate import InputError, shown
from . import grid

PROGRAM = associated(__file__)
# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
RS_DIRECT = kernel(PROGRAM, "rs_direct", out=BUFFER, src=BUFFER, h=int32, w=int32,
                   pitch=REAL, src_x0=REAL, src_y0=REAL, out_pitch=REAL, out_x0=REAL,
                   out_y0=REAL, z=REAL, k=REAL, sgn=REAL, gr=REAL, gi=REAL)
# fmt: on


def rayleigh_sommerfeld(
    field, *, wavelength, pitch, distance, offset=(0.0, 0.0), out_shape=None, out_pitch=None
):
    """Propagate a field to any grid of the parallel plane at ``distance`` by direct summation.

    Parameters
    ----------
    field : (H, W) complex array, NumPy or OpenCL device array
        Source field, pixel centres as in :mod:`.grid`.
    wavelength : float
        Wavelength λ [m].
    pitch : float
        Source sample spacing [m].
    distance : float
        Signed distance z to the target plane [m], non-zero.
    offset : (float, float)
        Position (x0, y0) [m] of the target grid's centre relative to the source's.
    out_shape : (int, int), optional
        Target grid (rows, cols); default the source shape.
    out_pitch : float, optional
        Target sample spacing [m]; default ``pitch``.

    Returns
    -------
    ndarray or pyopencl.array.Array
        Complex64 array of ``out_shape``, like the input.

    Raises
    ------
    InputError
        Where ``distance`` is zero or not finite, or ``wavelength`` or ``pitch`` is not finite
        and > 0.

    Warns
    -----
    SamplingWarning
        Where the impulse response is aliased on the grids at this distance.

    Notes
    -----
    The first Rayleigh–Sommerfeld solution, Eq. 7: a sum of spherical waves e^{ikr}/r from the
    source samples, weighted by the obliquity (r·n)/r. Cost is O(sources · outputs): zero
    samples are skipped, and NumPy input is first cropped to its non-zero bounding box.

    Examples
    --------
    One point source seen on axis 5 mm away: ``|U| = pitch²/(λz)``.

    >>> import numpy as np
    >>> from holo_core import rayleigh_sommerfeld
    >>> u = np.zeros((64, 64), complex)
    >>> u[32, 32] = 1
    >>> v = rayleigh_sommerfeld(u, wavelength=500e-9, pitch=5e-6, distance=5e-3)
    >>> v.shape, round(float(abs(v[32, 32])), 4)
    ((64, 64), 0.01)
    """
    wavelength, pitch = grid.wave(wavelength, pitch)
    z = validate.within("distance", distance, validate.MAX_LENGTH)
    if abs(z) < validate.MIN_LENGTH:
        raise InputError(
            f"distance must be non-zero for rayleigh_sommerfeld, |distance| >= "
            f"{validate.MIN_LENGTH:g} m (the integral is singular on the source "
            f"plane); got {shown(distance)}"
        )
    x0, y0 = validate.pair("offset", offset, "m", validate.MAX_LENGTH)
    out_pitch = pitch if out_pitch is None else validate.pitch("out_pitch", out_pitch)
    if not is_device_array(field):
        field = validate.host_field("field", field)
    out_shape = validate.shape2d("out_shape", field.shape if out_shape is None else out_shape)
    src_x0, src_y0 = -(field.shape[1] - 1) / 2 * pitch, -(field.shape[0] - 1) / 2 * pitch
    if not is_device_array(field):
        field, (r0, c0) = grid.support(field)
        src_x0, src_y0 = src_x0 + c0 * pitch, src_y0 + r0 * pitch
    rt, src, from_host = as_device(field)
    out_x0 = x0 - (out_shape[1] - 1) / 2 * out_pitch
    out_y0 = y0 - (out_shape[0] - 1) / 2 * out_pitch
    _check_aliasing(
        src.shape,
        pitch,
        (src_x0, src_y0),
        out_shape,
        out_pitch,
        (out_x0, out_y0),
        wavelength,
        abs(z),
    )
    k, sgn = 2 * math.pi / wavelength, math.copysign(1.0, z)
    g = pitch**2 * np.exp(1j * math.remainder(sgn * k * abs(z), 2 * math.pi))
    out = empty(rt, out_shape)
    RS_DIRECT.launch(
        rt,
        out_shape,
        options=rt.real_options,
        out=out,
        src=src,
        h=src.shape[0],
        w=src.shape[1],
        pitch=pitch,
        src_x0=src_x0,
        src_y0=src_y0,
        out_pitch=out_pitch,
        out_x0=out_x0,
        out_y0=out_y0,
        z=abs(z),
        k=k,
        sgn=sgn,
        gr=g.real,
        gi=g.imag,
    )
    return like_input(out, from_host)


def _check_aliasing(shape, pitch, src0, out_shape, out_pitch, out0, wavelength, z):
    """Warn when the impulse response is under-sampled at the source pitch somewhere."""
    sin_max = wavelength / (2 * pitch)  # the steepest ray the source pitch samples
    if sin_max >= 1:
        return
    span = [
        max(abs(o + (m - 1) * op - s), abs(o - s - (n - 1) * pitch))
        for o, m, op, s, n in (
            (out0[0], out_shape[1], out_pitch, src0[0], shape[1]),
            (out0[1], out_shape[0], out_pitch, src0[1], shape[0]),
        )
    ]
    rho = math.hypot(*span)
    z_min = rho * math.sqrt(1 / sin_max**2 - 1)
    if z < z_min:
        validate.warn_sampling(
            f"rayleigh_sommerfeld: at |distance| = {z:.4g} m the impulse response is aliased at "
            f"lateral separations up to {rho:.4g} m; this grid needs |distance| >= {z_min:.4g} m "
            f"or a pitch <= {wavelength * math.hypot(rho, z) / (2 * rho):.4g} m"
        )
