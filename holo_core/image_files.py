"""Image files a person can open, written atomically (temporary file, then rename)."""

from __future__ import annotations

import os
import struct
import tempfile
import zlib
from contextlib import contextmanager
from pathlib import Path

import numpy as np


@contextmanager
def atomic_path(path):
    """A temporary path beside ``path`` (same suffix) to write to; renamed onto ``path`` when
    the block succeeds, removed when it fails, so ``path`` is never left half-written."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def write_atomic(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder, then rename."""
    with atomic_path(path) as tmp:
        Path(tmp).write_bytes(data)
    return Path(path)


def write_png(path, image: np.ndarray) -> Path:
    """8-bit PNG of ``image`` in [0, 1]: (H, W) grey or (H, W, 3) RGB, row 0 at the top."""
    a = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0, 1)
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] != 3):
        raise ValueError(f"image must be (H, W) or (H, W, 3); got shape {a.shape}")
    pixels = np.round(a * 255).astype(np.uint8)
    h, w = pixels.shape[:2]
    colour = 2 if pixels.ndim == 3 else 0
    rows = pixels.reshape(h, -1)
    raw = np.concatenate([np.zeros((h, 1), np.uint8), rows], axis=1).tobytes()

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(
            ">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", w, h, 8, colour, 0, 0, 0)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 6)) \
        + chunk(b"IEND", b"")
    return write_atomic(path, data)


def write_exr(path, channels: dict, **header) -> Path:
    """Float32 OpenEXR (ZIP) of named (H, W) ``channels``, row 0 at the top, with extra
    ``header`` attributes, written atomically."""
    import OpenEXR
    data = {n: np.ascontiguousarray(a, np.float32) for n, a in channels.items()}
    head = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, **header}
    with atomic_path(path) as tmp, OpenEXR.File(head, data) as f:
        f.write(tmp)
    return Path(path)


def srgb(linear: np.ndarray) -> np.ndarray:
    """Linear [0, 1] to sRGB display values."""
    a = np.clip(linear, 0, 1)
    return np.where(a <= 0.0031308, 12.92 * a, 1.055 * a ** (1 / 2.4) - 0.055)
