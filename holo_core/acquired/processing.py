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
    """The least-squares polynomial in x, y (pixels, centred) of ``order`` (1: a plane, a
    tilt; 2: with a curvature) fitted to ``wave``'s unwrapped phase where ``mask`` is True
    (default: everywhere), evaluated on the whole (H, W) grid [rad]."""
    u = validate.host_field("wave", wave)
    order = validate.integer("order", order, 1, 4)
    phase = unwrap(u if np.iscomplexobj(u) else np.exp(1j * u))
    rows, cols = phase.shape
    y, x = np.mgrid[:rows, :cols].astype(np.float64)
    y, x = (y - (rows - 1) / 2) / rows, (x - (cols - 1) / 2) / cols
    terms = [x**i * y**j for i in range(order + 1) for j in range(order + 1 - i)]
    keep = np.ones(phase.shape, bool) if mask is None else np.asarray(mask, bool)
    if keep.shape != phase.shape or keep.sum() < len(terms):
        raise InputError(f"mask must be a boolean (H, W) = {phase.shape} array with at least "
                         f"{len(terms)} True samples")
    design = np.stack([t[keep] for t in terms], -1)
    coeffs, *_ = np.linalg.lstsq(design, phase[keep], rcond=None)
    return sum(c * t for c, t in zip(coeffs, terms))


@validate.public
def remove_tilt(wave, *, mask=None) -> np.ndarray:
    """``wave`` with the phase ramp (the plane fitted to its phase over ``mask``) taken away,
    complex64: a residual carrier, or the object's own tilt."""
    u = validate.host_field("wave", wave)
    return (u * np.exp(-1j * fit_phase(u, order=1, mask=mask))).astype(np.complex64)


@validate.public
def remove_background(wave, background=None, *, order: int = 2, mask=None) -> np.ndarray:
    """``wave`` with its background taken away, complex64: divided by ``background`` (the
    same optics' wave without the object, filtered alike), or, without one, by the phase
    polynomial of ``order`` fitted over ``mask`` (the object-free region)."""
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
