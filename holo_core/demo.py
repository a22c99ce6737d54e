"""The built-in demo: diffraction figures computed by the propagation engine.

Written as PNGs: a square aperture carried to Fresnel numbers 5, 1 and 0.25 (angular spectrum
beside the direct Rayleigh-Sommerfeld sum), a lens focusing a circular aperture to its Airy
pattern, and a tilted beam seen on the plane normal to it.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from .image_files import write_png
from .propagation import angular_spectrum, tilt
from .propagation.grid import coords

log = logging.getLogger(__name__)
LAM = 633e-9


def _tone(intensity: np.ndarray) -> np.ndarray:
    """Intensity to display values: normalised, gamma 1/2.2."""
    return (intensity / intensity.max()) ** (1 / 2.2)


def _mesh(n, pitch):
    return np.meshgrid(coords(n, pitch), coords(n, pitch))


def fresnel_series(n=512, pitch=2e-6, half_width=125e-6):
    x, y = _mesh(n, pitch)
    aperture = ((np.abs(x) <= half_width) & (np.abs(y) <= half_width)).astype(np.complex64)
    panels = [np.abs(aperture) ** 2]
    for nf in (5.0, 1.0, 0.25):
        z = half_width**2 / (LAM * nf)
        panels.append(np.abs(angular_spectrum(aperture, wavelength=LAM, pitch=pitch,
                                              distance=z)) ** 2)
    return np.concatenate([_tone(p) for p in panels], axis=1)


def airy_focus(n=1025, pitch=0.5e-6, f=2.5e-3, radius=0.25e-3):
    x, y = _mesh(n, pitch)
    lens = np.exp(-1j * 2 * np.pi / LAM * np.sqrt(x**2 + y**2 + f**2))  # Eq. 24
    field = np.where(x**2 + y**2 <= radius**2, lens, 0)
    focus = angular_spectrum(field, wavelength=LAM, pitch=pitch, distance=f)
    c = n // 2
    crop = np.abs(focus[c - 128:c + 128, c - 128:c + 128]) ** 2
    return _tone(crop) ** 0.5  # log-like stretch shows the rings


def tilted_beam(n=256, pitch=0.5e-6, w0=20e-6, degrees=20.0):
    t = np.radians(degrees)
    m = np.array([[np.cos(t), 0, np.sin(t)], [0, 1, 0], [-np.sin(t), 0, np.cos(t)]])
    x, y = _mesh(n, pitch)
    p = np.stack([x, y, np.zeros_like(x)], -1) @ m
    k, zr = 2 * np.pi / LAM, np.pi * w0**2 / LAM
    q = p[..., 2] - 1j * zr
    beam = (-1j * zr / q) * np.exp(1j * k * p[..., 2]
                                   + 1j * k * (p[..., 0] ** 2 + p[..., 1] ** 2) / (2 * q))
    out = tilt(beam, wavelength=LAM, pitch=pitch, rotation=m, padding=4)
    phase_before = (np.angle(beam) + np.pi) / (2 * np.pi)
    return np.concatenate([phase_before, _tone(np.abs(out) ** 2)], axis=1)


def run(output="out") -> list[Path]:
    """Compute the figures and write them under ``output``; returns the files written."""
    out = Path(output)
    figures = {"fresnel_series.png": fresnel_series, "airy_focus.png": airy_focus,
               "tilted_beam.png": tilted_beam}
    written = []
    for name, make in figures.items():
        log.info("demo: %s", name)
        written.append(write_png(out / name, make()))
    return written
