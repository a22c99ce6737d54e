"""Image files a person can open, written atomically, and EXR files read with their size
checked before their pixels are.

A write goes to a temporary file beside the target (``.<name>.holo-tmp.<host>.<pid>.<n><suffix>``),
is flushed to disk, takes the target's permissions (a new file: 0666 less the umask, as
``open`` would) and is renamed onto the target. A target that is a symbolic link is replaced
by the new file, never written through: the file it points to stays as it was (in a shared
folder a planted link must not redirect a write). A failure, SIGINT or SIGTERM removes the
temporary file; one left by a writer that was killed outright is removed by the next write to
that folder.
"""

from __future__ import annotations

import errno
import fcntl
import itertools
import os
import shutil
import signal
import socket
import stat
import struct
import threading
import zlib
from contextlib import contextmanager, nullcontext
from pathlib import Path

import numpy as np

from .. import memory
from ..preview import srgb as srgb  # the one transfer curve, named here for the writers
from ..validate import InputError

TEMP_TAG = ".holo-tmp."
EXR_MAGIC = b"\x76\x2f\x31\x01"
_count = itertools.count()


class Terminated(SystemExit):
    """SIGTERM, raised as an exception while a write is open so that its file is removed."""


@contextmanager
def atomic_paths(*paths):
    """Temporary paths beside ``paths`` to write to; when the block succeeds all are renamed
    onto their targets together (under a lock on their folder, so two writers of the same
    set never leave a mixed pair), when it fails all are removed."""
    targets = [_target(p) for p in paths]
    temps = [
        t.parent / f".{t.stem}{TEMP_TAG}{_HOST}.{os.getpid()}.{next(_count)}{t.suffix}"
        for t in targets
    ]
    try:
        with _terminate_raises():
            for tmp, path in zip(temps, paths):
                _create(tmp, path)
            yield [str(t) for t in temps]
            modes = [_mode(t) for t in targets]
            for tmp, mode in zip(temps, modes):
                _flush(tmp, mode)
            with _folder_lock(targets[0].parent):
                for tmp, t in zip(temps, targets):
                    os.replace(tmp, t)
            _flush_folder(targets[0].parent)
    except BaseException as e:
        for tmp in temps:
            tmp.unlink(missing_ok=True)
        failed = _failed_write(e, temps, targets)
        if failed is not None:
            raise failed from None
        raise


def _failed_write(e: BaseException, temps, targets) -> InputError | None:
    """The project's error for a write into ``temps`` that failed (a full disk, a quota, a
    lost share), naming the target the user asked for, never the hidden temporary file; None
    for another failure (the caller's own error, a cancellation)."""
    named = [
        t
        for tmp, t in zip(temps, targets)
        if str(tmp) in str(e) or str(tmp) == getattr(e, "filename", None)
    ]
    disk = isinstance(e, OSError) and e.errno in (
        errno.ENOSPC,
        errno.EDQUOT,
        errno.EFBIG,
        errno.EROFS,
        errno.EIO,
    )
    if not named and not disk:
        return None
    why = e.strerror if isinstance(e, OSError) and e.strerror else str(e)
    for tmp, t in zip(temps, targets):
        why = why.replace(str(tmp), str(t))
    full = (
        " (the disk is full: free some room there, or write to another folder)"
        if "No space left" in why or (isinstance(e, OSError) and e.errno == errno.ENOSPC)
        else ""
    )
    return InputError(
        f"{', '.join(map(str, named or targets))}: cannot be written ({why.rstrip('.')}){full}"[
            :600
        ]
    )


@contextmanager
def atomic_path(path):
    """A temporary path beside ``path`` (same suffix) to write to; renamed onto ``path`` when
    the block succeeds, removed when it fails, so ``path`` is never left half-written."""
    with atomic_paths(path) as (tmp,):
        yield tmp


