"""Paraxial propagation, for comparison and for the far field, each beside its adjoint.

``fresnel`` is the Fresnel transfer function exp(ikz)·exp(-iπλz(fx² + fy²)) on the same padded
grid as the angular spectrum (band-limited the same way); ``fraunhofer`` is the far field as one
centred Fourier transform, on the grid of pitch λz/(W·pitch) it implies: post·FFT(pre·u), whose
adjoint is pre̅·FFTᴴ(post̅·y), FFTᴴ the unnormalised inverse.
"""

from __future__ import annotations

import math

import numpy as np

from .. import validate
from ..opencl import as_device, is_device_array, like_input
from ..opencl.arrays import cached, copy, recycled
from ..scene.field import Field
from . import grid
from .batch import batched
from .convolution import convolution_setup, convolve, multiply, symmetric
from .scaled import scaled
from .transfer import fresnel_transfer, fresnel_transfer_host, quadrant_shape


def fresnel(
    field,
    *,
    wavelength,
    pitch,
    distance,
    offset=(0.0, 0.0),
    padding=2,
    out_pitch=None,
    out_shape=None,
):
    """Propagate a field paraxially (Fresnel) to the parallel plane at ``distance``.

    Parameters
    ----------
    field : (H, W) complex array, NumPy or OpenCL device array
        Field on the source plane, [row, col] = [y, x].
    wavelength : float
        Wavelength λ [m].
    pitch : float or (float, float)
        Sample spacing [m], a number or (x, y).
    distance : float
        Signed distance z to the target plane [m].
    offset : (float, float)
        Lateral position (x0, y0) [m] of the target plane's centre relative to the source's.
    padding : float
        Zero-padding factor per axis, >= 1.
    out_pitch : float or (float, float), optional
        Output sample spacing [m] (chirp-z transform, as for
        :func:`~holo_core.propagation.angular_spectrum`).
    out_shape : (int, int), optional
        Output (rows, cols).

    Returns
    -------
    ndarray or pyopencl.array.Array
        Same result as :func:`~holo_core.propagation.angular_spectrum`: complex64, like the
        input.

    Raises
    ------
    InputError
        Where ``wavelength`` or ``pitch`` is not finite and > 0, or ``distance`` is not finite.

    Notes
    -----
    The transfer function is exp(ikz)·exp(−iπλz(fx² + fy²)), the paraxial approximation of
    the angular spectrum's (Eq. 10); accurate only where the paraxial approximation holds.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import fresnel
    >>> v = fresnel(np.ones((64, 64), complex), wavelength=633e-9, pitch=4e-6, distance=1e-3)
    >>> v.shape, round(float(abs(v[32, 32])), 3)
    ((64, 64), 1.0)
    """
    if out_pitch is not None or out_shape is not None:
        return scaled(
            field,
            transfer=fresnel_transfer_host,
            name="fresnel",
            wavelength=wavelength,
            pitch=pitch,
            distance=distance,
            offset=offset,
            padding=padding,
            out_pitch=out_pitch,
            out_shape=out_shape,
        )
    s = convolution_setup(field, wavelength, pitch, distance, offset, padding)
    wavelength, pitch, z, (x0, y0), padding = s.wavelength, s.pitch, s.z, s.offset, s.padding
    rt, dev, from_host, shape = s.rt, s.dev, s.from_host, s.shape

    quadrant = symmetric(rt, (x0, y0)) and rt.has_fp64

    def make():
        tf = fresnel_transfer_host(shape, wavelength, pitch, z, (x0, y0))
        return tf / (shape[0] * shape[1]), []

    def made():  # on the device where it has float64 (transfer.py), else on the host
        tf = fresnel_transfer(
            rt,
            shape,
            wavelength=wavelength,
            pitch=pitch,
            distance=z,
            offset=(x0, y0),
            quadrant=quadrant,
            out=recycled(rt, "transfer", quadrant_shape(shape) if quadrant else shape)
            if rt.has_fp64
            else None,
        )
        return make() if tf is None else (tf, [])

    tf, _ = cached(rt, ("fresnel", shape, wavelength, pitch, z, x0, y0, quadrant), made)
    return like_input(convolve(rt, dev, tf, shape if quadrant else None), from_host)


def fresnel_adjoint(field, *, wavelength, pitch, distance, offset=(0.0, 0.0), **settings):
    """The adjoint of :func:`fresnel` (the same keywords): Fresnel to −z with the offset
    negated, as for the angular spectrum (its kept rays |x0 − λz·f| alike)."""
    x0, y0 = validate.pair("offset", offset, "m")
    return fresnel(
        field,
        wavelength=wavelength,
        pitch=pitch,
        distance=-np.asarray(distance),
        offset=(-x0, -y0),
        **settings,
    )


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
    phase = (
        math.remainder(k * z, 2 * math.pi)
        + k * (xo**2 + yo**2) / (2 * z)
        - np.pi * ((h - 1) ** 2 / (2 * h) + (w - 1) ** 2 / (2 * w))
    )
    return centred_ramp(shape) * np.exp(1j * phase) * pitch**2 / (1j * wavelength * z)


