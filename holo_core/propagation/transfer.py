"""Transfer functions: the float64 ones made on the host (``transfer_function``, the angular
spectrum's reference and the scaled propagation's; ``fresnel_transfer_host``) beside those
made on the device (``transfer.cl``), where a new distance costs one kernel pass over the
padded grid, not a float64 grid built on the host and uploaded.

The angular spectrum's chirp g = 2π·f²/(1/λ + fz) and 1/fz are made once per (grid,
wavelength, pitch) in float64 on the host, for the grid's first quadrant only (both depend on
fx² and fy²), g kept as two floats (hi + lo); each distance's z·g is then formed exactly to
float32 by an error-free product and a three-part 2π, and the band's rays z·fx/fz by one
multiply: a new distance costs one pass over the grid with no square root or division (a
focus sweep's step, ``bench/sweep.py``). The direct route (``split=False``, float64 devices)
forms and reduces the phase in double. Both agree with the float64
:func:`~holo_core.propagation.angular_spectrum.transfer_function` to float32 precision
(``tests/core/propagation/test_transfer.py``).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy import float32, float64, int32

from ..opencl import associated
from ..opencl.arrays import by_rows, cached, empty
from ..opencl.kernel import BUFFER, kernel
from ..validate import InputError
from . import grid

PROGRAM = associated(__file__)
# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
ASM_TRANSFER = kernel(PROGRAM, "asm_transfer", t=BUFFER, dfy=float64, dfx=float64,
                      inv_l=float64, z=float64, c=float64, x0=float64, y0=float64,
                      half_y=float64, half_x=float64, band=int32, edge=float32, scale=float32)
FRESNEL_TRANSFER = kernel(PROGRAM, "fresnel_transfer", t=BUFFER, quadrant=int32, h=int32,
                          w=int32, gw=int32, dfy=float64, dfx=float64, lam=float64,
                          z=float64, c=float64, x0=float64, y0=float64, half_y=float64,
                          half_x=float64, scale=float32)
ASM_TRANSFER_CHIRP = kernel(
    PROGRAM, "asm_transfer_chirp", t=BUFFER, g=BUFFER, inv_fz=BUFFER, qw=int32, ry=BUFFER,
    rx=BUFFER, shifted=int32, quadrant=int32, h=int32, w=int32, gw=int32, z_hi=float32,
    z_lo=float32, c=float32, dfy=float32, dfx=float32, x0=float32, y0=float32,
    half_y=float32, half_x=float32, band=int32, edge=float32, scale=float32)
# fmt: on
BAND_EDGE = 0.2  # fraction of the band-limited ray range given to the cosine roll-off


def quadrant_shape(shape) -> tuple[int, int]:
    """The first quadrant of an FFT-order grid: the samples at signed indices >= 0."""
    return shape[0] // 2 + 1, shape[1] // 2 + 1


def asm_transfer(
    rt,
    shape,
    *,
    wavelength,
    pitch,
    distance,
    offset,
    band_limit,
    edge,
    split=None,
    quadrant=False,
    out=None,
):
    """The band-limited angular spectrum's transfer function on the padded ``shape`` (FFT
    order), times 1/(H·W), as a complex64 device array. ``pitch`` (x, y) [m], ``wavelength``,
    ``distance``, ``offset`` [m]; ``edge`` the band's roll-off fraction; ``split=False`` takes
    the direct float64 route (float64 devices only), else the chirp table's; ``quadrant``
    (offset (0, 0) only: the function is even in fx and fy) makes the first quadrant only
    (:func:`quadrant_shape`); ``out``: the device array to fill (of that shape), else a new
    one."""
    h, w = shape
    px, py = pitch
    x0, y0 = offset
    carrier = math.remainder(2 * math.pi * distance / wavelength, 2 * math.pi)
    half = (h * py / 2, w * px / 2)
    if split is not False:
        return _from_chirp(
            rt,
            shape,
            wavelength,
            pitch,
            distance,
            offset,
            band_limit,
            edge,
            carrier,
            half,
            quadrant,
            out,
        )
    out = _output(rt, out, shape)
    ASM_TRANSFER.launch(
        rt,
        (w, h),
        options=rt.real_options,
        t=out,
        dfy=1 / (h * py),
        dfx=1 / (w * px),
        inv_l=1 / wavelength,
        z=distance,
        c=carrier,
        x0=x0,
        y0=y0,
        half_y=half[0],
        half_x=half[1],
        band=bool(band_limit),
        edge=edge,
        scale=1 / (h * w),
    )
    return out


def fresnel_transfer(rt, shape, *, wavelength, pitch, distance, offset, quadrant=False, out=None):
    """The Fresnel transfer function (see :func:`~holo_core.propagation.fresnel.fresnel`) on
    the device, times 1/(H·W) (its first quadrant only with ``quadrant``, offset (0, 0)), into
    ``out`` if given; None where the device lacks float64 (the host makes it)."""
    if not rt.has_fp64:
        return None
    h, w = shape
    px, py = pitch
    carrier = math.remainder(2 * math.pi * distance / wavelength, 2 * math.pi)
    made = quadrant_shape(shape) if quadrant else shape
    out = _output(rt, out, made)
    FRESNEL_TRANSFER.launch(
        rt,
        by_rows(made),
        options=rt.real_options,
        t=out,
        quadrant=bool(quadrant),
        h=h,
        w=w,
        gw=made[1],
        dfy=1 / (h * py),
        dfx=1 / (w * px),
        lam=wavelength,
        z=distance,
        c=carrier,
        x0=offset[0],
        y0=offset[1],
        half_y=h * py / 2,
        half_x=w * px / 2,
        scale=1 / (h * w),
    )
    return out


def chirp_table(shape, wavelength, pitch) -> tuple[np.ndarray, np.ndarray]:
    """(g_hi + i·g_lo as complex64, 1/fz as float32), each (h//2 + 1, w//2 + 1), over the grid's
    first quadrant (row, column: the |signed index|): g = 2π·f²/(1/λ + fz) [rad/m] = g_hi +
    g_lo to float64's precision, 1/fz [m]; 1/fz = -1 where the wave is evanescent."""
    (h, w), (px, py) = shape, pitch
    fy = np.arange(h // 2 + 1)[:, None] * (1 / (h * py))
    fx = np.arange(w // 2 + 1)[None, :] * (1 / (w * px))
    f2 = fx * fx + fy * fy
    fz2 = 1 / wavelength**2 - f2
    keep = fz2 > 0
    fz = np.sqrt(np.where(keep, fz2, 1.0))
    g = 2 * np.pi * f2 / (1 / wavelength + fz)
    hi = g.astype(np.float32)
    return (hi + 1j * (g - hi)).astype(np.complex64), np.where(keep, 1 / fz, -1).astype(np.float32)


_chirp_table = functools.lru_cache(maxsize=1)(chirp_table)  # its two parts are cached apart


def _from_chirp(
    rt, shape, wavelength, pitch, distance, offset, band_limit, edge, carrier, half, quadrant, out
):
    h, w = shape
    made = quadrant_shape(shape) if quadrant else shape
    out = _output(rt, out, made)
    px, py = pitch
    x0, y0 = offset
    table = [
        cached(
            rt,
            ("asm-chirp", part, shape, wavelength, pitch),
            lambda part=part: (rt.to_device(_chirp_table(shape, wavelength, pitch)[part]), []),
        )[0]
        for part in (0, 1)
    ]
    ry, _ = cached(rt, ("ramp", h, py, y0), lambda: (_ramp(h, py, y0), []))
    rx, _ = cached(rt, ("ramp", w, px, x0), lambda: (_ramp(w, px, x0), []))
    z_hi = np.float32(distance)
    z_lo = np.float32(distance - float(z_hi))
    ASM_TRANSFER_CHIRP.launch(
        rt,
        by_rows(made),
        t=out,
        g=table[0],
        inv_fz=table[1],
        qw=w // 2 + 1,
        ry=ry,
        rx=rx,
        shifted=x0 != 0 or y0 != 0,
        quadrant=bool(quadrant),
        h=h,
        w=w,
        gw=made[1],
        z_hi=z_hi,
        z_lo=z_lo,
        c=carrier,
        dfy=1 / (h * py),
        dfx=1 / (w * px),
        x0=x0,
        y0=y0,
        half_y=half[0],
        half_x=half[1],
        band=bool(band_limit),
        edge=edge,
        scale=1 / (h * w),
    )
    return out


def _output(rt, out, shape):
    """``out`` checked to be a complex64 device array of ``shape`` (the kernels write all of
    it), else a new one."""
    if out is None:
        return empty(rt, shape)
    if tuple(out.shape) != tuple(shape) or out.dtype != np.complex64:
        raise InputError(
            f"out must be complex64 of {tuple(shape)}; got {out.dtype} of {tuple(out.shape)}"
        )
    return out


def _ramp(n, pitch, x0) -> np.ndarray:
    """exp(i2π·f·x0) over the FFT-ordered frequencies of ``n`` samples, phase reduced in
    float64."""
    return np.exp(2j * np.pi * np.remainder(grid.freqs(n, pitch) * x0, 1.0))


# --- on the host, in float64 ------------------------------------------------------------------


def transfer_function(shape, *, wavelength, pitch, distance, offset=(0.0, 0.0), band_limit=True):
    """The angular spectrum's transfer function on a grid, float64 on the host.

    Parameters
    ----------
    shape : (int, int)
        The (padded) grid (H, W), in FFT order.
    wavelength : float
        λ [m].
    pitch : float or (float, float)
        Sample spacing [m], or (x, y).
    distance : float
        Propagation distance z [m].
    offset : (float, float)
        The output plane's lateral offset (x0, y0) [m].
    band_limit : bool
        Weight each frequency by the band limit (1 where its ray lands well inside half the
        padded window, rolling off to 0 at its edge); False: the unlimited function.

    Returns
    -------
    (H, W) complex128 ndarray
        exp(i2πz·fz)·exp(i2π(fx·x0 + fy·y0)), zero for evanescent frequencies (f >= 1/λ).

    Notes
    -----
    Eq. 12-13. The phase is formed as k·z (reduced mod 2π) plus −2πz·f²/(1/λ + fz), which
    keeps float64 precision for large k·z. It is the float64 reference of the transfer
    function :func:`holo_core.angular_spectrum` computes on the device, and the one it applies
    where ``out_pitch`` or ``out_shape`` is given.

    Examples
    --------
    At zero frequency the phase is k·z, reduced mod 2π:

    >>> import numpy as np
    >>> from holo_core.propagation import transfer_function
    >>> H = transfer_function((64, 64), wavelength=633e-9, pitch=2e-6, distance=1e-3)
    >>> H.dtype, round(float(np.angle(H[0, 0])), 6)
    (dtype('complex128'), -1.389646)
    >>> round(float(np.angle(np.exp(2j * np.pi * 1e-3 / 633e-9))), 6)
    -1.389646
    """
    px, py = grid.pitch_pair(pitch)
    fy, fx = grid.freqs(shape[0], py)[:, None], grid.freqs(shape[1], px)[None, :]
    x0, y0 = offset
    f2 = fx * fx + fy * fy
    fz2 = 1.0 / wavelength**2 - f2
    keep = fz2 > 0
    fz = np.sqrt(np.where(keep, fz2, 1.0))
    carrier = math.remainder(2 * math.pi * distance / wavelength, 2 * math.pi)
    phase = (
        carrier
        - 2 * np.pi * distance * f2 / (1.0 / wavelength + fz)
        + 2 * np.pi * (fx * x0 + fy * y0)
    )
    if band_limit:
        keep = keep * band_mask(shape, pitch, distance, offset, fx, fy, fz)
    return keep * np.exp(1j * phase)


def band_mask(shape, pitch, distance, offset, fx, fy, fz) -> np.ndarray:
    """Weights in [0, 1]: 1 where the ray x0 - z·fx/fz lands well within half the padded
    window, rolling off to 0 at its edge (per axis, multiplied)."""
    weight = 1.0
    px, py = grid.pitch_pair(pitch)
    for n, p, o, f in ((shape[1], px, offset[0], fx), (shape[0], py, offset[1], fy)):
        u = np.abs(o - distance * f / fz) / (n * p / 2)  # 1 at the edge of the band
        t = np.clip((u - (1 - BAND_EDGE)) / BAND_EDGE, 0, 1)
        weight = weight * np.where(u <= 1, np.cos(np.pi / 2 * t) ** 2, 0)
    return weight


def fresnel_transfer_host(shape, wavelength, pitch, distance, offset) -> np.ndarray:
    """The Fresnel transfer function exp(ikz)·exp(-iπλz(fx² + fy²))·exp(i2π(fx·x0 + fy·y0)) on
    the padded ``shape`` (FFT order), complex128, made in float64: the rays x0 - λz·f kept
    inside half the window. ``pitch`` (x, y), ``wavelength``, ``distance``, ``offset`` [m]."""
    (px, py), (x0, y0), z = pitch, offset, distance
    fy, fx = grid.freqs(shape[0], py)[:, None], grid.freqs(shape[1], px)[None, :]
    carrier = math.remainder(2 * math.pi * z / wavelength, 2 * math.pi)
    phase = carrier - np.pi * wavelength * z * (fx**2 + fy**2) + 2 * np.pi * (fx * x0 + fy * y0)
    keep = (np.abs(x0 - wavelength * z * fx) <= shape[1] * px / 2) & (
        np.abs(y0 - wavelength * z * fy) <= shape[0] * py / 2
    )
    return np.where(keep, np.exp(1j * phase), 0)