def write_atomic(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder, then rename."""
    with atomic_path(path) as tmp:
        Path(tmp).write_bytes(data)
    return Path(path)


def remove_stale_temps(folder) -> list[Path]:
    """Remove the temporary files in ``folder`` of this host's writers that are no longer
    running (killed with SIGKILL, or the machine went down); returns those removed."""
    removed = []
    for tmp in Path(folder).glob(f".*{TEMP_TAG}{_HOST}.*"):
        try:
            pid = int(tmp.name.split(TEMP_TAG, 1)[1].split(".")[1])
        except (IndexError, ValueError):
            continue
        if pid != os.getpid() and not process_alive(pid):
            tmp.unlink(missing_ok=True)
            removed.append(tmp)
    return removed


_HOST = socket.gethostname().split(".")[0] or "host"


def check_writable(path, suffix: str | None = None) -> Path:
    """:class:`InputError` unless a file can be written at ``path`` (ending in ``suffix``
    when given): it is not a folder, and its folder, or the nearest existing one above it,
    is a folder that takes a new file (tried with an empty temporary file, removed at once:
    permissions, read-only mounts and quotas answer alike). Call it before a long job, so
    that a bad output is found before the work, not after it."""
    path = Path(path)
    if suffix is not None and path.suffix.lower() != suffix:
        raise InputError(
            f"{path}: the file is written as {_FORMATS.get(suffix, suffix)}; name it *{suffix}"
        )
    if path.is_dir():
        raise InputError(f"{path}: is a folder; name the file to write")
    folder = _folder(path)
    existing = _existing(folder)
    if not existing.is_dir():
        raise InputError(f"{path}: cannot create its folder ({existing} is not a folder)")
    probe = existing / f".{path.stem}{TEMP_TAG}{_HOST}.{os.getpid()}.{next(_count)}.probe"
    try:
        with _terminate_raises():  # a SIGTERM now removes the probe too
            try:
                os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
            finally:
                probe.unlink(missing_ok=True)
    except OSError as e:
        raise InputError(f"{path}: its folder {existing} is not writable ({e.strerror})") from None
    return folder / path.name


def check_room(paths, nbytes: float, what: str) -> None:
    """:class:`InputError` where the disk that would hold some of ``paths`` (files or
    folders, made or not) has less free than ``nbytes`` [bytes] for each of them, naming
    what needs the room (``what``, its ``{n}`` the count of those files), the folder and both
    sizes. A file replaced is written beside its old version first (atomically), so the old
    one's room is not counted. Call it before a long job, with :func:`check_writable`."""
    folders = {}
    for path in paths:  # the files that share a folder need its room together
        folders.setdefault(_existing(_folder(Path(path))), []).append(path)
    for existing, held in folders.items():
        try:
            free = shutil.disk_usage(existing).free
        except OSError:  # a folder the system cannot measure: the write itself will say
            continue
        need = nbytes * len(held)
        if need > free:
            raise InputError(
                f"{what.format(n=len(held))} need {memory.gib(need)} on disk, and "
                f"{existing} has {memory.gib(free)} free: free some room there, or "
                f"write them to another folder"
            )


def _existing(folder: Path) -> Path:
    """``folder``, or the nearest folder above it that exists."""
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    return folder


_FORMATS = {".exr": "OpenEXR", ".png": "PNG"}


def _folder(path: Path) -> Path:
    """The folder ``path`` is in, its symbolic links resolved (the file's own name is not)."""
    return Path(os.path.realpath(path.parent if str(path.parent) else "."))


def _target(path) -> Path:
    """The file to write, in an existing or new folder, not a folder itself. Its folder's
    links are resolved, a link at the name itself is not: the rename replaces the link."""
    target = check_writable(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(f"{path}: cannot create its folder ({e.strerror})") from None
    remove_stale_temps(target.parent)
    return target


def _create(tmp: Path, path) -> None:
    try:
        os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
    except OSError as e:
        raise InputError(f"{path}: cannot write a file there ({e.strerror})") from None


def _mode(target: Path) -> int:
    """The target's permissions; a new file's (or one replacing a link, whose target's
    permissions are not ours to copy) 0666 less the umask."""
    try:
        st = os.lstat(target)
    except FileNotFoundError:
        st = None
    if st is None or stat.S_ISLNK(st.st_mode):
        return 0o666 & ~_umask()
    return st.st_mode & 0o7777


def _umask() -> int:
    with _UMASK_LOCK:
        mask = os.umask(0o022)
        os.umask(mask)
    return mask


_UMASK_LOCK = threading.Lock()


def _flush(tmp: Path, mode: int) -> None:
    os.chmod(tmp, mode)
    fd = os.open(tmp, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _flush_folder(folder: Path) -> None:
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)
    except OSError:  # some file systems cannot sync a folder
        pass
    finally:
        os.close(fd)


@contextmanager
def _folder_lock(folder: Path):
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` of this host is running (another user's counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _terminate_raises():
    """While a write is open, SIGTERM raises :class:`Terminated` (exit status 143) instead of
    ending the process where it stands, so the temporary file is removed."""
    if (
        threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL
    ):
        return nullcontext()
    return _sigterm_handler()


@contextmanager
def _sigterm_handler():
    def terminate(signum, _frame):
        raise Terminated(128 + signum)

    signal.signal(signal.SIGTERM, terminate)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def write_png(path, image: np.ndarray) -> Path:
    """8-bit PNG of ``image`` in [0, 1]: (H, W) grey or (H, W, 3) RGB, row 0 at the top."""
    check_writable(path, ".png")
    return write_atomic(path, png_bytes(image))


def write_exr(path, channels: dict, *, preview=None, compression="zip", **header) -> Path:
    """Float32 OpenEXR of named (H, W) ``channels``, row 0 at the top, with extra ``header``
    attributes, written atomically; with a ``preview`` image in [0, 1] (or the bytes of a PNG
    file) also a PNG beside it, the two renamed into place as one unit. ``compression``:
    'zip', or 'none' for data that barely compresses and is read often (a plate's samples)."""
    import OpenEXR  # noqa: F401 -- before the write opens: a SIGTERM inside an import is lost

    check_writable(path, ".exr")
    paths = [path] + ([Path(path).with_suffix(".png")] if preview is not None else [])
    with atomic_paths(*paths) as temps:
        _exr_to(temps[0], channels, compression=compression, **header)
        if preview is not None:
            Path(temps[1]).write_bytes(
                preview if isinstance(preview, bytes) else png_bytes(preview)
            )
    return Path(path)


def _exr_to(filename, channels: dict, compression="zip", **header) -> None:
    import OpenEXR

    data = {n: np.ascontiguousarray(a, np.float32) for n, a in channels.items()}
    codec = {"zip": OpenEXR.ZIP_COMPRESSION, "none": OpenEXR.NO_COMPRESSION}[compression]
    head = {"compression": codec, "type": OpenEXR.scanlineimage, **header}
    with OpenEXR.File(head, data) as f:
        f.write(str(filename))


def read_exr(path, *, what="image") -> tuple[dict, dict]:
    """(header, {channel name: float32 (H, W) pixels}) of the EXR ``path``, its size checked
    against the memory budget before a pixel is read; :class:`InputError` naming the file if
    it is missing, not an EXR, damaged or too large."""
    import OpenEXR

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    with open(path, "rb") as f:
        if f.read(4) != EXR_MAGIC:
            raise InputError(f"{path}: not an OpenEXR file")
    try:
        with OpenEXR.File(str(path), header_only=True) as f:  # closing it clears the header
            lo, hi = (np.asarray(c, np.int64) for c in f.header()["dataWindow"])
            w, h = (hi - lo + 1).tolist()
            count = len(f.header()["channels"])
    except Exception as e:  # noqa: BLE001 -- the EXR library's errors: damaged headers
        raise InputError(f"{path}: unreadable EXR header ({e})") from None
    if w < 1 or h < 1:
        raise InputError(f"{path}: an EXR of {w}x{h} pixels holds no image")
    memory.check_host(f"{path} ({what}, {w}x{h} pixels, {count} channels)", 2 * 4.0 * w * h * count)
    try:
        with OpenEXR.File(str(path), separate_channels=True) as f:
            header = dict(f.header())
            pixels = {n: np.asarray(c.pixels, np.float32) for n, c in f.channels().items()}
    except Exception as e:  # noqa: BLE001 -- truncated or damaged pixel data
        raise InputError(f"{path}: unreadable EXR data ({e})") from None
    for n, a in pixels.items():
        if a.shape != (h, w):
            raise InputError(
                f"{path}: channel {n} is sampled {a.shape}, not {h}x{w} "
                f"(subsampled channels are not supported)"
            )
    return header, pixels


def exr_attribute(path, name: str) -> bytes | None:
    """The raw value of the header attribute ``name`` of the EXR ``path`` (None when the file
    or the attribute is missing or the header is damaged), read without the EXR library (the
    add-on calls it in Blender's own process)."""
    try:
        with open(path, "rb") as f:
            head = f.read(1 << 20)
    except OSError:
        return None
    if head[:4] != EXR_MAGIC:
        return None
    at = 8
    while at < len(head) and head[at] != 0:
        key_end = head.find(b"\0", at)
        kind_end = head.find(b"\0", key_end + 1)
        if key_end < 0 or kind_end < 0 or kind_end + 5 > len(head):
            return None
        (size,) = struct.unpack_from("<i", head, kind_end + 1)
        value = kind_end + 5
        if size < 0 or value + size > len(head):
            return None
        if head[at:key_end] == name.encode():
            return head[value : value + size]
        at = value + size
    return None


def png_bytes(image: np.ndarray) -> bytes:
    """The 8-bit PNG file of ``image`` in [0, 1] (see :func:`write_png`)."""
    a = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0, 1)
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] != 3):
        raise InputError(f"image must be (H, W) or (H, W, 3); got shape {a.shape}")
    pixels = np.round(a * 255).astype(np.uint8)
    h, w = pixels.shape[:2]
    colour = 2 if pixels.ndim == 3 else 0
    rows = pixels.reshape(h, -1)
    raw = np.concatenate([np.zeros((h, 1), np.uint8), rows], axis=1).tobytes()

    def chunk(kind, body):
        return (
            struct.pack(">I", len(body))
            + kind
            + body
            + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
        )

    header = struct.pack(">IIBBBBB", w, h, 8, colour, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw, 6))
        + chunk(b"IEND", b"")
    )