def fraunhofer(field, *, wavelength, pitch, distance):
    """Propagate a field to the far field at ``distance`` > 0; return it and its grid's pitch.

    Parameters
    ----------
    field : (H, W) complex array, NumPy or OpenCL device array
        Field on the source plane, [row, col] = [y, x].
    wavelength : float
        Wavelength λ [m].
    pitch : float
        Source sample spacing [m].
    distance : float
        Distance z to the far-field plane [m], > 0.

    Returns
    -------
    field : ndarray or pyopencl.array.Array
        Complex64 like the input, on the centred grid of the input's shape.
    pitch : (float, float)
        The output's (x pitch, y pitch) [m]: λz/(W·pitch) along x (the columns) and
        λz/(H·pitch) along y (the rows); every pitch pair in the project is (x, y).

    Raises
    ------
    InputError
        Where ``distance`` is not finite and > 0, or ``wavelength`` or ``pitch`` is not.

    Warns
    -----
    SamplingWarning
        When ``distance`` is short of the Fraunhofer distance 2·D²/λ of the field's non-zero
        extent D.

    Notes
    -----
    U(x', y') = exp(ikz)·exp(ik(x'² + y'²)/(2z))/(iλz) · pitch² · Σ U(x, y)·exp(−i2π(x x' + y y')/(λz)),
    the far-field limit of the Rayleigh–Sommerfeld integral (Eq. 7).

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import fraunhofer
    >>> u = np.ones((64, 64), complex)
    >>> far, (px, py) = fraunhofer(u, wavelength=633e-9, pitch=4e-6, distance=1.0)
    >>> far.shape, round(px * 1e3, 4)
    ((64, 64), 2.4727)
    """
    wavelength, pitch = grid.wave(wavelength, pitch)
    z = validate.positive(
        "distance", validate.within("distance", distance, validate.MAX_LENGTH), "m"
    )
    if not is_device_array(field):
        support = grid.support(validate.host_field("field", field))[0].shape
        extent = math.hypot(*support) * pitch
        if z < 2 * extent**2 / wavelength:
            validate.warn_sampling(
                f"fraunhofer: distance {z:.4g} m is short of the far field of this field "
                f"(2·D²/λ = {2 * extent**2 / wavelength:.4g} m); use fresnel or angular_spectrum"
            )
    rt, dev, from_host = as_device(field)
    h, w = dev.shape
    out_pitch = (wavelength * z / (w * pitch), wavelength * z / (h * pitch))

    pre, _ = cached(rt, ("centred-dft", (h, w)), lambda: (centred_ramp((h, w)), []))
    post, _ = cached(
        rt,
        ("fraunhofer", (h, w), wavelength, pitch, z),
        lambda: (far_factor((h, w), wavelength, pitch, z), []),
    )
    out = copy(dev)
    multiply(rt, out, pre)
    rt.fft.forward(out)
    multiply(rt, out, post)
    return like_input(out, from_host), out_pitch


def _fraunhofer_adjoint(field, *, wavelength, pitch, distance):
    """The far field's adjoint: from its grid back to the source grid of ``pitch`` [m]."""
    wavelength, pitch = grid.wave(wavelength, pitch)
    z = validate.positive(
        "distance", validate.within("distance", distance, validate.MAX_LENGTH), "m"
    )
    rt, dev, from_host = as_device(field)
    h, w = dev.shape
    conj_pre, _ = cached(
        rt, ("centred-dft-adjoint", (h, w)), lambda: (centred_ramp((h, w)).conj(), [])
    )
    conj_post, _ = cached(
        rt,
        ("fraunhofer-adjoint", (h, w), wavelength, pitch, z),
        lambda: (far_factor((h, w), wavelength, pitch, z).conj(), []),
    )
    out = copy(dev)
    multiply(rt, out, conj_post)
    rt.fft.backward(out)
    multiply(rt, out, conj_pre)
    return like_input(out, from_host)


_batched_fraunhofer_adjoint = batched(_fraunhofer_adjoint)


def fraunhofer_adjoint(field, *, wavelength, pitch, distance):
    """The adjoint of :func:`~holo_core.propagation.fraunhofer`: a field on the far field's
    grid back to the source grid. ``pitch`` [m] is the *source* grid's, as given to
    fraunhofer; ``wavelength``, ``distance`` [m] (scalars or arrays over a batch). Arrays
    (H, W) or (..., H, W), NumPy or device; complex64 like the input."""
    if isinstance(field, Field):
        raise validate.InputError(
            "fraunhofer_adjoint takes arrays: a Field carries the far "
            "field's pitch, and the adjoint needs the source's"
        )
    return _batched_fraunhofer_adjoint(field, wavelength=wavelength, pitch=pitch, distance=distance)
