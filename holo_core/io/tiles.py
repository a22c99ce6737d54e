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

Nothing in a store is trusted. Reading never follows a link (a symbolic link, a device or a
FIFO anywhere inside a local store is refused before anything is read), reads a chunk only
when its file has exactly a chunk's size, a ``zarr.json`` only up to ``MAX_JSON`` bytes, and
checks the arrays' metadata against the plate's; every damage is a
:class:`~holo_core.io.hologram.HologramFileError` naming the store and, for a chunk, the tile.
Chunks and records are written by this module (a file's bytes, renamed into place on a local
path, so a rename replaces a planted link instead of following it), the metadata by Zarr.
"""

from __future__ import annotations

import errno
import hashlib
import itertools
import json
import math
import os
import shutil
import socket
import stat
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..scene.hologram import Hologram, HologramInfo
from .hologram import HologramFileError, info_of, metadata, read_hologram

WAVE, DONE, LOCK = "object_wave", "tiles_done", "holo.lock"
MIN_TILE, MAX_TILE = 64, 16384
STORE_FORMAT = 2
MAX_JSON = 2**20        # bytes of a zarr.json: the metadata is a few kB
SAMPLE = np.dtype("<c8")
RECORD = np.dtype("<u8")
_count = itertools.count()


class StoreError(HologramFileError):
    """A tiled store that cannot be used: missing, damaged, hostile, another plate's or
    another program's; the message names the store (and the tile)."""


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


# --- where a store lives: its files, read and written without following links --------------

