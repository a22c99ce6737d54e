"""What DHM tools do to an object wave after the sideband filter: phase unwrapping, the phase
ramp (tilt) and a background taken away.

- :func:`unwrap`: 2-D phase unwrapping by least squares (Ghiglia & Romero 1994: the Poisson
  equation of the wrapped phase differences, solved with cosine transforms), then made
  congruent with the wrapped phase (it differs from it by whole turns only), so a phase whose
  neighbours differ by less than π everywhere comes back exactly;
- :func:`fit_phase`: the least-squares polynomial of the unwrapped phase over a region (order
  1: a tilt; 2: a tilt and a curvature, a residual spherical wave);
- :func:`remove_tilt`, :func:`remove_background`: the wave with that polynomial (or a
  background wave, recorded without the object) divided away.
"""

from __future__ import annotations

import numpy as np

from .. import validate
from ..validate import InputError

VANISHING = 1e-9  # a background wave below this fraction of its rms cannot divide


def wrap(phase):
    """``phase`` [rad] into [−π, π)."""
    return (np.asarray(phase) + np.pi) % (2 * np.pi) - np.pi


@validate.public
def unwrap(phase) -> np.ndarray:
    """Unwrap a wrapped (H, W) phase, or a complex wave's angle.

    Parameters
    ----------
    phase : (H, W) real or complex array
        The wrapped phase [rad], or a complex wave whose angle is unwrapped; at least 2 × 2.

    Returns
    -------
    (H, W) float64 ndarray
        The unwrapped phase [rad]: least squares, then whole turns added to the wrapped phase.

    Raises
    ------
    InputError
        Where ``phase`` is not 2-D of at least 2 × 2, or not finite.

    Examples
    --------
    A ramp of 20 rad across the columns, wrapped, comes back whole:

    >>> import numpy as np
    >>> from holo_core import unwrap
    >>> wrapped = np.angle(np.exp(1j * np.tile(np.linspace(0, 20, 64), (64, 1))))
    >>> u = unwrap(wrapped)
    >>> round(float(u[0, -1] - u[0, 0]), 3)
    20.0
    """
    p = np.asarray(phase)
    p = np.angle(p) if np.iscomplexobj(p) else validate.host_field("phase", p).astype(np.float64)
    if p.ndim != 2 or min(p.shape) < 2:
        raise InputError(f"phase must be 2-D, at least 2x2; got shape {p.shape}")
    dx = np.zeros_like(p)
    dy = np.zeros_like(p)
    dx[:, :-1] = wrap(np.diff(p, axis=1))
    dy[:-1, :] = wrap(np.diff(p, axis=0))
    rho = dx.copy()
    rho[:, 1:] -= dx[:, :-1]
    rho += dy
    rho[1:, :] -= dy[:-1, :]
    smooth = _poisson_neumann(rho)
    return p + 2 * np.pi * np.round((smooth - p) / (2 * np.pi))


def _poisson_neumann(rho: np.ndarray) -> np.ndarray:
    """The solution φ of the 5-point Laplacian ∇²φ = ρ with zero-flux edges (mean zero), by
    the FFT of the half-sample-symmetric extension (the cosine transform's)."""
    rows, cols = rho.shape
    ext = np.block([[rho, rho[:, ::-1]], [rho[::-1, :], rho[::-1, ::-1]]])
    ky = np.arange(2 * rows)[:, None]
    kx = np.arange(2 * cols)[None, :]
    eigen = 2 * np.cos(np.pi * ky / rows) + 2 * np.cos(np.pi * kx / cols) - 4
    eigen[0, 0] = 1.0
    spectrum = np.fft.fft2(ext) / eigen
    spectrum[0, 0] = 0.0
    return np.fft.ifft2(spectrum).real[:rows, :cols]


