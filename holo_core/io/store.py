"""Plates in tiles: a Zarr (v3) group on a local path or any fsspec URL, for plates beyond memory.

The group (store format 2) holds what an EXR hologram file holds, in chunks:

``attributes`` of the group
    ``holo``: the same metadata, in the same schema, as the EXR's ``holo`` header
    (:func:`holo_core.io.hologram.metadata`), checked by the same reader; ``tile``: samples
    per tile side; ``store_format``; ``recording``: the digest of the scene it holds (its
    emitters' positions, colours and phases, the method and the sampling) and its parts, so
    that only the same recording resumes into it;
``object_wave`` (C, H, W) complex64
    the complex plate's samples, one chunk per tile and channel (uncompressed, little-endian,
    an edge tile padded with zeros as Zarr pads it), dimension names ``(channel, y, x)``:
    ``dask.array.from_zarr(url, component="object_wave")``, xarray and napari open it as it
    is;
``tiles_done`` (rows of tiles, columns of tiles, 1 + C) uint64
    a tile's record, one chunk per tile: the recording's id (the digest's first 8 bytes), then
    a checksum (BLAKE2b, 8 bytes) of each of its channel's chunks, written after all of them.
    A tile counts as written when its record names the store's recording and its chunks match
    their checksums; a recording killed inside a tile leaves no record, so resuming writes it
    again, and damage found later is named on reading and written again on resuming.
``holo.lock``
    not Zarr's: the lock a recording holds while it writes (its host, process and start).

Nothing in a store is trusted. Its files are read and written through
:class:`~holo_core.io.files.Files` (never following a link; a chunk read only when its file has
exactly a chunk's size, a ``zarr.json`` only up to ``MAX_JSON`` bytes); the arrays' metadata is
checked against the plate's; every damage is a
:class:`~holo_core.io.hologram.HologramFileError` naming the store and, for a chunk, the tile.
Chunks and records are written by this module, the metadata by Zarr; the keys and digests are
:mod:`holo_core.io.digests`', the lock :mod:`holo_core.io.store_lock`'s, the lazy reading of a
plate :mod:`holo_core.io.tiled_wave`'s.
"""

from __future__ import annotations

import json
import logging
import math
from contextlib import contextmanager

import numpy as np

from ..scene.hologram import HologramInfo
from ..validate import InputError
from .digests import DONE, WAVE, chunk_sum, record_id, record_key, wave_key
from .files import LOCK, Files, StoreError
from .hologram import HologramFileError, info_of, metadata
from .image import check_room
from .store_lock import locked

log = logging.getLogger(__name__)

MIN_TILE, MAX_TILE = 64, 16384
STORE_FORMAT = 2
SAMPLE = np.dtype("<c8")
RECORD = np.dtype("<u8")


def tile_grid(shape, tile) -> tuple[int, int]:
    """(rows, columns) of ``tile``-sized tiles that cover a plate of ``shape`` (rows, cols)."""
    return math.ceil(shape[0] / tile), math.ceil(shape[1] / tile)


def tile_window(shape, tile, i, j) -> tuple[int, int, int, int]:
    """(row0, row1, col0, col1) of tile (i, j); the last row and column of tiles may be
    smaller."""
    return i * tile, min((i + 1) * tile, shape[0]), j * tile, min((j + 1) * tile, shape[1])


def _zarr():
    try:
        import zarr
    except ImportError:  # an optional dependency: say how to get it
        raise HologramFileError("tiled plates need zarr: pip install 'holo[tiles]'") from None
    return zarr


def _array_meta(shape, chunks, dtype, fill, names) -> dict:
    """The fields of an array's zarr.json this module relies on."""
    return {
        "zarr_format": 3,
        "node_type": "array",
        "shape": list(shape),
        "data_type": dtype,
        "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": list(chunks)}},
        "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
        "fill_value": fill,
        "codecs": [{"name": "bytes", "configuration": {"endian": "little"}}],
        "dimension_names": list(names),
    }


