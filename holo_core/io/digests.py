"""Keys and digests of a tiled store: a recording's digest, its id in the tiles' records, a
chunk's checksum, and where a tile's chunk and record live in the store."""

from __future__ import annotations

import hashlib
import json

import numpy as np

WAVE, DONE = "object_wave", "tiles_done"


def digest_of(parts: dict) -> str:
    """The recording's digest (hex) of its ``parts`` (each a hex digest or a plain value)."""
    return hashlib.sha256(json.dumps(parts, sort_keys=True).encode()).hexdigest()


def array_digest(a) -> str:
    """A short digest (hex) of an array's values, shape and type."""
    a = np.ascontiguousarray(a)
    h = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())
    return h.hexdigest()[:16]


def record_id(recording: dict) -> int:
    """The recording's id in the tiles' records: its digest's first 8 bytes, never 0."""
    return int(recording["digest"][:16], 16) | 1


def chunk_sum(data: bytes) -> int:
    return int.from_bytes(hashlib.blake2b(data, digest_size=8).digest(), "little")


def wave_key(c, i, j) -> str:
    return f"{WAVE}/c/{c}/{i}/{j}"


def record_key(i, j) -> str:
    return f"{DONE}/c/{i}/{j}/0"
