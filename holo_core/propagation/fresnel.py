"""Paraxial propagation, for comparison and for the far field.

``fresnel`` is the Fresnel transfer function exp(ikz)·exp(-iπλz(fx² + fy²)) on the same padded
grid as the angular spectrum (band-limited the same way); ``fraunhofer`` is the far field as one
centred Fourier transform, on the grid of pitch λz/(W·pitch) it implies.
"""

from __future__ import annotations

import math

import numpy as np

from .. import validate
from ..opencl import as_device, is_device_array, like_input
from ..opencl.arrays import cached, copy
from . import grid
from .convolution import convolution_setup, convolve, multiply, symmetric
from .scaled import scaled
from .transfer import fresnel_transfer


def fresnel(field, *, wavelength, pitch, distance, offset=(0.0, 0.0), padding=2,
            out_pitch=None, out_shape=None):
    """The paraxial (Fresnel) field on the parallel plane at ``distance``.

    Same parameters and result as :func:`~holo_core.propagation.angular_spectrum` (``wavelength``,
    ``pitch`` (a number or (x, y)), ``distance``, ``offset``, ``out_pitch`` in metres,
    ``out_shape``); accurate only where the paraxial approximation holds.
    """
    if out_pitch is not None or out_shape is not None:
        return scaled("fresnel", field, wavelength=wavelength, pitch=pitch, distance=distance,
                      offset=offset, padding=padding, out_pitch=out_pitch, out_shape=out_shape)
    s = convolution_setup(field, wavelength, pitch, distance, offset, padding)
    wavelength, pitch, z, (x0, y0), padding = s.wavelength, s.pitch, s.z, s.offset, s.padding
    rt, dev, from_host, shape = s.rt, s.dev, s.from_host, s.shape

    quadrant = symmetric(rt, (x0, y0)) and rt.has_fp64

    def make():
        tf = fresnel_transfer_host(shape, wavelength, pitch, z, (x0, y0))
        return tf / (shape[0] * shape[1]), []

    def made():  # on the device where it has float64 (transfer.py), else on the host
        tf = fresnel_transfer(rt, shape, wavelength=wavelength, pitch=pitch, distance=z,
                              offset=(x0, y0), quadrant=quadrant)
        return make() if tf is None else (tf, [])

    tf, _ = cached(rt, ("fresnel", shape, wavelength, pitch, z, x0, y0, quadrant), made)
    return like_input(convolve(rt, dev, tf, shape if quadrant else None), from_host)


def fresnel_transfer_host(shape, wavelength, pitch, distance, offset) -> np.ndarray:
    """The Fresnel transfer function exp(ikz)·exp(-iπλz(fx² + fy²))·exp(i2π(fx·x0 + fy·y0)) on
    the padded ``shape`` (FFT order), complex128, made in float64: the rays x0 - λz·f kept
    inside half the window. ``pitch`` (x, y), ``wavelength``, ``distance``, ``offset`` [m]."""
    (px, py), (x0, y0), z = pitch, offset, distance
    fy, fx = grid.freqs(shape[0], py)[:, None], grid.freqs(shape[1], px)[None, :]
    carrier = math.remainder(2 * math.pi * z / wavelength, 2 * math.pi)
    phase = carrier - np.pi * wavelength * z * (fx**2 + fy**2) + 2 * np.pi * (fx * x0 + fy * y0)
    keep = (np.abs(x0 - wavelength * z * fx) <= shape[1] * px / 2) \
        & (np.abs(y0 - wavelength * z * fy) <= shape[0] * py / 2)
    return np.where(keep, np.exp(1j * phase), 0)


def centred_ramp(shape) -> np.ndarray:
    """The centred DFT's ramp: exp(-i2π(j-c)(n-c)/N) = ramp(n)·ramp(j)·exp(-i2πc²/N) with
    c = (N-1)/2, ramp(n) = exp(iπ(N-1)n/N), as the outer product over ``shape`` (rows, cols)."""
    ry, rx = [np.exp(1j * np.pi * (n - 1) * np.arange(n) / n) for n in shape]
    return ry[:, None] * rx[None, :]


def far_factor(shape, wavelength, pitch, z) -> np.ndarray:
    """What multiplies the centred DFT of a ``shape`` field of ``pitch`` [m] to give its far
    field at distance ``z`` [m] for ``wavelength`` [m]: the output ramp, the quadratic phase on
    the output grid (pitch λz/(N·pitch)) and the scale pitch²/(iλz)."""
    h, w = shape
    yo = grid.coords(h, wavelength * z / (h * pitch))[:, None]
    xo = grid.coords(w, wavelength * z / (w * pitch))[None, :]
    k = 2 * np.pi / wavelength
    phase = math.remainder(k * z, 2 * math.pi) + k * (xo**2 + yo**2) / (2 * z) \
        - np.pi * ((h - 1) ** 2 / (2 * h) + (w - 1) ** 2 / (2 * w))
    return centred_ramp(shape) * np.exp(1j * phase) * pitch**2 / (1j * wavelength * z)


def fraunhofer(field, *, wavelength, pitch, distance):
    """The far field at ``distance`` > 0 and the pitch of its grid.

    U(x', y') = exp(ikz)·exp(ik(x'² + y'²)/(2z))/(iλz) · pitch² · Σ U(x, y)·exp(-i2π(x x' + y y')/(λz))
    on the centred grid of the input's shape with pitch λz/(W·pitch) (per axis: λz/(H·pitch)
    for rows). ``wavelength``, ``pitch``, ``distance`` in metres. Warns when ``distance`` is
    short of the Fraunhofer distance 2·D²/λ of the field's non-zero extent D.

    Returns
    -------
    (field, (row pitch, column pitch)): complex64 like the input, pitches in metres.
    """
    wavelength, pitch = grid.wave(wavelength, pitch)
    z = validate.positive("distance", validate.within("distance", distance, validate.MAX_LENGTH),
                          "m")
    if not is_device_array(field):
        support = grid.support(validate.host_field("field", field))[0].shape
        extent = math.hypot(*support) * pitch
        if z < 2 * extent**2 / wavelength:
            validate.warn_sampling(
                f"fraunhofer: distance {z:.4g} m is short of the far field of this field "
                f"(2·D²/λ = {2 * extent**2 / wavelength:.4g} m); use fresnel or angular_spectrum")
    rt, dev, from_host = as_device(field)
    h, w = dev.shape
    out_pitch = (wavelength * z / (h * pitch), wavelength * z / (w * pitch))

    pre, _ = cached(rt, ("centred-dft", (h, w)), lambda: (centred_ramp((h, w)), []))
    post, _ = cached(rt, ("fraunhofer", (h, w), wavelength, pitch, z),
                     lambda: (far_factor((h, w), wavelength, pitch, z), []))
    out = copy(dev)
    multiply(rt, out, pre)
    rt.fft.forward(out)
    multiply(rt, out, post)
    return like_input(out, from_host), out_pitch
