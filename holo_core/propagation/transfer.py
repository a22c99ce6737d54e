"""Transfer functions made on the device (``transfer.cl``): a new distance costs one
kernel pass over the padded grid, not a float64 grid built on the host and uploaded.

Where the device has float64 the phase is formed and reduced in double. Where it does not, the
chirp g = 2π·f²/(1/λ + fz) is made once per (grid, wavelength, pitch) in float64 on the host
and kept as two floats (hi + lo), and each distance's z·g is formed exactly to float32 by an
error-free product and a three-part 2π (``split``). Both agree with the float64
:func:`~holo_core.propagation.angular_spectrum.transfer_function` to float32 precision
(``tests/core/propagation/test_transfer.py``).
"""

from __future__ import annotations

import math

import numpy as np

from ..opencl import associated
from ..opencl.arrays import cached, empty
from . import grid

PROGRAM = associated(__file__)


def asm_transfer(rt, shape, *, wavelength, pitch, distance, offset, band_limit, edge,
                 split=None):
    """The band-limited angular spectrum's transfer function on the padded ``shape`` (FFT
    order), times 1/(H·W), as a complex64 device array. ``pitch`` (x, y) [m], ``wavelength``,
    ``distance``, ``offset`` [m]; ``edge`` the band's roll-off fraction; ``split`` forces the
    float32 route (default: where the device lacks float64)."""
    h, w = shape
    px, py = pitch
    x0, y0 = offset
    carrier = math.remainder(2 * math.pi * distance / wavelength, 2 * math.pi)
    out = empty(rt, shape)
    half = (h * py / 2, w * px / 2)
    if not (rt.has_fp64 if split is None else not split):
        return _split(rt, out, shape, wavelength, pitch, distance, offset, band_limit, edge,
                      carrier, half)
    rt.kernel(PROGRAM, "asm_transfer", rt.real_options)(
        rt.queue, (h, w), None, out.data, np.float64(1 / (h * py)), np.float64(1 / (w * px)),
        np.float64(1 / wavelength), np.float64(distance), np.float64(carrier),
        np.float64(x0), np.float64(y0), np.float64(half[0]), np.float64(half[1]),
        np.int32(bool(band_limit)), np.float32(edge), np.float32(1 / (h * w)))
    return out


def fresnel_transfer(rt, shape, *, wavelength, pitch, distance, offset):
    """The Fresnel transfer function (see :func:`~holo_core.propagation.fresnel.fresnel`) on
    the device, times 1/(H·W); None where the device lacks float64 (the host makes it)."""
    if not rt.has_fp64:
        return None
    h, w = shape
    px, py = pitch
    carrier = math.remainder(2 * math.pi * distance / wavelength, 2 * math.pi)
    out = empty(rt, shape)
    rt.kernel(PROGRAM, "fresnel_transfer", rt.real_options)(
        rt.queue, (h, w), None, out.data, np.float64(1 / (h * py)), np.float64(1 / (w * px)),
        np.float64(wavelength), np.float64(distance), np.float64(carrier),
        np.float64(offset[0]), np.float64(offset[1]), np.float64(h * py / 2),
        np.float64(w * px / 2), np.float32(1 / (h * w)))
    return out


def chirp_split(shape, wavelength, pitch) -> np.ndarray:
    """g = 2π·f²/(1/λ + fz) [rad/m] per frequency as complex64 (hi + i·lo, hi + lo = g to
    float64's precision); hi = -1 where the wave is evanescent."""
    px, py = pitch
    fy, fx = grid.freqs(shape[0], py)[:, None], grid.freqs(shape[1], px)[None, :]
    f2 = fx * fx + fy * fy
    fz2 = 1 / wavelength**2 - f2
    keep = fz2 > 0
    g = 2 * np.pi * f2 / (1 / wavelength + np.sqrt(np.where(keep, fz2, 1.0)))
    hi = g.astype(np.float32)
    lo = (g - hi).astype(np.float32)
    return np.where(keep, hi, -1) + 1j * np.where(keep, lo, 0)


def _split(rt, out, shape, wavelength, pitch, distance, offset, band_limit, edge, carrier,
           half):
    h, w = shape
    px, py = pitch
    x0, y0 = offset
    ghl, _ = cached(rt, ("asm-chirp", shape, wavelength, pitch),
                    lambda: (chirp_split(shape, wavelength, pitch), []))
    ry, _ = cached(rt, ("ramp", h, py, y0), lambda: (_ramp(h, py, y0), []))
    rx, _ = cached(rt, ("ramp", w, px, x0), lambda: (_ramp(w, px, x0), []))
    z_hi = np.float32(distance)
    z_lo = np.float32(distance - float(z_hi))
    rt.kernel(PROGRAM, "asm_transfer_split")(
        rt.queue, (h, w), None, out.data, ghl.data, ry.data, rx.data, z_hi, z_lo,
        np.float32(carrier), np.float32(1 / (h * py)), np.float32(1 / (w * px)),
        np.float32(1 / wavelength), np.float32(x0), np.float32(y0), np.float32(half[0]),
        np.float32(half[1]), np.int32(bool(band_limit)), np.float32(edge),
        np.float32(1 / (h * w)))
    return out


def _ramp(n, pitch, x0) -> np.ndarray:
    """exp(i2π·f·x0) over the FFT-ordered frequencies of ``n`` samples, phase reduced in
    float64."""
    return np.exp(2j * np.pi * np.remainder(grid.freqs(n, pitch) * x0, 1.0))