@validate.public
def fit_phase(wave, *, order: int = 1, mask=None) -> np.ndarray:
    """The least-squares polynomial fitted to a wave's unwrapped phase.

    Parameters
    ----------
    wave : (H, W) complex or real array
        A complex wave, or its phase [rad]; unwrapped by :func:`~holo_core.acquired.unwrap`.
    order : int
        The polynomial's order in x, y (pixel coordinates, centred and scaled by the grid's
        size), 1 to 4: 1 a plane (a tilt), 2 a tilt and a curvature (a residual spherical
        wave).
    mask : (H, W) bool array, optional
        Where to fit (the object-free region); default everywhere.

    Returns
    -------
    (H, W) float64 ndarray
        The fitted phase [rad], evaluated on the whole grid.

    Raises
    ------
    InputError
        Where ``order`` is out of 1 to 4, or ``mask`` is not (H, W) with at least as many True
        samples as the polynomial has terms.

    Examples
    --------
    A tilt of 0.3 rad a column and 0.1 rad a row:

    >>> import numpy as np
    >>> from holo_core.acquired import fit_phase
    >>> y, x = np.mgrid[:64, :64]
    >>> p = fit_phase(np.exp(1j * (0.3 * x + 0.1 * y)))
    >>> round(float(p[0, 1] - p[0, 0]), 6), round(float(p[1, 0] - p[0, 0]), 6)
    (0.3, 0.1)
    """
    u = validate.host_field("wave", wave)
    order = validate.integer("order", order, 1, 4)
    phase = unwrap(u if np.iscomplexobj(u) else np.exp(1j * u))
    rows, cols = phase.shape
    y, x = np.mgrid[:rows, :cols].astype(np.float64)
    y, x = (y - (rows - 1) / 2) / rows, (x - (cols - 1) / 2) / cols
    terms = [x**i * y**j for i in range(order + 1) for j in range(order + 1 - i)]
    keep = np.ones(phase.shape, bool) if mask is None else np.asarray(mask, bool)
    if keep.shape != phase.shape or keep.sum() < len(terms):
        raise InputError(
            f"mask must be a boolean (H, W) = {phase.shape} array with at least "
            f"{len(terms)} True samples"
        )
    design = np.stack([t[keep] for t in terms], -1)
    coeffs, *_ = np.linalg.lstsq(design, phase[keep], rcond=None)
    return sum(c * t for c, t in zip(coeffs, terms))


@validate.public
def remove_tilt(wave, *, mask=None) -> np.ndarray:
    """A wave with its phase ramp taken away: a residual carrier, or the object's own tilt.

    Parameters
    ----------
    wave : (H, W) complex array
        The object wave.
    mask : (H, W) bool array, optional
        Where the plane is fitted to its phase (:func:`fit_phase`, order 1); default
        everywhere.

    Returns
    -------
    (H, W) complex64 ndarray
        ``wave`` times exp(−i·plane).

    Raises
    ------
    InputError
        As :func:`fit_phase`.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.acquired import remove_tilt
    >>> y, x = np.mgrid[:64, :64]
    >>> flat = remove_tilt(np.exp(1j * (0.3 * x + 0.1 * y)))
    >>> bool(np.abs(np.angle(flat)).max() < 1e-6)
    True
    """
    u = validate.host_field("wave", wave)
    return (u * np.exp(-1j * fit_phase(u, order=1, mask=mask))).astype(np.complex64)


@validate.public
def remove_background(wave, background=None, *, order: int = 2, mask=None) -> np.ndarray:
    """A wave with its background taken away.

    Parameters
    ----------
    wave : (H, W) complex array
        The object wave.
    background : (H, W) complex array, optional
        The same optics' wave without the object, filtered alike; the wave is divided by it.
        None: divided by exp(i·p) instead, p the phase polynomial of ``order`` fitted over
        ``mask``.
    order : int
        The polynomial's order, 1 to 4 (without ``background``).
    mask : (H, W) bool array, optional
        The object-free region the polynomial is fitted over (without ``background``).

    Returns
    -------
    (H, W) complex64 ndarray

    Raises
    ------
    InputError
        Where ``background``'s shape differs from the wave's, or it vanishes (below 1e-9 of
        its rms) anywhere; as :func:`fit_phase` without one.

    Examples
    --------
    A curvature and a tilt (a residual spherical wave) taken away by the order-2 fit:

    >>> import numpy as np
    >>> from holo_core.acquired import remove_background
    >>> y, x = np.mgrid[:64, :64] / 64
    >>> wave = np.exp(1j * (3 * x + 8 * (x - 0.5) ** 2 + 8 * (y - 0.5) ** 2))
    >>> bool(np.abs(np.angle(remove_background(wave))).max() < 1e-5)
    True
    """
    u = validate.host_field("wave", wave)
    if background is None:
        return (u * np.exp(-1j * fit_phase(u, order=order, mask=mask))).astype(np.complex64)
    b = validate.host_field("background", background)
    if b.shape != u.shape:
        raise InputError(f"background must have the wave's shape {u.shape}; got {b.shape}")
    small = np.abs(b) <= VANISHING * np.sqrt(np.mean(np.abs(b) ** 2))
    if small.any():
        raise InputError(f"background vanishes at {int(small.sum())} samples: it cannot divide")
    return (u / b).astype(np.complex64)