class Files:
    """The files of the store at ``url``: a local folder (a path, or ``file://``) or an fsspec
    URL. Keys are '/'-separated paths inside it."""

    def __init__(self, url):
        text = str(url)
        self.name = text
        if text.startswith("file://"):
            text = text[len("file://"):]
        if "://" in text:
            self.fs, self.root = _filesystem(text)
            self.local = None
        else:
            self.fs, self.root = None, text
            self.local = Path(os.path.abspath(text))

    @property
    def url(self) -> str:
        """The store's address as workers elsewhere reach it: an absolute path, or the URL."""
        return str(self.local) if self.local is not None else self.name

    def fail(self, problem, key=None) -> StoreError:
        where = f" ({key})" if key else ""
        return StoreError(f"{self.name}{where}: {problem}")

    def exists(self) -> bool:
        if self.local is not None:
            return os.path.lexists(self.local)
        return self.fs.exists(self.root)

    def is_empty(self) -> bool:
        """Whether nothing but our lock is there (a folder made for the store)."""
        if self.local is not None:
            return not os.path.lexists(self.local) or (
                self.local.is_dir() and set(os.listdir(self.local)) <= {LOCK})
        try:
            listed = self.fs.ls(self.root, detail=False)
        except FileNotFoundError:
            return True
        return {p.rstrip("/").rsplit("/", 1)[-1] for p in listed} <= {LOCK}

    def check_tree(self) -> None:
        """Refuse a local store holding anything but folders and regular files (a symbolic
        link, a device, a FIFO, a socket), before any of it is read."""
        if self.local is None:
            return
        if not self.local.is_dir():
            raise self.fail("not a tiled plate (not a folder)")
        for folder, dirs, files in os.walk(self.local):  # os.walk never follows links
            for name in dirs + files:
                path = os.path.join(folder, name)
                try:
                    kind = _kind(os.lstat(path).st_mode)
                except FileNotFoundError:  # gone since the listing: a recording's temporary
                    continue               # file renamed into place (nothing left to refuse)
                if kind not in ("a folder", "a regular file"):
                    raise self.fail(f"holds {kind} {os.path.relpath(path, self.local)}: a store "
                                    f"holds only folders and regular files, and none is read")

    def read(self, key, *, size=None, limit=None) -> bytes | None:
        """The bytes of ``key``, None when it is missing: refused unless it is a regular file
        of exactly ``size`` bytes (or at most ``limit``); a link is never followed."""
        if self.local is not None:
            return self._read_local(key, size, limit)
        path = f"{self.root.rstrip('/')}/{key}"
        try:
            info = self.fs.info(path)
        except FileNotFoundError:
            return None
        if info.get("type") != "file":
            raise self.fail(f"is a {info.get('type')}, not a file", key)
        self._check_size(key, int(info.get("size") or 0), size, limit)
        data = self.fs.cat_file(path)
        self._check_size(key, len(data), size, limit)
        return data

    def _read_local(self, key, size, limit) -> bytes | None:
        path = self.local / key
        try:
            fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_NOCTTY)
        except FileNotFoundError:
            return None
        except NotADirectoryError:
            raise self.fail("a folder of it is a file", key) from None
        except OSError as e:
            if e.errno == errno.ELOOP:
                raise self.fail("is a symbolic link; a store's files are read, never "
                                "followed", key) from None
            raise self.fail(f"cannot be read ({e.strerror})", key) from None
        try:
            st = os.fstat(fd)
            if not stat.S_ISREG(st.st_mode):
                raise self.fail(f"is {_kind(st.st_mode)}, not a regular file", key)
            self._check_size(key, st.st_size, size, limit)
            with os.fdopen(fd, "rb", closefd=False) as f:
                data = f.read(st.st_size + 1)
        finally:
            os.close(fd)
        self._check_size(key, len(data), size, limit)
        return data

    def _check_size(self, key, actual, size, limit) -> None:
        if size is not None and actual != size:
            raise self.fail(f"holds {actual} bytes; it must hold {size}", key)
        if limit is not None and actual > limit:
            raise self.fail(f"holds {actual} bytes, more than the {limit} it may", key)

    def write(self, key, data: bytes) -> None:
        """``data`` as ``key``: on a local path a temporary file renamed into place (a rename
        replaces a link there, never writes through it)."""
        if self.local is None:
            self.fs.pipe_file(f"{self.root.rstrip('/')}/{key}", data)
            return
        path = self.local / key
        if path.is_dir() and not path.is_symlink():
            raise self.fail("is a folder where a file belongs; remove it", key)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{socket.gethostname()}.{os.getpid()}."
                             f"{next(_count)}.tmp")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW, 0o666)
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            os.replace(tmp, path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise

    def json(self, key) -> dict:
        """A ``zarr.json`` document: a JSON object of at most MAX_JSON bytes."""
        data = self.read(key, limit=MAX_JSON)
        if data is None:
            raise self.fail("not a tiled plate (it is missing)", key)
        try:
            doc = json.loads(data.decode("utf-8"))
        except (UnicodeDecodeError, ValueError, RecursionError) as e:
            raise self.fail(f"damaged metadata ({type(e).__name__}: {e})"[:300], key) from None
        if not isinstance(doc, dict):
            raise self.fail("damaged metadata (not a JSON object)", key)
        return doc

    def remove_all(self) -> None:
        """Remove the store's contents but the lock (a store this call made, or one the
        caller asked to replace)."""
        if self.local is None:
            for path in self.fs.ls(self.root, detail=False):
                if not str(path).rstrip("/").endswith(LOCK):
                    self.fs.rm(path, recursive=True)
            return
        for entry in os.scandir(self.local):
            if entry.name == LOCK:
                continue
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path)
            else:
                os.unlink(entry.path)


