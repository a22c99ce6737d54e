"""An off-axis optical hologram as a lab's camera records it, made by a code path of its own
(float64 NumPy, none of Holo's recorder or propagation): a letter-shaped transmission object
with a dot on its right, 5 cm behind a 2048² sensor of 3.45 µm pixels, lit at 633 nm, its
light band-limited by the object beam's aperture stop, interfering with a tilted plane
reference, saved as a 16-bit PNG. The core's and the add-on's tests import it with the pitch,
wavelength and distance alone and compare what they see with :func:`letter`.
"""

from __future__ import annotations

import zlib
from pathlib import Path

import numpy as np

WAVELENGTH, PITCH, DISTANCE, SIZE = 633e-9, 3.45e-6, 0.05, 2048
BAND = 35e3  # the aperture stop's band [1/m] (sin θ = 0.022)
CARRIER = (0.55 / (2 * PITCH), -0.55 / (2 * PITCH))  # [1/m]: 0.78 of Nyquist, azimuth -45°
LETTER_HEIGHT = 3.2e-3  # the letter 'F' [m]
NOISE = 2e-3  # the camera's noise, rms, of the peak intensity


def letter(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The ground truth: True on the letter 'F' and its dot, at positions x, y [m] of the
    object plane, as a viewer in front of the hologram sees it (x to the right, y up; the
    project's arrays put row i at y, so an array of it shows the F upside down). The F's bar
    and arm point right (+x); the dot lies right of the stem, below the arm."""
    h = LETTER_HEIGHT
    stroke = 0.18 * h
    left, top = -0.35 * h, 0.5 * h

    def box(x0, y1, w, hh):  # from its left edge x0 and its top edge y1, down
        return (x >= x0) & (x < x0 + w) & (y <= y1) & (y > y1 - hh)

    stem = box(left, top, stroke, h)
    bar = box(left, top, 0.62 * h, stroke)
    arm = box(left, top - 0.42 * h, 0.45 * h, stroke)
    dot = (x - 0.25 * h) ** 2 + (y + 0.3 * h) ** 2 <= (0.09 * h) ** 2
    return stem | bar | arm | dot


def coords(n: int, pitch: float) -> np.ndarray:
    return (np.arange(n) - (n - 1) / 2) * pitch


def object_wave(size: int = SIZE) -> np.ndarray:
    """The object's wave on the sensor (float64): the letter's transmission lit by a plane
    wave, band-limited to :data:`BAND` (a smooth stop), carried ``DISTANCE`` by the exact
    angular spectrum on a 2x grid (no light of it leaves the sensor)."""
    n = 2 * size
    x = coords(n, PITCH)
    mask = letter(x[None, :], x[:, None]).astype(np.float64)
    f = np.fft.fftfreq(n, PITCH)
    f2 = f[None, :] ** 2 + f[:, None] ** 2
    stop = 0.5 * (1 - np.tanh((np.sqrt(f2) - BAND) / (0.05 * BAND)))
    kz = np.sqrt(np.maximum(1 / WAVELENGTH**2 - f2, 0.0))
    transfer = np.exp(2j * np.pi * DISTANCE * kz) * stop
    wave = np.fft.ifft2(np.fft.fft2(mask) * transfer)
    lo = (n - size) // 2
    return wave[lo : lo + size, lo : lo + size]


def hologram(size: int = SIZE, seed: int = 38) -> np.ndarray:
    """|O + R|² on the sensor (float64), the reference a plane wave of unit amplitude at
    :data:`CARRIER`, the object wave scaled to peak at 0.6 of it, with the camera's noise."""
    o = object_wave(size)
    o *= 0.6 / np.abs(o).max()
    x = coords(size, PITCH)
    r = np.exp(
        2j
        * np.pi
        * (np.remainder(CARRIER[0] * x, 1.0)[None, :] + np.remainder(CARRIER[1] * x, 1.0)[:, None])
    )
    h = np.abs(o + r) ** 2
    rng = np.random.default_rng(seed)
    return np.clip(h + NOISE * h.max() * rng.normal(size=h.shape), 0, None)


def save_png16(path, intensity: np.ndarray) -> Path:
    """A 16-bit greyscale PNG of ``intensity`` scaled to its peak (a camera's raw frame),
    written by zlib alone."""
    counts = np.round(intensity / intensity.max() * 65535).astype(">u2")
    rows = b"".join(b"\0" + counts[i].tobytes() for i in range(counts.shape[0]))

    def chunk(kind, data):
        return (
            len(data).to_bytes(4, "big")
            + kind
            + data
            + (zlib.crc32(kind + data) & 0xFFFFFFFF).to_bytes(4, "big")
        )

    h, w = counts.shape
    header = w.to_bytes(4, "big") + h.to_bytes(4, "big") + bytes([16, 0, 0, 0, 0])
    path = Path(path)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(rows, 6))
        + chunk(b"IEND", b"")
    )
    return path


def optical_scan(folder, size: int = SIZE) -> Path:
    """The scan as a 16-bit PNG in ``folder`` (made once per folder)."""
    path = Path(folder) / f"letter_scan_{size}.png"
    if not path.exists():
        save_png16(path, hologram(size))
    return path


def depth_of_focus() -> float:
    """λ/NA² [m] of the recorded wave, NA = sin θ of its band: the range of distances over
    which the refocused image stays sharp."""
    na = BAND * WAVELENGTH
    return WAVELENGTH / na**2


def resolution() -> float:
    """The finest period the band carries at the object [m]: 1/BAND."""
    return 1 / BAND


__all__ = [
    "BAND",
    "CARRIER",
    "DISTANCE",
    "PITCH",
    "SIZE",
    "WAVELENGTH",
    "depth_of_focus",
    "hologram",
    "letter",
    "object_wave",
    "optical_scan",
    "resolution",
]
