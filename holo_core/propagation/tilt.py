"""Tilted planes by rotating the angular spectrum (Eq. 11), and placed planes (Sect. IV-D).

A rotation ``M`` has the target plane's axes (ξ, η, ζ) as its columns, in source coordinates:
it maps target coordinates to source coordinates, and target frequencies to source ones,
f = M·f'. Both planes pass through the source grid's centre. The rotated spectrum is read
between the source's bins as a non-uniform FFT reads them: a TAPS-wide "exponential of
semicircle" kernel, with the source divided beforehand by the kernel's Fourier transform
(deapodization), so that ``padding`` >= 2 gives ~1e-5 for any target grid. Linear interpolation
(Delen & Hooker) erred by 1e-2 on a tilted beam, and by 10-25 % where the target grid is larger
than the source (a primitive carried to a hologram): it copies the source at every padded
period, attenuated only by sinc².
"""

from __future__ import annotations

import math

import numpy as np
from numpy import float32, int32

from .. import validate
from ..opencl import as_device, associated, like_input
from ..opencl.arrays import by_rows, cached, empty, place, window
from ..opencl.kernel import BUFFER, REAL, kernel
from ..validate import InputError
from . import grid
from .angular_spectrum import angular_spectrum
from .convolution import multiply

PROGRAM = associated(__file__)
_ROTATION = {f"m{i}{j}": REAL for i in range(3) for j in range(3)}  # its rows
# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
ROTATE_SPECTRUM = kernel(PROGRAM, "rotate_spectrum", dst=BUFFER, A=BUFFER, hs=int32,
                         ws=int32, ht=int32, wt=int32, dft_y=REAL, dft_x=REAL,
                         dfs_y=REAL, dfs_x=REAL, inv_l2=REAL, **_ROTATION, ct_y=REAL,
                         ct_x=REAL, scale=float32, es=BUFFER)
# fmt: on

TAPS = 6  # spectrum interpolation taps per axis (error ~10^-(TAPS-1) at padding 2)
ES_BETA = 2.30  # the kernel's shape per tap for 2x oversampling (Barnett et al. 2019)
ES_TABLE = 4096  # kernel samples, linearly interpolated (error ~1e-6)


