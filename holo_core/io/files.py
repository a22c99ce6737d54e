"""A store's files: a local folder or an fsspec URL, read and written without following links.

Reading never follows a link (a symbolic link, a device or a FIFO anywhere inside a local
store is refused before anything is read), reads a file only when it has exactly the size
asked for (or at most a limit); writing a local file renames a temporary file into place, so
that a rename replaces a planted link instead of writing through it.
"""

from __future__ import annotations

import errno
import itertools
import json
import os
import re
import shutil
import socket
import stat
import time
from pathlib import Path

from .hologram import HologramFileError
from .image import check_writable, process_alive

LOCK = "holo.lock"  # the recording lock's file (:mod:`holo_core.io.store_lock`)
MAX_JSON = 2**20  # bytes of a zarr.json: the metadata is a few kB
STALE_TEMPORARY = 3600  # [s] unchanged, another host's temporary file is a dead writer's
# a temporary file as Files.write names it: .NAME.HOST.PID.N.tmp (NAME and HOST may hold dots)
_TEMPORARY = re.compile(r"^\.(?P<name_host>.+)\.(?P<pid>\d+)\.\d+\.tmp$")
_count = itertools.count()


class StoreError(HologramFileError):
    """A tiled store that cannot be used: missing, damaged, hostile, another plate's or
    another program's; the message names the store (and the tile)."""


class Files:
    """The files of the store at ``url``: a local folder (a path, or ``file://``) or an fsspec
    URL. Keys are '/'-separated paths inside it."""

    def __init__(self, url):
        text = str(url)
        self.name = text
        if text.startswith("file://"):
            text = text[len("file://") :]
        if "://" in text:
            self.fs, self.root = _filesystem(text)
            self.local = None
            if {"file", "local"} & set(_protocols(self.fs)):  # local://: a local folder
                self.fs, self.local = None, Path(os.path.abspath(self.root))
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
                self.local.is_dir() and set(os.listdir(self.local)) <= {LOCK}
            )
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
                    continue  # file renamed into place (nothing left to refuse)
                if kind not in ("a folder", "a regular file"):
                    raise self.fail(
                        f"holds {kind} {os.path.relpath(path, self.local)}: a store "
                        f"holds only folders and regular files, and none is read"
                    )

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
                raise self.fail(
                    "is a symbolic link; a store's files are read, never followed", key
                ) from None
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

    def write(self, key, data: bytes, what: str = "") -> None:
        """``data`` as ``key``: on a local path a temporary file renamed into place (a rename
        replaces a link there, never writes through it). A write that fails (a full disk, a
        lost share) is :class:`StoreError` naming the store, ``what`` is written (a tile) and
        ``key``, never the temporary file."""
        try:
            self._write(key, data)
        except OSError as e:
            raise self.fail(f"{what}cannot be written ({e.strerror or e})", key) from None

    def _write(self, key, data: bytes) -> None:
        if self.local is None:
            self.make_folders(key.rpartition("/")[0])
            self.fs.pipe_file(f"{self.root.rstrip('/')}/{key}", data)
            return
        path = self.local / key
        if path.is_dir() and not path.is_symlink():
            raise self.fail("is a folder where a file belongs; remove it", key)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(
            f".{path.name}.{socket.gethostname()}.{os.getpid()}.{next(_count)}.tmp"
        )
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW, 0o666)
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            os.replace(tmp, path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise

    def make_folders(self, *keys) -> None:
        """Make the folders ``keys`` of a store at a URL whose file system has folders (one
        that has none, an object store, makes nothing): a file is put only into a folder that
        exists there, as on a local path."""
        if self.local is None:
            for key in keys:
                self.fs.makedirs(f"{self.root.rstrip('/')}/{key}".rstrip("/"), exist_ok=True)

    def remove_dead_temporaries(self) -> int:
        """Remove the temporary files of writers that died inside a write (a worker killed
        mid-chunk), and return how many: those of a process of this host that is gone, and
        those of another host unchanged for ``STALE_TEMPORARY`` seconds (a live writer's
        file grows as it writes). Called under the store's lock, when a recording resumes."""
        if self.local is None:
            return 0  # written whole by the file system's client: no temporary files
        host, now, removed = socket.gethostname(), time.time(), 0
        for folder, _, names in os.walk(self.local):
            for name in names:
                found = _TEMPORARY.match(name)
                if found is None:
                    continue
                path = os.path.join(folder, name)
                try:
                    if found["name_host"].endswith(f".{host}"):
                        dead = not process_alive(int(found["pid"]))
                    else:
                        dead = now - os.lstat(path).st_mtime > STALE_TEMPORARY
                    if dead:
                        os.unlink(path)
                        removed += 1
                except FileNotFoundError:  # renamed into place meanwhile
                    continue
        return removed

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
    for test, name in (
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISREG, "a regular file"),
        (stat.S_ISLNK, "a symbolic link"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "an unknown kind of file"


def _protocols(fs) -> tuple:
    protocol = getattr(fs, "protocol", ())
    return (protocol,) if isinstance(protocol, str) else tuple(protocol)


def _filesystem(url):
    try:
        import fsspec

        return fsspec.core.url_to_fs(url)
    except ImportError as e:  # the protocol's own package (s3fs, gcsfs, ...) is missing
        raise StoreError(
            f"{url}: its protocol needs a package that is not installed ({e})"[:400]
        ) from None
    except (ValueError, KeyError) as e:
        raise StoreError(f"{url}: not a store address fsspec knows ({e})"[:400]) from None


def check_output(url) -> Files:
    """The store ``url`` a recording will write, checked before the work: a path (made
    absolute, since workers elsewhere resolve a relative one in their own folder) whose folder
    takes new files, or a URL whose protocol is installed and reachable from other processes
    (not ``memory://``, which lives in one process) and whose file system answers now (its
    store folder made where it has folders). :class:`StoreError` naming it."""
    files = Files(url)
    if files.local is None:
        if files.name.split("://", 1)[0] == "memory":
            raise files.fail(
                "a memory:// store lives in one process; the recording's "
                "workers cannot reach it: record to a path or a shared URL"
            )
        try:
            files.make_folders("")
            files.fs.exists(files.root)
        except Exception as e:  # noqa: BLE001 -- each file system fails its own way
            raise files.fail(
                f"cannot be reached or written ({type(e).__name__}: {e})"[:300]
            ) from None
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