def _expected_arrays(shape, count, tile) -> dict:
    rows, cols = tile_grid(shape, tile)
    return {
        WAVE: _array_meta(
            (count, *shape), (1, tile, tile), "complex64", [0.0, 0.0], ("channel", "y", "x")
        ),
        DONE: _array_meta(
            (rows, cols, 1 + count),
            (1, 1, 1 + count),
            "uint64",
            0,
            ("tile_row", "tile_col", "record"),
        ),
    }


class PlateStore:
    """A checked tiled store: its files, the plate's description, tile size, recording and
    tiles' records."""

    def __init__(
        self, files: Files, info: HologramInfo, tile: int, recording: dict, records, bad=None
    ):
        self.files, self.info, self.tile, self.recording = files, info, tile, recording
        self.records = records  # (rows, cols, 1 + C) uint64; 0: no record
        self.bad = bad or {}  # (i, j): why a tile's record cannot be read
        self.shape = info.shape
        self.count = len(info.wavelengths)

    @property
    def chunk_bytes(self) -> int:
        return SAMPLE.itemsize * self.tile * self.tile

    def written(self) -> np.ndarray:
        """The tiles whose record names this store's recording (their chunks not yet read)."""
        return self.records[..., 0] == record_id(self.recording)

    def foreign(self) -> np.ndarray:
        """The tiles whose record names another recording (a task of an earlier one)."""
        return (self.records[..., 0] != 0) & ~self.written()

    def read_tile(self, c, i, j) -> np.ndarray:
        """Channel ``c`` of tile (i, j), (tile, tile) complex64, checked against its record."""
        key = wave_key(c, i, j)
        data = self.files.read(key, size=self.chunk_bytes)
        if data is None:
            raise self.files.fail(
                f"tile ({i}, {j}) channel {c}: its samples are missing "
                f"though its record says written",
                key,
            )
        if chunk_sum(data) != int(self.records[i, j, 1 + c]):
            raise self.files.fail(
                f"tile ({i}, {j}) channel {c}: its samples do not match "
                f"their checksum (damaged or written by another "
                f"recording); resume the recording to write it again",
                key,
            )
        return np.frombuffer(data, SAMPLE).reshape(self.tile, self.tile)

    def damaged(self, i, j) -> str | None:
        """Why tile (i, j) of this recording cannot be read back, or None."""
        try:
            for c in range(self.count):
                self.read_tile(c, i, j)
        except StoreError as e:
            return str(e)
        return None

    def write_tile(self, i, j, samples) -> None:
        """Tile (i, j)'s samples (C, rows, cols) complex, each channel's chunk, then its
        record (the recording's id and the chunks' checksums), each file whole."""
        sums = [record_id(self.recording)]
        for c in range(self.count):
            chunk = np.zeros((self.tile, self.tile), SAMPLE)
            chunk[: samples.shape[1], : samples.shape[2]] = samples[c]
            data = chunk.tobytes()
            self.files.write(wave_key(c, i, j), data, what=f"tile ({i}, {j}) ")
            sums.append(chunk_sum(data))
        self.files.write(
            record_key(i, j), np.array(sums, RECORD).tobytes(), what=f"tile ({i}, {j})'s record "
        )


