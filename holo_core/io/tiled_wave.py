"""A tiled store's plate read lazily: only the tiles an index touches, each checked against its
record the first time it is read."""

from __future__ import annotations

import numpy as np

from ..scene.hologram import Hologram
from .store import PlateStore, read_store


class TiledWave:
    """A tiled store's object wave as an array (C, H, W) complex64 that reads, and checks,
    only the tiles an index touches: each tile's chunk against its record's checksum, the
    first time it is read. Tiles not written read as zero (``open_plate(complete=False)``)."""

    def __init__(self, store: PlateStore):
        self.store = store
        self.shape = (store.count, *store.shape)
        self.ndim, self.dtype = 3, np.dtype(np.complex64)
        self._written = store.written()

    def __len__(self) -> int:
        return self.shape[0]

    def __array__(self, dtype=None, copy=None):
        a = self[...]
        return a if dtype is None else a.astype(dtype)

    def __getitem__(self, key) -> np.ndarray:
        axes = _axes(key, self.shape)
        (c0, c1), (r0, r1), (q0, q1) = (
            (int(a.min()), int(a.max()) + 1) if a.size else (0, 0) for a, _ in axes
        )
        box = self._box(c0, c1, r0, r1, q0, q1)
        rel = [a - lo for (a, _), lo in zip(axes, (c0, r0, q0))]
        out = box[np.ix_(*rel)]
        return out[tuple(0 if scalar else slice(None) for _, scalar in axes)]

    def _box(self, c0, c1, r0, r1, q0, q1) -> np.ndarray:
        out = np.zeros((c1 - c0, r1 - r0, q1 - q0), np.complex64)
        t = self.store.tile
        for c in range(c0, c1):
            for i in range(r0 // t, -(-r1 // t)):
                for j in range(q0 // t, -(-q1 // t)):
                    if not self._written[i, j]:
                        continue
                    tile = self.store.read_tile(c, i, j)
                    a, b = max(r0, i * t), min(r1, (i + 1) * t)
                    e, f = max(q0, j * t), min(q1, (j + 1) * t)
                    out[c - c0, a - r0 : b - r0, e - q0 : f - q0] = tile[
                        a - i * t : b - i * t, e - j * t : f - j * t
                    ]
        return out


def _axes(key, shape):
    """Each axis's indices (an array) and whether the key took it away (an integer)."""
    key = key if isinstance(key, tuple) else (key,)
    if any(k is Ellipsis for k in key):
        at = next(n for n, k in enumerate(key) if k is Ellipsis)
        key = key[:at] + (slice(None),) * (len(shape) - len(key) + 1) + key[at + 1 :]
    key = key + (slice(None),) * (len(shape) - len(key))
    if len(key) != len(shape):
        raise IndexError(f"too many indices for an array of {len(shape)} dimensions")
    axes = []
    for k, n in zip(key, shape):
        if isinstance(k, (int, np.integer)) and not isinstance(k, bool):
            if not -n <= k < n:
                raise IndexError(f"index {k} is out of bounds for an axis of size {n}")
            axes.append((np.array([k % n]), True))
        elif isinstance(k, slice):
            axes.append((np.arange(n)[k], False))
        else:
            raise IndexError(f"a tiled plate takes integers and slices; got {k!r}"[:200])
    return axes


def open_plate(url, *, complete=True) -> Hologram:
    """The tiled plate at ``url`` as a :class:`Hologram` whose ``object_wave`` reads and checks
    only the tiles an index touches (:class:`TiledWave`): nothing is read until a view reads
    the rows and columns it needs. The metadata and every tile's record are checked now.
    With ``complete``, :class:`StoreError` names the tiles still missing (a recording that
    did not finish: resume it) and those another recording wrote."""
    store = read_store(url)
    if store.bad:
        raise store.files.fail(next(iter(store.bad.values())))
    foreign = np.argwhere(store.foreign())
    if len(foreign):
        i, j = map(int, foreign[0])
        raise store.files.fail(
            f"tile ({i}, {j}) and {len(foreign) - 1} more were written by "
            f"another recording than the store's; resume the recording to "
            f"write them again"
        )
    missing = np.argwhere(~store.written())
    if complete and len(missing):
        i, j = map(int, missing[0])
        raise store.files.fail(
            f"{len(missing)} of {store.written().size} tiles are not "
            f"written yet (tile ({i}, {j}) first); resume the recording "
            f"(the same call again)"
        )
    return Hologram(info=store.info, object_wave=TiledWave(store))


def tiles_done(url) -> np.ndarray:
    """The flags (rows of tiles, columns of tiles) of the tiles whose record names the store's
    recording (their chunks are checked when read)."""
    return read_store(url).written()