def _kind(mode) -> str:
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISREG, "a regular file"),
                       (stat.S_ISLNK, "a symbolic link"), (stat.S_ISFIFO, "a FIFO"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "an unknown kind of file"


def _filesystem(url):
    try:
        import fsspec
        return fsspec.core.url_to_fs(url)
    except ImportError as e:  # the protocol's own package (s3fs, gcsfs, ...) is missing
        raise StoreError(f"{url}: its protocol needs a package that is not installed "
                         f"({e})"[:400]) from None
    except (ValueError, KeyError) as e:
        raise StoreError(f"{url}: not a store address fsspec knows ({e})"[:400]) from None


def check_output(url) -> Files:
    """The store ``url`` a recording will write, checked before the work: a path (made
    absolute, since workers elsewhere resolve a relative one in their own folder) whose folder
    takes new files, or a URL whose protocol is installed and reachable from other processes
    (not ``memory://``, which lives in one process). :class:`StoreError` naming it."""
    from .image import check_writable
    files = Files(url)
    if files.local is None:
        if files.name.split("://", 1)[0] == "memory":
            raise files.fail("a memory:// store lives in one process; the recording's "
                             "workers cannot reach it: record to a path or a shared URL")
        return files
    if os.path.lexists(files.local) and not files.local.is_dir():
        raise files.fail("is a file, not a store folder: record to another path")
    try:
        check_writable(files.local / "zarr.json")
    except HologramFileError:
        raise
    except ValueError as e:
        raise files.fail(str(e).split(": ", 1)[-1]) from None
    return files


# --- what a store holds, and its metadata -----------------------------------------------------

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


def _array_meta(shape, chunks, dtype, fill, names) -> dict:
    """The fields of an array's zarr.json this module relies on."""
    return {"zarr_format": 3, "node_type": "array", "shape": list(shape), "data_type": dtype,
            "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": list(chunks)}},
            "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
            "fill_value": fill, "codecs": [{"name": "bytes",
                                            "configuration": {"endian": "little"}}],
            "dimension_names": list(names)}


def _expected_arrays(shape, count, tile) -> dict:
    rows, cols = tile_grid(shape, tile)
    return {WAVE: _array_meta((count, *shape), (1, tile, tile), "complex64", [0.0, 0.0],
                              ("channel", "y", "x")),
            DONE: _array_meta((rows, cols, 1 + count), (1, 1, 1 + count), "uint64", 0,
                              ("tile_row", "tile_col", "record"))}


class PlateStore:
    """A checked tiled store: its files, the plate's description, tile size, recording and
    tiles' records."""

    def __init__(self, files: Files, info: HologramInfo, tile: int, recording: dict, records,
                 bad=None):
        self.files, self.info, self.tile, self.recording = files, info, tile, recording
        self.records = records  # (rows, cols, 1 + C) uint64; 0: no record
        self.bad = bad or {}    # (i, j): why a tile's record cannot be read
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
            raise self.files.fail(f"tile ({i}, {j}) channel {c}: its samples are missing "
                                  f"though its record says written", key)
        if chunk_sum(data) != int(self.records[i, j, 1 + c]):
            raise self.files.fail(f"tile ({i}, {j}) channel {c}: its samples do not match "
                                  f"their checksum (damaged or written by another "
                                  f"recording); resume the recording to write it again", key)
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
            chunk[:samples.shape[1], :samples.shape[2]] = samples[c]
            data = chunk.tobytes()
            self.files.write(wave_key(c, i, j), data)
            sums.append(chunk_sum(data))
        self.files.write(record_key(i, j), np.array(sums, RECORD).tobytes())


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
        raise files.fail("not a tiled plate (a Zarr group without hologram metadata)",
                         "zarr.json")
    info = info_of(files.name, json.dumps(attrs["holo"]))
    tile, recording = attrs.get("tile"), attrs.get("recording")
    if attrs.get("store_format") != STORE_FORMAT:
        raise files.fail(f"store format {attrs.get('store_format')!r}; this reader reads "
                         f"format {STORE_FORMAT} (record the plate again)"[:300], "zarr.json")
    if isinstance(tile, bool) or not isinstance(tile, int) or not MIN_TILE <= tile <= MAX_TILE:
        raise files.fail(f"tile must be an integer in [{MIN_TILE}, {MAX_TILE}]; got "
                         f"{tile!r}"[:200], "zarr.json")
    if not isinstance(recording, dict) or not isinstance(recording.get("digest"), str) or \
            len(recording["digest"]) != 64 or \
            any(ch not in "0123456789abcdef" for ch in recording["digest"]):
        raise files.fail("damaged metadata: recording must name the scene's digest",
                         "zarr.json")
    if info.encoding != "complex":
        raise files.fail(f"a tiled plate is complex; it says encoding {info.encoding!r}",
                         "zarr.json")
    shape, count = info.shape, len(info.wavelengths)
    for name, expected in _expected_arrays(shape, count, tile).items():
        key = f"{name}/zarr.json"
        found = files.json(key)
        for field, value in expected.items():
            if found.get(field) != value:
                raise files.fail(f"{name}'s {field} is {found.get(field)!r}; the plate's is "
                                 f"{value!r}"[:300], key)
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
    group = zarr.open_group(store=files.url, mode="a")
    group.create_array(WAVE, shape=(count, *shape), chunks=(1, tile, tile), dtype="complex64",
                       fill_value=0, compressors=None, dimension_names=("channel", "y", "x"))
    group.create_array(DONE, shape=(*tile_grid(shape, tile), 1 + count),
                       chunks=(1, 1, 1 + count), dtype="uint64", fill_value=0,
                       compressors=None, dimension_names=("tile_row", "tile_col", "record"))
    # last: a group without them is not a plate (and is removed by the call that made it)
    group.attrs.update({"holo": metadata(info), "tile": tile, "store_format": STORE_FORMAT,
                        "recording": recording})
    return read_store(files.name, files=files)


