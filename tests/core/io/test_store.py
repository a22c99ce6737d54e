"""The plate store as a farm meets it: a recording racing another for one store is told the
other is writing it, a worker killed inside a chunk leaves nothing for good, a disk too small
is said before the first tile and a disk that fills mid-way names the store and the tile.

Stores are written through the store's own functions (no Dask cluster): 2 x 3 tiles of 64²,
one channel, random samples."""

import fcntl
import json
import os
import signal
import socket
import subprocess
import sys
import time

import numpy as np
import pytest
from disks import fill

zarr = pytest.importorskip("zarr")

from holo_core.io import store  # noqa: E402
from holo_core.io.digests import digest_of  # noqa: E402
from holo_core.io.files import LOCK, Files, StoreError  # noqa: E402
from holo_core.io.tiled_wave import open_plate  # noqa: E402
from holo_core.scene.hologram import HologramInfo  # noqa: E402

SHAPE, TILE = (128, 192), 64
INFO = HologramInfo(shape=SHAPE, encoding="complex", wavelengths=(633e-9,), pitch=8e-6)
RECORDING = {"digest": digest_of({"scene": "a"}), "parts": {"scene": "a"}}


def samples(seed=0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return (rng.standard_normal((1, *SHAPE)) + 1j * rng.standard_normal((1, *SHAPE))).astype(
        np.complex64
    )


def write(url, wave, tiles=None):
    """Write ``tiles`` (default all) of ``wave`` into the store at ``url``, as the tasks do."""
    with store.recording_into(Files(url), INFO, TILE, RECORDING) as plate:
        for i, j in tiles or np.ndindex(*store.tile_grid(SHAPE, TILE)):
            r0, r1, c0, c1 = store.tile_window(SHAPE, TILE, i, j)
            plate.write_tile(i, j, wave[:, r0:r1, c0:c1])


def test_the_loser_of_a_race_is_told_the_winner_is_writing_never_to_remove_it(tmp_path):
    """Two recordings start on one empty path: the winner holds the lock and has made its
    group, not yet its Holo metadata. The loser judges the store only under the lock, so it
    is told another recording is writing it (not that it holds another program's data, to be
    removed), and the winner's store is untouched and completes."""
    url = tmp_path / "p.zarr"
    url.mkdir()
    fd = os.open(url / LOCK, os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        os.pwrite(
            fd,
            json.dumps(
                {"host": "farm-7", "pid": 4242, "since": "now", "recording": "winner"}
            ).encode(),
            0,
        )
        zarr.open_group(str(url), mode="a")  # the winner's group, half made
        before = sorted(p.name for p in url.rglob("*"))
        with pytest.raises(StoreError) as refused:
            write(url, samples())
        assert "another recording is writing it (host farm-7, process 4242" in str(refused.value), (
            str(refused.value)
        )
        assert "remove" not in str(refused.value), str(refused.value)
        assert sorted(p.name for p in url.rglob("*")) == before
    finally:
        os.close(fd)


def test_a_folder_that_is_not_a_store_is_refused_under_the_lock_and_left_as_it_was(tmp_path):
    folder = tmp_path / "theirs"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine")
    with pytest.raises(StoreError, match="cannot be told to be a Holo plate"):
        write(folder, samples())
    assert [p.name for p in folder.iterdir()] == ["notes.txt"]


_KILLED_INSIDE_A_WRITE = """
import os, sys, time
from holo_core.io.files import Files
def hang(*_):
    print("inside", flush=True)
    time.sleep(600)
os.replace = hang  # the chunk's bytes are in its temporary file, not yet renamed into place
Files(sys.argv[1]).write("object_wave/c/0/0/1", b"x" * 32768)
"""


def test_a_writer_killed_inside_a_chunk_leaves_no_temporary_file_after_the_resume(tmp_path):
    """A worker killed (SIGKILL) between writing a chunk's bytes and renaming them into
    place leaves its temporary file; the recording resuming the store removes it (its
    writer is gone), and the store reads back as recorded."""
    url, wave = tmp_path / "p.zarr", samples()
    write(url, wave, tiles=[(0, 0)])
    proc = subprocess.Popen(
        [sys.executable, "-c", _KILLED_INSIDE_A_WRITE, str(url)],
        stdout=subprocess.PIPE,
        env={**os.environ, "PYTHONPATH": os.getcwd()},
    )
    try:
        assert proc.stdout.readline().strip() == b"inside"
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        proc.stdout.close()
    left = list(url.rglob("*.tmp"))
    assert len(left) == 1 and str(proc.pid) in left[0].name, left
    folder = url / "object_wave" / "c" / "0" / "1"
    live = folder / f".2.{socket.gethostname()}.{os.getpid()}.0.tmp"
    folder.mkdir(parents=True)
    live.write_bytes(b"a live writer's")  # this process is alive: its file is not touched
    write(url, wave)
    assert list(url.rglob("*.tmp")) == [live]
    assert np.array_equal(open_plate(url).object_wave[...], wave)


def test_another_hosts_temporary_file_is_removed_once_stale(tmp_path):
    url, wave = tmp_path / "p.zarr", samples()
    write(url, wave, tiles=[(0, 0)])
    folder = url / "object_wave" / "c" / "0" / "1"
    folder.mkdir(parents=True)
    fresh, stale = folder / ".1.other-host.7.0.tmp", folder / ".2.other.host.8.3.tmp"
    for path in (fresh, stale):
        path.write_bytes(b"part of a chunk")
    old = time.time() - 2 * 3600
    os.utime(stale, (old, old))
    write(url, wave)
    assert list(url.rglob("*.tmp")) == [fresh]


def test_a_store_beyond_the_disks_room_is_refused_before_the_first_tile(small_disk):
    """2 x 3 tiles of 64² complex64 need 192 KiB: a disk with less free is said before any
    tile, naming the store, and the store this call made is removed again."""
    (small_disk / "filler").write_bytes(b"\0" * (900 * 1024))
    url = small_disk / "p.zarr"
    with pytest.raises(
        StoreError,
        match=rf"{url}: the 6 tiles still to write need .* on "
        rf"disk, and {url} has .* free",
    ):
        write(url, samples())
    assert not url.exists()


def test_a_disk_that_fills_mid_way_names_the_store_and_the_tile(small_disk):
    url, wave = small_disk / "p.zarr", samples()
    write(url, wave, tiles=[(0, 0)])
    real = store.PlateStore.write_tile

    def fill_then_write(plate, i, j, part):  # another program takes the room left
        if (i, j) == (1, 1):
            fill(small_disk)
        real(plate, i, j, part)

    with pytest.MonkeyPatch.context() as m:
        m.setattr(store.PlateStore, "write_tile", fill_then_write)
        with pytest.raises(StoreError) as full:
            write(url, wave)
    message = str(full.value)
    assert message.startswith(
        f"{url} (object_wave/c/0/1/1): tile (1, 1) cannot be written (No space left on device)"
    ), message
    assert ".tmp" not in message, message
    assert not list(url.rglob("*.tmp"))
