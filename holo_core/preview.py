"""Pictures and one-line summaries of the library's types for notebooks (``_repr_png_``,
``__repr__``): no physics, no files, importable by every layer.

A picture is at most ``MAX_SIDE`` pixels a side (block means of the samples), 8-bit PNG.
"""

from __future__ import annotations

import math
import struct
import zlib

import numpy as np

MAX_SIDE = 512  # pixels of a notebook picture's longer side, at most


def png(image: np.ndarray) -> bytes:
    """An 8-bit PNG of ``image`` in [0, 1]: (H, W) grey or (H, W, 3) RGB, row 0 at the top."""
    a = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0, 1)
    pixels = np.round(a * 255).astype(np.uint8)
    h, w = pixels.shape[:2]
    rows = pixels.reshape(h, -1)
    raw = np.concatenate([np.zeros((h, 1), np.uint8), rows], axis=1).tobytes()

    def chunk(kind, body):
        return (
            struct.pack(">I", len(body))
            + kind
            + body
            + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
        )

    header = struct.pack(">IIBBBBB", w, h, 8, 2 if pixels.ndim == 3 else 0, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw, 6))
        + chunk(b"IEND", b"")
    )


def thumbnail(a: np.ndarray, max_side: int = MAX_SIDE) -> np.ndarray:
    """``a`` (H, W, ...) reduced by block means to at most ``max_side`` a side."""
    a = np.asarray(a, np.float64)
    step = max(1, math.ceil(max(a.shape[:2]) / max_side))
    if step == 1:
        return a
    h, w = (a.shape[0] // step) * step, (a.shape[1] // step) * step
    a = a[:h, :w]
    return a.reshape(h // step, step, w // step, step, *a.shape[2:]).mean(axis=(1, 3))


def normalised(a: np.ndarray) -> np.ndarray:
    """``a`` divided by its 99.9th percentile (a few hot pixels do not darken the rest)."""
    a = np.nan_to_num(np.asarray(a, np.float64))
    top = float(np.percentile(a, 99.9)) if a.size else 0.0
    top = top if top > 0 else float(a.max()) if a.size and a.max() > 0 else 1.0
    return np.clip(a / top, 0, 1)


def srgb(linear: np.ndarray) -> np.ndarray:
    """Linear [0, 1] to sRGB display values."""
    a = np.clip(linear, 0, 1)
    return np.where(a <= 0.0031308, 12.92 * a, 1.055 * a ** (1 / 2.4) - 0.055)


def length(metres: float) -> str:
    """A length [m] in the unit that reads best: '633 nm', '3.45 µm', '1.2 mm', '0.5 m',
    '1.97 pm' (an electron's wave)."""
    m = abs(float(metres))
    for unit, scale in (("m", 1.0), ("mm", 1e-3), ("µm", 1e-6), ("nm", 1e-9)):
        if m >= scale * (1 - 5e-5) or m == 0:
            return f"{metres / scale:.4g} {unit}"
    return f"{metres / 1e-12:.4g} pm"


def lengths(values) -> str:
    """Several lengths [m] in one unit, as '633/532/473 nm'."""
    values = [float(v) for v in values]
    top = max(abs(v) for v in values) if values else 0.0
    unit = length(top).split()[-1]
    scale = {"pm": 1e-12, "nm": 1e-9, "µm": 1e-6, "mm": 1e-3, "m": 1.0}[unit]
    return "/".join(f"{v / scale:.4g}" for v in values) + f" {unit}"


def where(a) -> str:
    """'host' for NumPy arrays, 'device <name>' for OpenCL arrays (read without importing
    pyopencl: any array that names a queue)."""
    queue = getattr(a, "queue", None)
    if queue is None:
        return "host"
    try:
        return f"device {queue.device.name.strip()}"
    except Exception:  # noqa: BLE001 -- a released queue still names no device
        return "device"
