"""Tilted planes by rotating the angular spectrum (Eq. 11), and placed planes (Sect. IV-D).

A rotation ``M`` has the target plane's axes (ξ, η, ζ) as its columns, in source coordinates:
it maps target coordinates to source coordinates, and target frequencies to source ones,
f = M·f'. Both planes pass through the source grid's centre. The spectrum is interpolated
linearly (after Delen & Hooker) on the zero-padded grid, so ``padding`` also refines it.
"""

from __future__ import annotations

import numpy as np

from .. import validate
from ..opencl import as_device, like_input
from . import grid
from .angular_spectrum import angular_spectrum
from .resample import resample
from ..opencl.arrays import embed, empty, window


def tilt(field, *, wavelength, pitch, rotation, padding=2, out_shape=None, out_pitch=None):
    """The field on the plane through the source centre with orientation ``rotation``.

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
        Zero-padding factor (>= 1) of source and target grids; finer spectra interpolate better.
    out_shape : (int, int), optional
        Target grid (rows, cols); default the source shape.
    out_pitch : float, optional
        Target sample spacing [m]; default ``pitch``.

    Returns
    -------
    Complex64 field on the target plane, like the input. Components travelling backwards in
    either frame are dropped, so only light that reaches the target from the source side stays.
    """
    wavelength, pitch = grid.wave(wavelength, pitch)
    m = validate.rotation("rotation", rotation)
    padding = grid.padding_factor(padding)
    rt, src, from_host = as_device(field)
    out_shape = validate.shape2d("out_shape", src.shape if out_shape is None else out_shape)
    out_pitch = pitch if out_pitch is None else validate.positive("out_pitch", out_pitch, "m")
    hs, ws = grid.padded_shape(src.shape, padding)
    ht, wt = grid.padded_shape(out_shape, padding)
    spectrum = rt.scratch("tilt-source", (hs, ws))
    (r0, c0), (t0, u0) = _corner(src.shape, (hs, ws)), _corner(out_shape, (ht, wt))
    embed(rt, spectrum, src, r0, c0)
    rt.fft.forward(spectrum)
    target = empty(rt, (ht, wt))
    freq = [1 / (ht * out_pitch), 1 / (wt * out_pitch), 1 / (hs * pitch), 1 / (ws * pitch),
            1 / wavelength**2, *m.ravel(),
            (r0 + (src.shape[0] - 1) / 2) / hs, (c0 + (src.shape[1] - 1) / 2) / ws,
            (t0 + (out_shape[0] - 1) / 2) / ht, (u0 + (out_shape[1] - 1) / 2) / wt]
    scale = np.float32(pitch**2 / (out_pitch**2 * ht * wt))
    rt.kernel("spectral", "rotate_spectrum", rt.real_options)(
        rt.queue, (ht, wt), None, target.data, spectrum.data, np.int32(hs), np.int32(ws),
        *(rt.real(f) for f in freq), scale)
    rt.fft.backward(target)
    return like_input(window(rt, target, out_shape, t0, u0), from_host)


def _corner(shape, padded):
    """Where a field of ``shape`` sits, centred, in the ``padded`` grid: (row, col)."""
    return (padded[0] - shape[0]) // 2, (padded[1] - shape[1]) // 2


def propagate_to_plane(field, *, wavelength, pitch, rotation, position, padding=2,
                       out_shape=None, out_pitch=None):
    """The field on a placed plane: tilt first, then propagate with offset (Sect. IV-D).

    Parameters
    ----------
    field, wavelength, pitch, padding, out_shape, out_pitch
        As for :func:`tilt`.
    rotation : (3, 3) array
        Orientation of the target plane (columns: its axes in source coordinates).
    position : (float, float, float)
        Centre of the target plane [m] in source coordinates.

    Returns
    -------
    Complex64 field on the target grid, like the input.
    """
    m = validate.rotation("rotation", rotation)
    p = np.asarray(position, dtype=np.float64)
    if p.shape != (3,) or not np.isfinite(p).all():
        raise ValueError(f"position must be 3 finite coordinates [m]; got {position!r}")
    x0, y0, z = m.T @ p
    tilted = field
    if not np.allclose(m, np.eye(3), atol=1e-12):
        tilted = tilt(field, wavelength=wavelength, pitch=pitch, rotation=m, padding=padding,
                      out_shape=out_shape, out_pitch=out_pitch)
        pitch = out_pitch or pitch
    elif out_shape is not None or out_pitch is not None:
        tilted = resample(field, pitch=pitch, out_shape=out_shape or np.shape(field),
                          out_pitch=out_pitch or pitch)
        pitch = out_pitch or pitch
    if z == 0 and x0 == 0 and y0 == 0:
        return tilted
    return angular_spectrum(tilted, wavelength=wavelength, pitch=pitch, distance=z,
                            offset=(x0, y0), padding=padding)