def read_store(url, *, files: Files | None = None, records=True) -> PlateStore:
    """The tiled store at ``url``, every part of its metadata and (with ``records``; a task
    writing one tile reads none) every tile's record checked (:class:`StoreError` naming the
    store, the file and the problem), after the local store's tree (no link, device or FIFO
    in it); no chunk is read."""
    files = files or Files(url)
    if not files.exists():
        raise files.fail("not a tiled plate (nothing is there)")
    if records:
        files.check_tree()
    group = files.json("zarr.json")
    attrs = group.get("attributes")
    if group.get("node_type") != "group" or not isinstance(attrs, dict) or "holo" not in attrs:
        raise files.fail("not a tiled plate (a Zarr group without hologram metadata)", "zarr.json")
    info = info_of(files.name, json.dumps(attrs["holo"]))
    tile, recording = attrs.get("tile"), attrs.get("recording")
    if attrs.get("store_format") != STORE_FORMAT:
        raise files.fail(
            f"store format {attrs.get('store_format')!r}; this reader reads "
            f"format {STORE_FORMAT} (record the plate again)"[:300],
            "zarr.json",
        )
    if isinstance(tile, bool) or not isinstance(tile, int) or not MIN_TILE <= tile <= MAX_TILE:
        raise files.fail(
            f"tile must be an integer in [{MIN_TILE}, {MAX_TILE}]; got {tile!r}"[:200], "zarr.json"
        )
    if (
        not isinstance(recording, dict)
        or not isinstance(recording.get("digest"), str)
        or len(recording["digest"]) != 64
        or any(ch not in "0123456789abcdef" for ch in recording["digest"])
    ):
        raise files.fail("damaged metadata: recording must name the scene's digest", "zarr.json")
    if info.encoding != "complex":
        raise files.fail(
            f"a tiled plate is complex; it says encoding {info.encoding!r}", "zarr.json"
        )
    shape, count = info.shape, len(info.wavelengths)
    for name, expected in _expected_arrays(shape, count, tile).items():
        key = f"{name}/zarr.json"
        found = files.json(key)
        for field, value in expected.items():
            if found.get(field) != value:
                raise files.fail(
                    f"{name}'s {field} is {found.get(field)!r}; the plate's is {value!r}"[:300], key
                )
        if found.get("storage_transformers", []) != []:
            raise files.fail(f"{name} has storage transformers; it has none", key)
    table = np.zeros((*tile_grid(shape, tile), 1 + count), np.uint64)
    bad = {}
    for i, j in np.ndindex(*table.shape[:2]) if records else ():
        try:
            data = files.read(record_key(i, j), size=RECORD.itemsize * (1 + count))
        except StoreError as e:  # a damaged record: the tile counts as not written
            bad[i, j] = f"tile ({i}, {j})'s record {str(e).split(': ', 1)[-1]}"
            continue
        if data is not None:
            table[i, j] = np.frombuffer(data, RECORD)
    return PlateStore(files, info, tile, recording, table, bad)


# --- making, resuming and locking a store -----------------------------------------------------


def create_plate(files: Files, info: HologramInfo, tile: int, recording: dict) -> PlateStore:
    """A new store at ``files`` (empty or absent) for the complex plate ``info`` describes,
    recording ``recording``."""
    zarr = _zarr()
    shape, count = info.shape, len(info.wavelengths)
    try:
        files.make_folders("", WAVE, DONE)  # Zarr puts its metadata there, as into a bucket
        group = zarr.open_group(store=files.url, mode="a")
        group.create_array(
            WAVE,
            shape=(count, *shape),
            chunks=(1, tile, tile),
            dtype="complex64",
            fill_value=0,
            compressors=None,
            dimension_names=("channel", "y", "x"),
        )
        group.create_array(
            DONE,
            shape=(*tile_grid(shape, tile), 1 + count),
            chunks=(1, 1, 1 + count),
            dtype="uint64",
            fill_value=0,
            compressors=None,
            dimension_names=("tile_row", "tile_col", "record"),
        )
        # last: a group without them is not a plate (and is removed by the call that made it)
        group.attrs.update(
            {
                "holo": metadata(info),
                "tile": tile,
                "store_format": STORE_FORMAT,
                "recording": recording,
            }
        )
    except OSError as e:  # a full disk, a lost share: said as the store, not as Zarr's file
        raise files.fail(f"its metadata cannot be written ({e.strerror or e})") from None
    return read_store(files.name, files=files)


def same_plate(store: PlateStore, info: HologramInfo, tile: int, recording: dict) -> str | None:
    """What differs between the plate in ``store`` and the one a call would record, in the
    user's terms, or None."""
    theirs, ours = store.recording, recording
    if theirs["digest"] != ours["digest"]:
        parts = sorted(
            k
            for k in set(theirs.get("parts", {})) | set(ours["parts"])
            if theirs.get("parts", {}).get(k) != ours["parts"].get(k)
        )
        return (
            f"its {', '.join(parts) or 'scene'} differ: the store holds recording "
            f"{theirs['digest'][:12]} ({_describe(theirs)}), this call is recording "
            f"{ours['digest'][:12]} ({_describe(ours)})"
        )
    ours, theirs = (json.loads(json.dumps(metadata(i))) for i in (info, store.info))
    keys = sorted(k for k in set(ours) | set(theirs) if ours.get(k) != theirs.get(k))
    if keys or store.tile != tile:
        return (
            f"its {', '.join(keys + (['tile'] if store.tile != tile else []))} differ "
            f"from this call's"
        )
    return None