def tilt(
    field,
    *,
    wavelength,
    pitch,
    rotation,
    padding=2,
    out_shape=None,
    out_pitch=None,
    out_padding=None,
):
    """Propagate a field to the plane through the source centre with orientation ``rotation``.

    Parameters
    ----------
    field : (H, W) complex array, NumPy or OpenCL device array
        Source field on z = 0, pixel centres as in :mod:`.grid`.
    wavelength : float
        Wavelength λ [m].
    pitch : float
        Source sample spacing [m].
    rotation : (3, 3) array
        Rotation matrix M whose columns are the target axes ξ, η, ζ in source coordinates.
    padding : float
        Zero-padding factor of source and target grids, >= 2 for the interpolation's accuracy
        (at 1 the field may fill the window, where the deapodization grows large).
    out_shape : (int, int), optional
        Target grid (rows, cols); default the source shape.
    out_pitch : float, optional
        Target sample spacing [m]; default ``pitch``.
    out_padding : float, optional
        Zero-padding factor of the target grid alone, default ``padding``: the rotated field
        wraps around the padded target, so it must hold the target and the field's reach
        beyond it (the interpolation's accuracy rests on the source's padding only).

    Returns
    -------
    ndarray or pyopencl.array.Array
        Complex64 field on the target plane, like the input. Components travelling backwards in
        either frame are dropped, so only light that reaches the target from the source side
        stays.

    Raises
    ------
    InputError
        Where ``rotation`` is not a (3, 3) rotation, or ``wavelength``, ``pitch`` or a padding
        is out of range.

    Notes
    -----
    The rotation of the angular spectrum, Eq. 11: target frequencies map to source ones by
    f = M·f', read between the source's bins by a non-uniform FFT's kernel (module docstring).

    Examples
    --------
    The identity rotation leaves a plane wave as it is:

    >>> import numpy as np
    >>> from holo_core import tilt
    >>> v = tilt(np.ones((64, 64), complex), wavelength=633e-9, pitch=4e-6, rotation=np.eye(3))
    >>> v.shape, round(float(abs(v[32, 32])), 3)
    ((64, 64), 1.0)
    """
    wavelength, pitch = grid.wave(wavelength, pitch)
    m = validate.rotation("rotation", rotation)
    padding = grid.padding_factor(padding)
    rt, src, from_host = as_device(field)
    out_shape = validate.shape2d("out_shape", src.shape if out_shape is None else out_shape)
    out_pitch = pitch if out_pitch is None else validate.pitch("out_pitch", out_pitch)
    angle, reach = math.acos(np.clip(m[2, 2], -1, 1)), tilt_reach(wavelength, pitch, out_pitch)
    if angle >= reach:  # the result would be zero whatever the field: say so instead
        raise InputError(
            f"rotation tilts the target plane by {math.degrees(angle):.1f}°; "
            f"light sampled at pitch {pitch:.3g} m and out_pitch {out_pitch:.3g} m "
            f"(λ = {wavelength:.3g} m) reaches planes tilted by less than "
            f"{math.degrees(reach):.1f}°"
        )
    hs, ws = grid.padded_shape(src.shape, padding)
    ht, wt = grid.padded_shape(
        out_shape, padding if out_padding is None else grid.padding_factor(out_padding)
    )
    spectrum = rt.scratch("tilt-source", (hs, ws))
    (r0, c0), (t0, u0) = _corner(src.shape, (hs, ws)), _corner(out_shape, (ht, wt))
    lies = ((r0, r0 + src.shape[0]),), ((c0, c0 + src.shape[1]),)  # where the source is
    rt.fft.clear(spectrum, lies)
    place(rt, spectrum, src, r0, c0)
    centre = ((r0 + (src.shape[0] - 1) / 2) / hs, (c0 + (src.shape[1] - 1) / 2) / ws)
    multiply(rt, spectrum, cached_array(rt, "deapodize", _deapodization, (hs, ws), centre))
    rt.fft.forward(spectrum, nonzero=lies)
    multiply(rt, spectrum, cached_array(rt, "centring", _centring, (hs, ws), centre))
    target = empty(rt, (ht, wt))
    options = rt.real_options + (f"-DTAPS={TAPS}", f"-DES_TABLE={ES_TABLE}")
    ROTATE_SPECTRUM.launch(
        rt,
        by_rows((ht, wt)),
        options=options,
        dst=target,
        A=spectrum,
        hs=hs,
        ws=ws,
        ht=ht,
        wt=wt,
        dft_y=1 / (ht * out_pitch),
        dft_x=1 / (wt * out_pitch),
        dfs_y=1 / (hs * pitch),
        dfs_x=1 / (ws * pitch),
        inv_l2=1 / wavelength**2,
        **dict(zip(_ROTATION, m.ravel())),
        ct_y=(t0 + (out_shape[0] - 1) / 2) / ht,
        ct_x=(u0 + (out_shape[1] - 1) / 2) / wt,
        scale=pitch**2 / (out_pitch**2 * ht * wt),
        es=cached_array(rt, "es-table", es_table),
    )
    rt.fft.backward(target, read=((u0, u0 + out_shape[1]),))
    return like_input(window(rt, target, out_shape, t0, u0), from_host)


def tilt_reach(wavelength, pitch, out_pitch) -> float:
    """The largest tilt [rad] that light can bridge between a grid at ``pitch`` and one at
    ``out_pitch`` (``wavelength`` [m]): each holds the directions within asin(λ/2p) of its
    normal, and the two cones must overlap."""
    return sum(math.asin(min(1.0, wavelength / (2 * q))) for q in (pitch, out_pitch))


def es_kernel(t, taps=TAPS, beta=ES_BETA) -> np.ndarray:
    """The spectrum's interpolation kernel at ``t`` [bins]: exp(β(√(1 - (2t/taps)²) - 1)),
    β = ``beta``·taps (2.30 for 2x oversampling, 2.03 for 1.5x)."""
    s = 1 - (2 * np.asarray(t, np.float64) / taps) ** 2
    return np.where(s > 0, np.exp(beta * taps * (np.sqrt(np.clip(s, 0, None)) - 1)), 0.0)


def es_transform(xi, taps=TAPS, beta=ES_BETA) -> np.ndarray:
    """The kernel's Fourier transform at ``xi`` = position over the padded size: the factor
    interpolation lays on the field."""
    t, dt = np.linspace(-taps / 2, taps / 2, 64 * taps + 1, retstep=True)
    return (es_kernel(t, taps, beta) * np.cos(2 * np.pi * np.multiply.outer(xi, t))).sum(-1) * dt