def same_plate(store: PlateStore, info: HologramInfo, tile: int, recording: dict) -> str | None:
    """What differs between the plate in ``store`` and the one a call would record, in the
    user's terms, or None."""
    theirs, ours = store.recording, recording
    if theirs["digest"] != ours["digest"]:
        parts = sorted(k for k in set(theirs.get("parts", {})) | set(ours["parts"])
                       if theirs.get("parts", {}).get(k) != ours["parts"].get(k))
        return (f"its {', '.join(parts) or 'scene'} differ: the store holds recording "
                f"{theirs['digest'][:12]} ({_describe(theirs)}), this call is recording "
                f"{ours['digest'][:12]} ({_describe(ours)})")
    ours, theirs = (json.loads(json.dumps(metadata(i))) for i in (info, store.info))
    keys = sorted(k for k in set(ours) | set(theirs) if ours.get(k) != theirs.get(k))
    if keys or store.tile != tile:
        return (f"its {', '.join(keys + (['tile'] if store.tile != tile else []))} differ "
                f"from this call's")
    return None


def _describe(recording: dict) -> str:
    parts = recording.get("parts", {})
    return ", ".join(f"{k} {parts[k]}" for k in ("emitters", "seed", "method") if k in parts)


@contextmanager
def recording_into(files: Files, info: HologramInfo, tile: int, recording: dict, *,
                   overwrite=False):
    """The store a recording writes, locked for it while the block runs: a new one, or the
    existing one of the same recording (resumed), or with ``overwrite`` a new one in place of
    another recording's Holo store. Never another program's data: a folder or Zarr group that
    is not a Holo store is refused, even with ``overwrite``. If the block fails before a tile
    was written into a store this call made, the store is removed again: a recording that
    never started leaves nothing behind."""
    folder = files.exists()
    existed = folder and not files.is_empty()
    if existed:  # before the lock: the lock file is ours to add
        files.check_tree()
        _check_holo(files)
    with _locked(files, recording):
        store, made = _open_or_make(files, info, tile, recording, overwrite)
        try:
            yield store
        except BaseException:
            if made and _nothing_written(files):
                files.remove_all()
                _remove_folder(files, folder)
            raise


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
        raise files.fail(f"cannot be told to be a Holo plate ({str(e).split(': ', 1)[-1]}); "
                         f"what is not known to be one is never written into: record to "
                         f"another path, or remove it") from None
    attrs = group.get("attributes") if isinstance(group.get("attributes"), dict) else {}
    if "holo" not in attrs or "store_format" not in attrs:
        raise files.fail("holds data that is not a Holo plate (no Holo store metadata); it is "
                         "never written into: record to another path")


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
        raise files.fail(f"holds another recording ({differs}); record to a new path, or "
                         f"replace it (overwrite=True, --overwrite)")
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