def _describe(recording: dict) -> str:
    parts = recording.get("parts", {})
    return ", ".join(f"{k} {parts[k]}" for k in ("emitters", "seed", "method") if k in parts)


@contextmanager
def recording_into(
    files: Files, info: HologramInfo, tile: int, recording: dict, *, overwrite=False
):
    """The store a recording writes, locked for it while the block runs: a new one, or the
    existing one of the same recording (resumed), or with ``overwrite`` a new one in place of
    another recording's Holo store. Never another program's data: a folder or Zarr group that
    is not a Holo store is refused, even with ``overwrite``. If the block fails before a tile
    was written into a store this call made, the store is removed again: a recording that
    never started leaves nothing behind.

    The store is judged under its lock: a recording that finds another writing it is told so
    (never that the half-made store is another program's, to be removed). Resuming removes
    the temporary files of writers killed inside a chunk, and checks the disk's room for the
    tiles still to write before any is."""
    folder = files.exists()
    with locked(files, recording) as made_lock:
        try:
            if not files.is_empty():
                files.check_tree()
                _check_holo(files)
        except StoreError:
            if made_lock:  # nothing of ours is left in what is not a Holo store
                _remove_folder(files, folder)
            raise
        store, made = _open_or_make(files, info, tile, recording, overwrite)
        if not made:
            removed = files.remove_dead_temporaries()
            if removed:
                log.info(
                    "%s: removed %d temporary file(s) of writers that died inside a write",
                    files.name,
                    removed,
                )
        try:
            _check_room(store)
            yield store
        except BaseException:
            if made and _nothing_written(files):
                files.remove_all()
                _remove_folder(files, folder)
            raise


def _check_room(store: PlateStore) -> None:
    """:class:`StoreError` naming the store unless its disk holds the tiles still to write
    (a store at a URL: its service says, when it is full)."""
    if store.files.local is None:
        return
    missing = int((~store.written()).sum())
    need = missing * (store.count * store.chunk_bytes + RECORD.itemsize * (1 + store.count))
    try:
        check_room([store.files.local / WAVE], need, f"the {missing} tiles still to write")
    except InputError as e:
        raise store.files.fail(str(e)) from None


def _nothing_written(files: Files) -> bool:
    try:
        return not read_store(files.name, files=files).written().any()
    except StoreError:
        return False  # damaged meanwhile: left as it is, for a look


def _check_holo(files: Files) -> None:
    """Refuse what is not known to be a Holo store (another program's folder or Zarr group,
    or one whose group metadata cannot be read): it is never written into."""
    try:
        group = files.json("zarr.json")
    except StoreError as e:
        raise files.fail(
            f"cannot be told to be a Holo plate ({str(e).split(': ', 1)[-1]}); "
            f"what is not known to be one is never written into: record to "
            f"another path, or remove it"
        ) from None
    attrs = group.get("attributes") if isinstance(group.get("attributes"), dict) else {}
    if "holo" not in attrs or "store_format" not in attrs:
        raise files.fail(
            "holds data that is not a Holo plate (no Holo store metadata); it is "
            "never written into: record to another path"
        )


def _open_or_make(files, info, tile, recording, overwrite):
    """(store, whether this call made it)."""
    if files.is_empty():
        return create_plate(files, info, tile, recording), True
    _check_holo(files)
    if overwrite:
        files.remove_all()
        return create_plate(files, info, tile, recording), True
    store = read_store(files.name, files=files)
    differs = same_plate(store, info, tile, recording)
    if differs:
        raise files.fail(
            f"holds another recording ({differs}); record to a new path, or "
            f"replace it (overwrite=True, --overwrite)"
        )
    return store, False


def _remove_folder(files: Files, existed: bool) -> None:
    """Remove the lock of a store this call made, and its folder when the call made that."""
    if files.local is None:
        return
    (files.local / LOCK).unlink(missing_ok=True)
    if not existed:
        try:
            files.local.rmdir()
        except OSError:  # something else arrived meanwhile: left as it is
            pass
