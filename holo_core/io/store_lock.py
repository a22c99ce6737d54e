"""The lock a recording holds on a tiled store while it writes it."""

from __future__ import annotations

import errno
import json
import os
import socket
import time
from contextlib import contextmanager

from .files import LOCK, MAX_JSON, Files


@contextmanager
def locked(files: Files, recording: dict):
    """Hold the store's lock for one recording. On a local path: an exclusive ``flock`` on
    ``holo.lock`` (which names its holder), released by the system when the holder ends, even
    killed: a lock whose holder died is free, with no stale lock to remove. On a URL (no
    shared locks there): ``holo.lock`` is created when absent and removed at the end; one left
    by a killed recording is refused by name, to be removed by hand once that recording is
    known to have stopped. Yields whether this call made the lock file (a store refused under
    the lock then leaves no file of ours behind)."""
    holder = json.dumps(
        {
            "host": socket.gethostname(),
            "pid": os.getpid(),
            "since": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "recording": recording["digest"][:12],
        }
    )
    if files.local is None:
        found = files.read(LOCK, limit=MAX_JSON)
        if found is not None:
            raise files.fail(
                f"another recording holds its lock ({_holder(found)}); if that "
                f"one is not running, remove {files.name}/{LOCK}",
                LOCK,
            )
        files.write(LOCK, holder.encode())
        try:
            yield True
        finally:
            files.fs.rm(f"{files.root.rstrip('/')}/{LOCK}")
        return
    import fcntl

    try:
        files.local.mkdir(parents=True, exist_ok=True)
        made = not os.path.lexists(files.local / LOCK)
        fd = os.open(files.local / LOCK, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o666)
    except OSError as e:
        if e.errno == errno.ELOOP:
            raise files.fail(
                "is a symbolic link; a store's files are read, never followed", LOCK
            ) from None
        raise files.fail(f"cannot be locked ({e.strerror or e})", LOCK) from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder_now = _holder(os.pread(fd, MAX_JSON, 0))
            raise files.fail(
                f"another recording is writing it ({holder_now}); wait for it to end, or stop it",
                LOCK,
            ) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, holder.encode(), 0)
        try:
            yield made
        finally:
            os.ftruncate(fd, 0)  # free: no holder named
    finally:
        os.close(fd)  # releases the flock


def _holder(data: bytes) -> str:
    try:
        h = json.loads(data.decode("utf-8"))
        return (
            f"host {h['host']}, process {h['pid']}, since {h['since']}, recording {h['recording']}"
        )[:200]
    except (ValueError, KeyError, TypeError, UnicodeDecodeError, RecursionError):
        return "its holder unreadable"
