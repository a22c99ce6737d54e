"""The built-in demo: a holographic scene and diffraction figures.

The scene (Fig. 13 and 15c in spirit): bright beads, a tilted textured checkerboard and a
vertex-coloured mesh, recorded once onto a 30 cm plate (RGB plus the depth wavelength), then
rendered from two camera positions and with two focus settings: ``scene_<view>.exr`` (Combined
and Depth, as Blender reads them), ``.png`` previews and ``scene_<view>_depth.png``.
The diffraction figures (PNG): a square aperture carried to Fresnel numbers 5, 1 and 0.25, a
lens focusing a circular aperture to its Airy pattern, a tilted beam on the plane normal to it.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from .io.hologram import write_hologram
from .io.image import write_png
from .io.view import write_view
from .plate.record import record_hologram
from .plate.view import render_view
from .propagation import angular_spectrum, tilt
from .propagation.grid import coords
from .scene.camera import Camera, look_at
from .scene.mesh import Mesh
from .scene.plate import Plate

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
        panels.append(
            np.abs(angular_spectrum(aperture, wavelength=LAM, pitch=pitch, distance=z)) ** 2
        )
    return np.concatenate([_tone(p) for p in panels], axis=1)


def airy_focus(n=1025, pitch=0.5e-6, f=2.5e-3, radius=0.25e-3):
    x, y = _mesh(n, pitch)
    lens = np.exp(-1j * 2 * np.pi / LAM * np.sqrt(x**2 + y**2 + f**2))  # Eq. 24
    field = np.where(x**2 + y**2 <= radius**2, lens, 0)
    focus = angular_spectrum(field, wavelength=LAM, pitch=pitch, distance=f)
    c = n // 2
    crop = np.abs(focus[c - 128 : c + 128, c - 128 : c + 128]) ** 2
    return _tone(crop) ** 0.5  # log-like stretch shows the rings


def tilted_beam(n=256, pitch=0.5e-6, w0=20e-6, degrees=20.0):
    t = np.radians(degrees)
    m = np.array([[np.cos(t), 0, np.sin(t)], [0, 1, 0], [-np.sin(t), 0, np.cos(t)]])
    x, y = _mesh(n, pitch)
    p = np.stack([x, y, np.zeros_like(x)], -1) @ m
    k, zr = 2 * np.pi / LAM, np.pi * w0**2 / LAM
    q = p[..., 2] - 1j * zr
    beam = (-1j * zr / q) * np.exp(
        1j * k * p[..., 2] + 1j * k * (p[..., 0] ** 2 + p[..., 1] ** 2) / (2 * q)
    )
    out = tilt(beam, wavelength=LAM, pitch=pitch, rotation=m, padding=4)
    phase_before = (np.angle(beam) + np.pi) / (2 * np.pi)
    return np.concatenate([phase_before, _tone(np.abs(out) ** 2)], axis=1)


def _octahedron(centre, radius, colours=None):
    v = np.asarray(centre) + radius * np.array(
        [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1.0]]
    )
    tri = np.array(
        [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    )
    return Mesh(vertices=v, triangles=tri, colours=colours)


def scene_emitters():
    """A tilted 8×8 checkerboard, a vertex-coloured octahedron and three small bright
    beads (the paper's points), in metres (plate at z = 0)."""
    tex = (np.add.outer(np.arange(8), np.arange(8)) % 2)[..., None] * [0.75, 0.7, 0.6] + 0.05
    board = Mesh(
        vertices=np.array(
            [[-0.1, -0.08, -0.03], [0.1, -0.08, -0.03], [0.1, 0.06, -0.16], [-0.1, 0.06, -0.16]]
        ),
        triangles=np.array([[0, 2, 1], [0, 3, 2]]),
        uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]),
        texture=tex,
    )
    octa = _octahedron(
        (0.03, 0.0, -0.09),
        0.04,
        np.array(
            [[1, 0.2, 0.1], [0.1, 0.3, 1], [0.2, 1, 0.2], [1, 1, 0.1], [1, 0.2, 1], [0.1, 1, 1.0]]
        ),
    )
    beads = [
        _octahedron(c, 0.004, np.full((6, 3), 3.0))
        for c in ((-0.07, 0.05, -0.05), (-0.05, 0.07, -0.12), (0.08, 0.06, -0.07))
    ]
    return [board, octa, *beads]


def holographic_scene(out: Path, resolution=1024, iterations=4) -> list[Path]:
    """One recording (``iterations`` random-phase sets, for the temporal composition) seen from
    two viewpoints at two focus settings each: a hologram is recorded once and viewed from
    anywhere in front of it. Recorded without a camera, nothing is culled: surfaces hidden from
    a view show through the ones in front, as light does not occlude light."""
    plate = Plate(matrix_world=np.eye(4), width=0.3, height=0.3)
    log.info("demo: recording %d random-phase holograms", iterations)
    holos = [
        record_hologram(
            scene_emitters(), plate=plate, seed=i, resolution=resolution, method="auto"
        )  # a point sum: nothing culled, nothing hidden
        for i in range(iterations)
    ]
    written = [write_hologram(out / "scene_hologram.exr", holos[0])]
    for side, eye in {"left": (-0.06, 0.04, 0.6), "right": (0.07, -0.03, 0.6)}.items():
        for name, focus in (("near", 0.64), ("far", 0.74)):
            cam = Camera(
                matrix_world=look_at(eye, (0, 0, -0.09), up=(0, 1, 0)),
                lens=50,
                sensor_width=24,
                resolution=(256, 256),
                fstop=0.5,
                focus_distance=focus,
            )
            view = render_view(holos, cam)
            written += write_view(view, out / f"scene_{side}_{name}_focus.exr")
            z = np.where(view.alpha > 0, view.depth, np.nan)
            lo, hi = np.nanmin(z), np.nanmax(z)
            written.append(
                write_png(
                    out / f"scene_{side}_{name}_focus_depth.png",
                    np.nan_to_num(1 - (z - lo) / max(hi - lo, 1e-9)),
                )
            )
    return written


def run(output="out") -> list[Path]:
    """Compute the figures and write them under ``output``; returns the files written."""
    out = Path(output)
    figures = {
        "fresnel_series.png": fresnel_series,
        "airy_focus.png": airy_focus,
        "tilted_beam.png": tilted_beam,
    }
    written = holographic_scene(out)
    for name, make in figures.items():
        log.info("demo: %s", name)
        written.append(write_png(out / name, make()))
    return written