@contextmanager
def _locked(files: Files, recording: dict):
    """Hold the store's lock for one recording. On a local path: an exclusive ``flock`` on
    ``holo.lock`` (which names its holder), released by the system when the holder ends, even
    killed: a lock whose holder died is free, with no stale lock to remove. On a URL (no
    shared locks there): ``holo.lock`` is created when absent and removed at the end; one left
    by a killed recording is refused by name, to be removed by hand once that recording is
    known to have stopped."""
    holder = json.dumps({"host": socket.gethostname(), "pid": os.getpid(),
                         "since": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                         "recording": recording["digest"][:12]})
    if files.local is None:
        found = files.read(LOCK, limit=MAX_JSON)
        if found is not None:
            raise files.fail(f"another recording holds its lock ({_holder(found)}); if that "
                             f"one is not running, remove {files.name}/{LOCK}", LOCK)
        files.write(LOCK, holder.encode())
        try:
            yield
        finally:
            files.fs.rm(f"{files.root.rstrip('/')}/{LOCK}")
        return
    import fcntl
    files.local.mkdir(parents=True, exist_ok=True)
    fd = os.open(files.local / LOCK, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o666)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder_now = _holder(os.pread(fd, MAX_JSON, 0))
            raise files.fail(f"another recording is writing it ({holder_now}); wait for it "
                             f"to end, or stop it", LOCK) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, holder.encode(), 0)
        try:
            yield
        finally:
            os.ftruncate(fd, 0)  # free: no holder named
    finally:
        os.close(fd)  # releases the flock


def _holder(data: bytes) -> str:
    try:
        h = json.loads(data.decode("utf-8"))
        return (f"host {h['host']}, process {h['pid']}, since {h['since']}, recording "
                f"{h['recording']}")[:200]
    except (ValueError, KeyError, TypeError, UnicodeDecodeError, RecursionError):
        return "its holder unreadable"


# --- reading a plate --------------------------------------------------------------------------

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
        (c0, c1), (r0, r1), (q0, q1) = ((int(a.min()), int(a.max()) + 1) if a.size else (0, 0)
                                         for a, _ in axes)
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
                    out[c - c0, a - r0:b - r0, e - q0:f - q0] = \
                        tile[a - i * t:b - i * t, e - j * t:f - j * t]
        return out


def _axes(key, shape):
    """Each axis's indices (an array) and whether the key took it away (an integer)."""
    key = key if isinstance(key, tuple) else (key,)
    if any(k is Ellipsis for k in key):
        at = next(n for n, k in enumerate(key) if k is Ellipsis)
        key = key[:at] + (slice(None),) * (len(shape) - len(key) + 1) + key[at + 1:]
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
        raise store.files.fail(f"tile ({i}, {j}) and {len(foreign) - 1} more were written by "
                               f"another recording than the store's; resume the recording to "
                               f"write them again")
    missing = np.argwhere(~store.written())
    if complete and len(missing):
        i, j = map(int, missing[0])
        raise store.files.fail(f"{len(missing)} of {store.written().size} tiles are not "
                               f"written yet (tile ({i}, {j}) first); resume the recording "
                               f"(the same call again)")
    return Hologram(info=store.info, object_wave=TiledWave(store))


def tiles_done(url) -> np.ndarray:
    """The flags (rows of tiles, columns of tiles) of the tiles whose record names the store's
    recording (their chunks are checked when read)."""
    return read_store(url).written()


def store_of(path) -> Path:
    """The tiled store that holds a plate file's samples when its plate is recorded tile by
    tile (:func:`holo_core.runner.needs_tiles`): NAME.zarr beside NAME.exr."""
    return Path(path).with_suffix(".zarr")


def read_plate(path) -> Hologram:
    """The hologram file at ``path``, or the complete tiled store beside it
    (:func:`store_of`)."""
    found = plate_files(path)
    return open_plate(str(found)) if found.suffix == ".zarr" else read_hologram(found)


def plate_files(path) -> Path:
    """Where the plate of file ``path`` is: the file, or the tiled store beside it when only
    that was written (:func:`store_of`)."""
    path = Path(path)
    return store_of(path) if not path.is_file() and store_of(path).is_dir() else path


def plate_current(path) -> bool:
    """Whether the plate file at ``path``, or the tiled store beside it, is there whole (a
    store's every tile written by its recording; a cancelled one resumes)."""
    path = Path(path)
    if path.is_file():
        return True
    if not store_of(path).is_dir():
        return False
    try:
        store = read_store(str(store_of(path)))
    except HologramFileError:  # a StoreError too
        return False
    return not store.bad and bool(store.written().all()) and not store.foreign().any()
