"""Analytic fields for the physics tests (float64 NumPy)."""

import numpy as np

from holo_core.propagation.grid import coords


def mesh(shape, pitch):
    """(X, Y) [m] of a grid's pixel centres, [row, col] = [y, x]."""
    return np.meshgrid(coords(shape[1], pitch), coords(shape[0], pitch))


def gaussian_beam(x, y, z, *, w0, wavelength):
    """Paraxial Gaussian beam with its waist w0 [m] at z = 0, exp(+ikz) convention.

    U = (q0/q)·exp(ikz)·exp(ik(x² + y²)/(2q)), q = z - i·zR, zR = π w0²/λ.
    """
    k = 2 * np.pi / wavelength
    zr = k * w0**2 / 2
    q = z - 1j * zr
    return (-1j * zr / q) * np.exp(1j * k * z) * np.exp(1j * k * (x**2 + y**2) / (2 * q))


def rot_y(angle):
    """Rotation by ``angle`` [rad] about y: columns are the rotated x, y, z axes."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_x(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
