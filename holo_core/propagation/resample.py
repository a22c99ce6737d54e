"""Resampling between grids of different size and pitch (the four cases of Fig. 4).

One band-limited interpolation covers all four: per axis, out = K·in with
K[j, i] = (1/n)·Σ_m w_m·cos(2π f_m (x'_j - x_i)) over the input's DFT frequencies f_m, cut at
the lower of the two Nyquist frequencies (cut in frequency) or not (zero-pad in frequency),
and zero for output samples outside the input window (zero-pad in space; samples outside the
output window are simply not asked for: cut in space). The sum has a closed form (a Dirichlet
kernel); edge bins that fall exactly on the cut get half weight, which keeps K real and makes
it the identity between equal grids.
"""

from __future__ import annotations

import math

import numpy as np
from numpy import int32

from .. import validate
from ..opencl import as_device, associated, like_input
from ..opencl.arrays import empty
from ..opencl.kernel import BUFFER, kernel
from . import grid

PROGRAM = associated(__file__)
APPLY_AXIS0, APPLY_AXIS1 = (
    kernel(PROGRAM, name, out=BUFFER, K=BUFFER, src=BUFFER, n_in=int32)
    for name in ("apply_axis0", "apply_axis1")
)


def resample(field, *, pitch, out_shape, out_pitch):
    """Resample a field onto a centred grid of ``out_shape`` at ``out_pitch``.

    Parameters
    ----------
    field : (H, W) complex array, NumPy or OpenCL device array
        Input field, pixel centres as in :mod:`.grid`.
    pitch : float
        Input sample spacing [m].
    out_shape : (int, int)
        Output grid (rows, cols).
    out_pitch : float
        Output sample spacing [m]; coarser than ``pitch`` low-passes at the new Nyquist
        frequency, finer interpolates (band-limited).

    Returns
    -------
    ndarray or pyopencl.array.Array
        Complex64 array of ``out_shape``, like the input.

    Raises
    ------
    InputError
        Where ``pitch`` or ``out_pitch`` is not finite and > 0, or ``out_shape`` is not two
        positive integers.

    Notes
    -----
    The re-sampling step of the paper's pipeline (Sect. IV-D, Fig. 4), where source and target
    apertures differ in size or resolution.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import resample
    >>> v = resample(np.ones((64, 64), complex), pitch=4e-6, out_shape=(32, 32), out_pitch=8e-6)
    >>> v.shape, round(float(abs(v[16, 16])), 3)
    ((32, 32), 1.0)
    """
    pitch = validate.pitch("pitch", pitch)
    out_pitch = validate.pitch("out_pitch", out_pitch)
    out_shape = validate.shape2d("out_shape", out_shape)
    rt, src, from_host = as_device(field)
    (h, w), (oh, ow) = src.shape, out_shape
    ky = rt.to_device(interpolation_matrix(h, pitch, oh, out_pitch), np.float32)
    kx = rt.to_device(interpolation_matrix(w, pitch, ow, out_pitch), np.float32)
    rows = empty(rt, (oh, w))
    APPLY_AXIS0.launch(rt, (oh, w), out=rows, K=ky, src=src, n_in=h)
    out = empty(rt, (oh, ow))
    APPLY_AXIS1.launch(rt, (oh, ow), out=out, K=kx, src=rows, n_in=w)
    return like_input(out, from_host)


def interpolation_matrix(n: int, pitch: float, n_out: int, out_pitch: float) -> np.ndarray:
    """The band-limited interpolation matrix of one axis (the module docstring's K).

    Parameters
    ----------
    n : int
        Input samples.
    pitch : float
        Input sample spacing [m].
    n_out : int
        Output samples.
    out_pitch : float
        Output sample spacing [m].

    Returns
    -------
    (n_out, n) float64 ndarray
        K with out = K·in, both grids centred; rows of output samples outside the input
        window are zero.

    Notes
    -----
    K[j, i] = (1/n)·Σ_m w_m·cos(2π f_m (x'_j − x_i)) over the input's DFT frequencies, cut at
    the lower of the two Nyquist frequencies, in closed form (a Dirichlet kernel); bins that
    fall on the cut get half weight, which makes K real and the identity between equal grids.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.propagation import interpolation_matrix
    >>> bool(np.allclose(interpolation_matrix(8, 1e-6, 8, 1e-6), np.eye(8)))
    True
    >>> interpolation_matrix(16, 1e-6, 8, 2e-6).shape
    (8, 16)
    """
    df = 1.0 / (n * pitch)
    cut = min(1 / (2 * pitch), 1 / (2 * out_pitch)) / df  # the band's edge, in bins
    d = grid.coords(n_out, out_pitch)[:, None] - grid.coords(n, pitch)[None, :]
    theta = math.pi * df * d
    s, c = np.sin(theta), np.cos(theta)
    small = np.abs(s) < 1e-12  # d on a multiple of the window: the kernel's limit
    s_safe = np.where(small, 1.0, s)
    if abs(cut - round(cut)) < 1e-9:  # the cut falls on bins ±M: they get half weight
        m = round(cut)
        k = np.where(small, 2.0 * m, np.sin(2 * m * theta) * c / s_safe)
    else:
        m = math.floor(cut)
        k = np.where(
            small,
            (2.0 * m + 1) * np.cos((2 * m + 1) * theta) / np.where(small, c, 1),
            np.sin((2 * m + 1) * theta) / s_safe,
        )
    k /= n
    inside = np.abs(grid.coords(n_out, out_pitch)) <= n * pitch / 2 * (1 + 1e-12)
    return k * inside[:, None]