def cached_array(rt, name, make, *args):
    """``make(*args)`` as a device array, made once per runtime and cached under ``name``."""
    return cached(rt, (name, *args), lambda: (make(*args), None))[0]


def es_profile(rt, n: int, taps=TAPS, *, inverse=False):
    """:func:`es_transform` at the n signed indices of a grid oversampled twice (index/(2n)),
    or its inverse: a device float32 array (n,) in FFT order, made once per runtime."""

    def make():
        t = es_transform(grid.signed_indices(n) / (2 * n), taps)
        return rt.to_device(1 / t if inverse else t, np.float32), None

    return cached(rt, ("es-profile", n, taps, inverse), make)[0]


def es_table(taps=TAPS, beta=ES_BETA):
    """(value, slope) per table interval, packed as complex: what ``es_weight`` reads."""
    phi = es_kernel(np.linspace(-taps / 2, taps / 2, ES_TABLE + 1), taps, beta)
    return phi[:-1] + 1j * np.diff(phi)


def _deapodization(padded, centre):
    """1 / es_transform about the field's centre (fractions of the padded size), per axis."""
    w = [1 / es_transform(np.arange(n) / n - c) for n, c in zip(padded, centre)]
    return np.outer(*w)


def _centring(padded, centre):
    """exp(i2π·bin·centre) in FFT order: the spectrum of the field moved to the origin, smooth
    between bins (the field's own spectrum turns by 2π·centre per bin)."""
    ramps = [np.exp(2j * np.pi * np.fft.fftfreq(n, 1 / n) * c) for n, c in zip(padded, centre)]
    return np.outer(*ramps)


def _corner(shape, padded):
    """Where a field of ``shape`` sits, centred, in the ``padded`` grid: (row, col)."""
    return (padded[0] - shape[0]) // 2, (padded[1] - shape[1]) // 2


def propagate_to_plane(
    field, *, wavelength, pitch, rotation, position, padding=2, out_shape=None, out_pitch=None
):
    """Propagate a field to a placed plane: tilt first, then propagate with offset.

    Parameters
    ----------
    field : (H, W) complex array, NumPy or OpenCL device array
        Source field on z = 0, as for :func:`tilt`.
    wavelength : float
        Wavelength λ [m].
    pitch : float
        Source sample spacing [m].
    rotation : (3, 3) array
        Orientation of the target plane (columns: its axes in source coordinates).
    position : (float, float, float)
        Centre of the target plane [m] in source coordinates.
    padding, out_shape, out_pitch
        As for :func:`tilt` (``out_pitch`` [m]).

    Returns
    -------
    ndarray or pyopencl.array.Array
        Complex64 field on the target grid, like the input.

    Raises
    ------
    InputError
        Where an argument is out of range, as for :func:`tilt` and
        :func:`~holo_core.propagation.angular_spectrum`.

    Notes
    -----
    The paper's discrete propagation pipeline (Sect. IV-D): the rotation of Eq. 11, then the
    propagation to a parallel plane with offset of Eq. 14-15.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import propagate_to_plane
    >>> v = propagate_to_plane(np.ones((64, 64), complex), wavelength=633e-9, pitch=4e-6,
    ...                        rotation=np.eye(3), position=(0.0, 0.0, 1e-3))
    >>> v.shape, round(float(abs(v[32, 32])), 3)
    ((64, 64), 1.0)
    """
    m = validate.rotation("rotation", rotation)
    p = validate.vector("position", position, 3, "m")
    x0, y0, z = m.T @ p
    rt, tilted, from_host = as_device(field)  # both stages on the device, one upload
    if out_shape is not None or out_pitch is not None or not np.allclose(m, np.eye(3), atol=1e-12):
        # also without a tilt: the interpolated spectrum places a small field in a large grid
        # without the wrap-around of resampling on the small grid
        tilted = tilt(
            tilted,
            wavelength=wavelength,
            pitch=pitch,
            rotation=m,
            padding=padding,
            out_shape=out_shape,
            out_pitch=out_pitch,
        )
        pitch = out_pitch or pitch
    if z != 0 or x0 != 0 or y0 != 0:
        tilted = angular_spectrum(
            tilted, wavelength=wavelength, pitch=pitch, distance=z, offset=(x0, y0), padding=padding
        )
    return like_input(tilted, from_host)
