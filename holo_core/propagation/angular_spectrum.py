"""Angular spectrum propagation to a parallel plane with a lateral offset (Eq. 10, 12-15), its
adjoint, and its transfer function (``transfer_function``, float64, kept in transfer.py beside
the device's).

The band limit follows Matsushima & Shimobaba (2009) and, for an offset, Matsushima (2010): a
frequency is kept only where the transfer function's phase is sampled at the padded grid's
frequency step, i.e. where the ray it stands for, x0 - z·fx/fz, stays within half the padded
window. A hard band edge leaves a slowly decaying Gibbs tail (~1/(π·f_lim·x)) all over the
output, so the limit rolls off with a raised cosine over the outermost ``BAND_EDGE`` of that
range: against the direct Rayleigh-Sommerfeld sum (250 µm square, N_F = 0.25, 4x padding) the
error falls from 4e-3 to 1e-5; only rays linking the window's far corners are attenuated.
Evanescent components (fx² + fy² > 1/λ²) are dropped.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .. import validate
from ..opencl import like_input
from ..opencl.arrays import cached, nonzero_count, recycled
from . import grid
from .convolution import convolution_setup, convolve, symmetric
from .scaled import scaled
from .transfer import BAND_EDGE, asm_transfer, quadrant_shape, transfer_function


def angular_spectrum(
    field,
    *,
    wavelength,
    pitch,
    distance,
    offset=(0.0, 0.0),
    padding=2,
    band_limit=True,
    out_pitch=None,
    out_shape=None,
    read=None,
):
    """Propagate a field to the parallel plane at ``distance``, its centre shifted by ``offset``.

    Parameters
    ----------
    field : (H, W) complex array, NumPy or OpenCL device array
        Field on the source plane, [row, col] = [y, x], pixel centres as in :mod:`.grid`.
    wavelength : float
        Wavelength λ [m].
    pitch : float or (float, float)
        Sample spacing of input and output [m], or (x, y) spacings [m].
    distance : float
        Signed distance z to the target plane [m]; negative propagates backwards.
    offset : (float, float)
        Lateral position (x0, y0) [m] of the target plane's centre relative to the source's.
    padding : float
        Zero-padding factor per axis, >= 1 (2 keeps the circular convolution from wrapping).
    band_limit : bool
        Apply the (shifted) band limit; without it, distances beyond the grid's alias-free
        limit give a :class:`~holo_core.validate.SamplingWarning`.
    out_pitch : float or (float, float), optional
        Output sample spacing [m]: the propagation is evaluated on that grid by a chirp-z
        transform (:mod:`.scaled`); coarser than ``pitch`` drops what it cannot hold.
    out_shape : (int, int), optional
        Output (rows, cols), centred at ``offset``; default the input's window at
        ``out_pitch``.
    read : (int, int), optional
        Only (rows, cols) samples around the output's centre will be read: a padded grid that
        spans the input and those (padding < 2) wraps nothing onto them, and is not reported.

    Returns
    -------
    ndarray or pyopencl.array.Array
        Complex64 array of the input's shape and pitch (or ``out_shape`` and ``out_pitch``),
        NumPy or device array like the input.

    Raises
    ------
    InputError
        Where ``wavelength`` or ``pitch`` is not finite and > 0, ``distance`` or ``offset`` is
        not finite, ``padding`` < 1, or ``field`` is not a finite 2-D array.

    Notes
    -----
    The discrete propagation to a parallel plane with offset (DPPO) of the paper, Eq. 14 with
    the offset's shift theorem Eq. 15 (continuous form Eq. 10, 12-13): the angular spectrum is
    multiplied by exp(i2πz√(1/λ² − fx² − fy²))·exp(i2π(fx x0 + fy y0)); evanescent components
    are dropped.

    Examples
    --------
    A plane wave keeps its amplitude and gains the phase kz:

    >>> import numpy as np
    >>> from holo_core import angular_spectrum
    >>> u = np.ones((64, 64), complex)
    >>> v = angular_spectrum(u, wavelength=500e-9, pitch=4e-6, distance=1.25e-7)
    >>> v.shape, round(float(abs(v[32, 32])), 3), round(float(np.angle(v[32, 32])), 3)
    ((64, 64), 1.0, 1.571)
    """
    if out_pitch is not None or out_shape is not None:
        return scaled(
            field,
            transfer=functools.partial(_transfer, band_limit=band_limit),
            name="angular_spectrum",
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

    quadrant = symmetric(rt, (x0, y0))

    def make():  # on the device (transfer.py); the float64 reference is transfer_function
        tf = asm_transfer(
            rt,
            shape,
            wavelength=wavelength,
            pitch=pitch,
            distance=z,
            offset=(x0, y0),
            band_limit=band_limit,
            edge=BAND_EDGE,
            quadrant=quadrant,
            out=recycled(rt, "transfer", quadrant_shape(shape) if quadrant else shape),
        )
        # with no offset the straight-through wave (f = 0) always passes
        reaches = quadrant or (x0, y0) == (0.0, 0.0) or nonzero_count(rt, tf) > 0
        notes = sampling_notes(
            dev.shape, shape, wavelength, pitch, z, (x0, y0), padding, band_limit, reaches, read
        )
        return tf, notes

    key = (
        "asm",
        dev.shape,
        shape,
        wavelength,
        pitch,
        z,
        x0,
        y0,
        bool(band_limit),
        None if read is None else tuple(read),
        quadrant,
    )
    tf, notes = cached(rt, key, make)
    for note in notes:
        validate.warn_sampling(note)
    return like_input(convolve(rt, dev, tf, shape if quadrant else None), from_host)


def angular_spectrum_adjoint(field, *, wavelength, pitch, distance, offset=(0.0, 0.0), **settings):
    """The adjoint of :func:`angular_spectrum` (the same keywords): a field on the target
    plane back to the source's grid. The propagation pads, transforms, multiplies by H,
    transforms back and crops at the same place, so its adjoint multiplies by H̄ instead, and
    H̄(z, x0, y0) = H(−z, −x0, −y0), its band limit |x0 − z·f/fz| too: the angular spectrum
    to −z with the offset negated."""
    x0, y0 = validate.pair("offset", offset, "m")
    return angular_spectrum(
        field,
        wavelength=wavelength,
        pitch=pitch,
        distance=-np.asarray(distance),
        offset=(-x0, -y0),
        **settings,
    )


def _transfer(shape, wavelength, pitch, distance, offset, band_limit) -> np.ndarray:
    return transfer_function(
        shape,
        wavelength=wavelength,
        pitch=pitch,
        distance=distance,
        offset=offset,
        band_limit=band_limit,
    )


def alias_free_distance(shape, pitch, wavelength, offset=(0.0, 0.0)) -> float:
    """The largest distance for which the unlimited transfer function is alias-free on a grid.

    The ray slope fx/fz is largest at the grid's highest frequencies; beyond this distance the
    band limit removes frequencies the grid holds (without it, they alias).

    Parameters
    ----------
    shape : (int, int)
        The (padded) grid (H, W).
    pitch : float or (float, float)
        Sample spacing [m], or (x, y).
    wavelength : float
        λ [m].
    offset : (float, float)
        The output plane's lateral offset (x0, y0) [m].

    Returns
    -------
    float
        The largest |z| [m]; 0 where the grid's corner frequency reaches the evanescent
        cut-off (a square pitch <= λ/√2) or the offset is half the window or more.

    Notes
    -----
    A ray of frequency (fx, fy) moves by z·fx/fz across the plane (Eq. 12-13): it stays in
    the half window n·pitch/2 − |x0| up to this z.

    Examples
    --------
    >>> from holo_core.propagation import alias_free_distance
    >>> round(alias_free_distance((256, 256), 2e-6, 633e-9) * 1e3, 3)   # mm
    1.577
    """
    px, py = grid.pitch_pair(pitch)
    fmax = [np.abs(grid.freqs(n, p)).max() for n, p in zip(shape, (py, px))]  # (fy, fx)
    fz2 = 1.0 / wavelength**2 - fmax[0] ** 2 - fmax[1] ** 2
    if fz2 <= 0:
        return 0.0
    limits = [
        (n * p / 2 - abs(o)) * math.sqrt(fz2) / f
        for n, p, o, f in ((shape[1], px, offset[0], fmax[1]), (shape[0], py, offset[1], fmax[0]))
    ]
    return max(0.0, min(limits))


def sampling_notes(
    shape, padded, wavelength, pitch, z, offset, padding, band_limit, reaches, read=None
):
    """Why the grid cannot carry the field to ``z`` alias-free, as messages (empty if it can);
    ``reaches``: the transfer function is not all zero; ``read``: the (rows, cols) around the
    output's centre that will be read (a padded grid spanning the input and those wraps
    nothing onto them)."""
    safe = alias_free_distance(padded, pitch, wavelength, offset)
    px, py = grid.pitch_pair(pitch)
    spacing = f"{px:.4g} m" if px == py else f"{px:.4g} x {py:.4g} m"
    where = f"{shape[0]}x{shape[1]} at {spacing} pitch, padding {padding:g}"
    notes = []
    if abs(z) > safe and not band_limit:
        notes.append(
            f"angular_spectrum: |distance| = {abs(z):.4g} m exceeds the alias-free "
            f"limit {safe:.4g} m of this grid ({where}); use band_limit=True or more "
            f"padding"
        )
    elif (
        abs(z) > safe
        and padding < 2
        and (read is None or any(p < n + r for p, n, r in zip(padded, shape, read)))
    ):
        notes.append(
            f"angular_spectrum: with padding {padding:g} < 2 the band-limited "
            f"convolution wraps around beyond |distance| = {safe:.4g} m; use padding >= 2"
        )
    if not reaches:
        notes.append(
            f"angular_spectrum: no direction this grid ({where}) samples reaches the "
            f"target at offset {offset} m, distance {z:.4g} m: the result is zero"
        )
    return notes
