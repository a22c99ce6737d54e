"""Folders as a farm node meets them: one that exists but takes no file (a read-only share),
and a disk with little room. As root, permissions do not stop a write, so these are real
mounts (a read-only bind mount, a small tmpfs), unmounted afterwards; a user who may not
mount gets a folder without write permission, and no small disk (the test is skipped)."""

import contextlib
import os
import subprocess

import pytest


def _mount(*args) -> bool:
    return subprocess.run(["mount", *args], capture_output=True, check=False).returncode == 0


@contextlib.contextmanager
def _mounted(target, *args):
    if not _mount(*args, str(target)):
        pytest.skip(f"this test needs a mount ({' '.join(args)}) and the user may not mount")
    try:
        yield target
    finally:
        subprocess.run(["umount", str(target)], capture_output=True, check=True)


@contextlib.contextmanager
def read_only_folder(path):
    """``path`` made a folder that exists, readable, where no file can be created."""
    path.mkdir(parents=True, exist_ok=True)
    if os.geteuid() != 0:
        path.chmod(0o555)
        try:
            yield path
        finally:
            path.chmod(0o755)
        return
    with _mounted(path, "--bind", "-o", "ro", str(path)):
        if os.access(path, os.W_OK) and _writes(path):
            pytest.skip(f"{path} is still writable after a read-only bind mount")
        yield path


def _writes(path) -> bool:
    try:
        (path / ".probe").touch()
    except OSError:
        return False
    (path / ".probe").unlink()
    return True


@contextlib.contextmanager
def small_disk(path, size: str = "1m"):
    """``path`` made an empty file system of ``size`` (tmpfs's notation: 1m is 1 MiB)."""
    path.mkdir(parents=True, exist_ok=True)
    if os.geteuid() != 0:
        pytest.skip("a small disk needs a tmpfs mount, which only root may make")
    with _mounted(path, "-t", "tmpfs", "-o", f"size={size}", "tmpfs"):
        yield path
