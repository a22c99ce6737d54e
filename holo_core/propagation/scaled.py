"""Propagation onto an output grid of another pitch and size (``out_pitch``, ``out_shape`` of
the angular spectrum and Fresnel), by a chirp-z transform (Rabiner, Schafer & Rader 1969;
Bluestein's algorithm).

The transfer-function propagation on a zero-padded grid of P samples per axis yields, before
its inverse FFT, a spectrum S_k; the propagated field is the trigonometric polynomial
u(x) = (1/P)·Σ_k S_k·exp(i2π·k·i(x)/P), i(x) the fractional index of x on the padded grid.
Evaluated on the output grid x_j = x_0 + j·out_pitch, the sum's k·j term is a chirp:
k·j = (k² + j² − (j − k)²)/2, so each axis is one convolution by FFT, O(P log P), at any
pitch and size. The padded grid covers the source and the output window (``padding`` times
the larger); an output pitch coarser than the input's first drops the frequencies above its
Nyquist, which it could not hold (it would alias them). The phases are formed in float64 and
the sums are on the host (numpy.fft, complex128); the result is complex64 like the input,
back on the device where the input was.
"""

from __future__ import annotations

import math

import numpy as np

from .. import memory, validate
from ..opencl import is_device_array, to_device
from . import grid

MAX_SAMPLES = 2**26  # padded samples (1 GiB of complex128), at most


def scaled(
    field, *, transfer, name, wavelength, pitch, distance, offset, padding, out_pitch, out_shape
):
    """The propagation of ``field`` (H, W) by the transfer function ``transfer(shape,
    wavelength, pitch (x, y), distance, offset) -> complex128`` (FFT order) to ``distance``
    [m], centred at ``offset`` (x0, y0) [m], on ``out_shape`` (rows, cols) samples of
    ``out_pitch`` [m] (a number or (x, y); default ``pitch``; the default shape keeps the
    input's window); ``pitch`` [m] (a number or (x, y)); ``padding`` >= 1; ``name`` the
    propagation's, for messages. Every setting is checked here."""
    wavelength, (px, py) = grid.wave_pair(wavelength, pitch)
    distance = validate.within("distance", distance, validate.MAX_LENGTH)
    x0, y0 = validate.pair("offset", offset, "m", validate.MAX_LENGTH)
    padding = grid.padding_factor(padding)
    opx, opy = (px, py) if out_pitch is None else grid.pitch_pair(out_pitch, "out_pitch")
    on_device = is_device_array(field)
    u = field.get() if on_device else field
    u = validate.host_field("field", u).astype(np.complex128)
    h, w = u.shape
    oh, ow = (
        (max(1, round(h * py / opy)), max(1, round(w * px / opx)))
        if out_shape is None
        else validate.shape2d("out_shape", out_shape)
    )
    memory.check_host(
        f"{name} onto {oh}x{ow} samples", 16.0 * 6 * max(h * w, oh * ow) * padding * padding
    )
    extent = [
        max(n * p, 2 * abs(o) + m * q)
        for n, p, o, m, q in ((h, py, y0, oh, opy), (w, px, x0, ow, opx))
    ]
    shape = tuple(
        grid.next_fast_len(math.ceil(padding * e / p - 1e-9)) for e, p in zip(extent, (py, px))
    )
    if math.prod(shape) > MAX_SAMPLES:
        raise validate.InputError(
            f"out_shape and offset need a padded grid of {shape[0]}x"
            f"{shape[1]} samples at the input pitch; at most "
            f"{MAX_SAMPLES} (bring the window nearer the source)"
        )
    pitch, offset = (px, py), (x0, y0)
    r0, c0 = (shape[0] - h) // 2, (shape[1] - w) // 2
    big = np.zeros(shape, np.complex128)
    big[r0 : r0 + h, c0 : c0 + w] = u
    spectrum = np.fft.fft2(big) * transfer(shape, wavelength, pitch, distance, offset)
    # each output axis: fractional indices a + j·b on the padded grid (its centre the offset)
    rows = _czt(
        spectrum,
        0,
        r0 + (h - 1) / 2 - (oh - 1) / 2 * opy / py,
        opy / py,
        oh,
        1 / (2 * opy) if opy > py else None,
        py,
    )
    out = _czt(
        rows,
        1,
        c0 + (w - 1) / 2 - (ow - 1) / 2 * opx / px,
        opx / px,
        ow,
        1 / (2 * opx) if opx > px else None,
        px,
    )
    out = (out / (shape[0] * shape[1])).astype(np.complex64)
    return to_device(out) if on_device else out


def _czt(spectrum, axis, a, b, count, cut, pitch) -> np.ndarray:
    """Σ_k S_k·exp(i2π·k·(a + j·b)/P) for j < ``count`` along ``axis`` (k the signed DFT
    index of the P samples), frequencies above ``cut`` [1/m] dropped first."""
    s = np.moveaxis(spectrum, axis, -1)
    p = s.shape[-1]
    k0 = -(p // 2)
    s = np.fft.fftshift(s, axes=-1)  # k = k0 + m, m = 0 .. P-1
    m = np.arange(p)
    if cut is not None:
        s = s * (np.abs((k0 + m) / (p * pitch)) <= cut)
    j = np.arange(count)
    turn = lambda t: np.exp(2j * np.pi * np.remainder(t, 1.0))  # exp(i2π·t), t reduced
    beta = b / p  # exp(i2π·β·m·j), m·j = (m² + j² − (j − m)²)/2
    x = s * turn(m * a / p + beta * m * m / 2)
    n = np.arange(-(p - 1), count)
    kernel = turn(-beta * n * n / 2)
    size = grid.next_fast_len(p + count - 1)
    conv = np.fft.ifft(np.fft.fft(x, size) * np.fft.fft(kernel, size))[..., p - 1 : p - 1 + count]
    out = conv * turn(beta * j * j / 2 + k0 * (a + b * j) / p)
    return np.moveaxis(out, -1, axis)
