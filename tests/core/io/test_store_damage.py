"""A tiled store is verified, not trusted: each damage to its tiles, their records or its
metadata ends in the project's error naming the store (and the tile, where the damage is a
tile's), never in another exception, a hang on a FIFO or a read of /dev/zero; damage to a
tile's samples is found on resuming and written again; a store that is not Holo's is never
written into.

The stores here are written through the store's own functions from a plate recorded in
memory (no Dask cluster): 4 x 5 tiles of 64² (the last row and column of tiles cut short),
two channels."""

import gzip
import json
import os
import shutil
import stat
from pathlib import Path

import numpy as np
import pytest

zarr = pytest.importorskip("zarr")

from holo_core.io import store  # noqa: E402
from holo_core.io.files import LOCK, Files, check_output  # noqa: E402
from holo_core.io.hologram import HologramFileError  # noqa: E402
from holo_core.io.tiled_wave import open_plate  # noqa: E402
from holo_core.plate import tiles as recorder  # noqa: E402
from holo_core.plate.points import record_points  # noqa: E402
from holo_core.scene.hologram import HologramInfo  # noqa: E402

SHAPE, PITCH, TILE, WAVELENGTHS = (250, 300), 8e-6, 64, (633e-9, 532e-9)
CHUNK, RECORD = "object_wave/c/1/1/2", "tiles_done/c/1/2/0"  # tile (1, 2)
EDGE = "object_wave/c/0/3/4"  # the corner tile, cut short: its chunk padded with zeros
META = ("zarr.json", "object_wave/zarr.json", "tiles_done/zarr.json")


def scene(seed=3):
    rng = np.random.default_rng(seed)
    n = 40
    positions = np.c_[rng.uniform(-1e-3, 1e-3, (n, 2)), rng.uniform(-0.03, -0.02, n)]
    return positions, rng.uniform(0.2, 1, (n, len(WAVELENGTHS)))


def write_store(url, positions, colours, *, seed=0, overwrite=False, checked=check_output):
    """The plate of ``positions`` and ``colours`` written tile by tile into the store ``url``
    (its files as ``checked`` gives them) as the recording's tasks write it."""
    files = checked(url)
    h = record_points(
        positions,
        colours,
        shape=SHAPE,
        pitch=PITCH,
        wavelengths=WAVELENGTHS,
        method="direct",
        seed=seed,
    )
    info = HologramInfo(
        shape=SHAPE, encoding="complex", wavelengths=WAVELENGTHS, pitch=PITCH, bounds=h.bounds
    )
    recording = recorder._recording(
        np.asarray(positions, np.float64),
        colours,
        None,
        seed,
        method="direct",
        shape=SHAPE,
        pitch=PITCH,
        band=None,
        wavelengths=WAVELENGTHS,
        tile=TILE,
    )
    with store.recording_into(files, info, TILE, recording, overwrite=overwrite) as plate:
        for i, j in np.ndindex(*store.tile_grid(SHAPE, TILE)):
            r0, r1, c0, c1 = store.tile_window(SHAPE, TILE, i, j)
            plate.write_tile(i, j, h.object_wave[:, r0:r1, c0:c1])
    return h


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    url = tmp_path_factory.mktemp("pristine") / "p.zarr"
    h = write_store(url, *scene())
    return url, h


@pytest.fixture
def copy(pristine, tmp_path):
    url = tmp_path / "p.zarr"
    shutil.copytree(pristine[0], url, symlinks=True)
    return url


def read_all(url):
    return open_plate_read(url)


def open_plate_read(url):
    h = open_plate(url)
    return h.object_wave[...]


def test_a_whole_store_reads_back_as_recorded(pristine):
    url, h = pristine
    assert np.array_equal(open_plate_read(url), h.object_wave)
    back = open_plate(url).object_wave
    assert np.array_equal(back[1, 70:140, -90:], h.object_wave[1, 70:140, -90:])
    assert np.array_equal(back[0, 5], h.object_wave[0, 5])
    assert np.array_equal(back[:, ::7, 3], h.object_wave[:, ::7, 3])


# --- the damage cases: (what is done to a copy of the store, what the error must say) --------


def _edit_json(key, change):
    def damage(url):
        doc = json.loads((url / key).read_text())
        change(doc)
        (url / key).write_text(json.dumps(doc))

    return damage


def _attrs(**kw):
    return _edit_json("zarr.json", lambda d: d["attributes"].update(kw))


def _array(key, **kw):
    return _edit_json(f"{key}/zarr.json", lambda d: d.update(kw))


def _write(key, data):
    return lambda url: (url / key).write_bytes(data(url) if callable(data) else data)


def _remove(key):
    return lambda url: (url / key).unlink()


def _symlink(key, target):
    def damage(url):
        (url / key).unlink()
        os.symlink(target(url) if callable(target) else target, url / key)

    return damage


def _fifo(key):
    def damage(url):
        (url / key).unlink()
        os.mkfifo(url / key)

    return damage


def _folder(key):
    def damage(url):
        (url / key).unlink()
        (url / key).mkdir()

    return damage


def _flip(key, offset):
    def damage(url):
        data = bytearray((url / key).read_bytes())
        data[offset] ^= 0x40
        (url / key).write_bytes(bytes(data))

    return damage


def _outside(url):
    """A file beside the store, of a chunk's size: what a planted link would read."""
    target = url.parent / "outside.bin"
    target.write_bytes(b"\1" * (8 * TILE * TILE))
    return target


def _deep(depth=100_000):
    return ("[" * depth + "]" * depth).encode()


def _record_of_another_recording(url):
    data = np.frombuffer((url / RECORD).read_bytes(), "<u8").copy()
    data[0] ^= np.uint64(0xFF00)
    return data.tobytes()


def _swapped(url):
    return (url / "object_wave/c/1/2/2").read_bytes()


TILE_NAMED = r"tile \(1, 2\)"
CASES = {
    # a tile's samples
    "chunk missing, flagged done": (
        _remove(CHUNK),
        TILE_NAMED + r" channel 1: its samples are "
        r"missing",
    ),
    "chunk truncated": (
        _write(CHUNK, lambda u: (u / CHUNK).read_bytes()[:1000]),
        r"object_wave/c/1/1/2\): holds 1000 bytes; it must hold 32768",
    ),
    "chunk emptied": (_write(CHUNK, b""), r"holds 0 bytes; it must hold 32768"),
    "chunk one byte longer": (
        _write(CHUNK, lambda u: (u / CHUNK).read_bytes() + b"\0"),
        r"holds 32769 bytes",
    ),
    "chunk gzip-garbled": (
        _write(CHUNK, lambda u: gzip.compress((u / CHUNK).read_bytes())),
        r"object_wave/c/1/1/2\): holds \d+ bytes; it must hold 32768",
    ),
    "chunk garbage of its size": (
        _write(CHUNK, os.urandom(8 * TILE * TILE)),
        TILE_NAMED + r" channel 1: its samples do not match",
    ),
    "chunk one bit flipped": (
        _flip(CHUNK, 4321),
        TILE_NAMED + r" channel 1: its samples do "
        r"not match",
    ),
    "chunk of another tile": (
        _write(CHUNK, _swapped),
        TILE_NAMED + r" channel 1: its "
        r"samples do not match",
    ),
    "edge chunk's padding written": (
        _flip(EDGE, 8 * TILE * TILE - 3),
        r"tile \(3, 4\) channel 0: its samples do not match",
    ),
    "chunk symlinked outside": (
        _symlink(CHUNK, _outside),
        r"holds a symbolic link "
        r"object_wave/c/1/1/2",
    ),
    "chunk symlinked to /dev/zero": (
        _symlink(CHUNK, "/dev/zero"),
        r"holds a symbolic link "
        r"object_wave/c/1/1/2",
    ),
    "chunk a FIFO": (_fifo(CHUNK), r"holds a FIFO object_wave/c/1/1/2"),
    "chunk a folder": (_folder(CHUNK), r"object_wave/c/1/1/2\): is a folder, not a regular"),
    "chunk folder symlinked outside": (
        lambda u: (
            shutil.move(u / "object_wave/c/1", u.parent / "c1"),
            os.symlink(u.parent / "c1", u / "object_wave/c/1"),
        ),
        r"holds a symbolic link object_wave/c/1\b",
    ),
    # a tile's record
    "record missing": (_remove(RECORD), r"1 of 20 tiles are not written yet \(tile \(1, 2\)"),
    "record truncated": (
        _write(RECORD, lambda u: (u / RECORD).read_bytes()[:7]),
        r"tile \(1, 2\)'s record holds 7 bytes; it must hold 24",
    ),
    "record of another recording": (
        _write(RECORD, _record_of_another_recording),
        TILE_NAMED + r" and 0 more were written by another "
        r"recording",
    ),
    "record's checksum flipped": (
        _flip(RECORD, 12),
        TILE_NAMED + r" channel 0: its samples "
        r"do not match",
    ),
    "record symlinked to /dev/zero": (
        _symlink(RECORD, "/dev/zero"),
        r"holds a symbolic link tiles_done/c/1/2/0",
    ),
    "record a FIFO": (_fifo(RECORD), r"holds a FIFO tiles_done/c/1/2/0"),
    # the group's metadata
    "zarr.json missing": (
        _remove("zarr.json"),
        r"\(zarr.json\): not a tiled plate \(it is "
        r"missing\)",
    ),
    "zarr.json truncated": (
        _write("zarr.json", lambda u: (u / "zarr.json").read_bytes()[:50]),
        r"\(zarr.json\): damaged metadata \(JSONDecodeError",
    ),
    "zarr.json deeply nested": (
        _write("zarr.json", _deep()),
        r"\(zarr.json\): damaged metadata \(RecursionError",
    ),
    "zarr.json of 2 MiB": (
        _write("zarr.json", b" " * 2**21 + b"{}"),
        r"\(zarr.json\): holds 2097154 bytes, more than the 1048576",
    ),
    "zarr.json symlinked to /dev/zero": (
        _symlink("zarr.json", "/dev/zero"),
        r"holds a symbolic link zarr.json",
    ),
    "zarr.json symlinked outside": (
        _symlink("zarr.json", _outside),
        r"holds a symbolic link zarr.json",
    ),
    "zarr.json a FIFO": (_fifo("zarr.json"), r"holds a FIFO zarr.json"),
    "zarr.json not UTF-8": (_write("zarr.json", b"\xff\xfe{}"), r"UnicodeDecodeError"),
    "zarr.json a list": (_write("zarr.json", b"[]"), r"damaged metadata \(not a JSON object"),
    "hologram metadata missing": (
        _edit_json("zarr.json", lambda d: d["attributes"].pop("holo")),
        r"not a tiled plate \(a Zarr group without hologram metadata\)",
    ),
    "pitch -1": (
        _edit_json("zarr.json", lambda d: d["attributes"]["holo"].update(pitch_m=-1)),
        r"metadata pitch_m must be in",
    ),
    "size changed": (
        _edit_json("zarr.json", lambda d: d["attributes"]["holo"].update(size_px=[250, 299])),
        r"object_wave's shape is \[2, 250, 300\]; the plate's is "
        r"\[2, 250, 299\]",
    ),
    "encoding intensity": (
        _edit_json("zarr.json", lambda d: d["attributes"]["holo"].update(encoding="intensity")),
        r"a tiled plate is complex",
    ),
    "tile 128": (
        _attrs(tile=128),
        r"object_wave's chunk_grid is .*64, 64.*; the plate's is "
        r".*128, 128",
    ),
    "tile not a number": (
        _attrs(tile="64"),
        r"tile must be an integer in \[64, 16384\]; got "
        r"'64'",
    ),
    "store format 1": (_attrs(store_format=1), r"store format 1; this reader reads format 2"),
    "scene digest garbled": (
        _attrs(recording={"digest": "x" * 64}),
        r"recording must name the scene's digest",
    ),
    # the arrays' metadata
    "object_wave rewritten as float32": (
        _array("object_wave", data_type="float32"),
        r"object_wave's data_type is 'float32'; the "
        r"plate's is 'complex64'",
    ),
    "object_wave gzip codec": (
        _array(
            "object_wave",
            codecs=[
                {"name": "bytes", "configuration": {"endian": "little"}},
                {"name": "gzip", "configuration": {"level": 1}},
            ],
        ),
        r"object_wave's codecs is",
    ),
    "object_wave big-endian": (
        _array("object_wave", codecs=[{"name": "bytes", "configuration": {"endian": "big"}}]),
        r"object_wave's codecs",
    ),
    "object_wave fill value 1": (
        _array("object_wave", fill_value=[1.0, 0.0]),
        r"object_wave's fill_value",
    ),
    "object_wave storage transformer": (
        _array("object_wave", storage_transformers=[{"name": "x"}]),
        r"object_wave has storage transformers",
    ),
    "object_wave zarr.json deeply nested": (
        _write("object_wave/zarr.json", _deep()),
        r"object_wave/zarr.json\): damaged metadata "
        r"\(RecursionError",
    ),
    "tiles_done reshaped": (
        _array("tiles_done", shape=[5, 4, 3]),
        r"tiles_done's shape is "
        r"\[5, 4, 3\]; the plate's is \[4, 5, 3\]",
    ),
    "tiles_done retyped bool": (
        _array("tiles_done", data_type="bool"),
        r"tiles_done's data_type is 'bool'; the plate's is 'uint64'",
    ),
    "tiles_done retyped uint8": (
        _array("tiles_done", data_type="uint8"),
        r"tiles_done's data_type is 'uint8'",
    ),
    "tiles_done zarr.json missing": (
        _remove("tiles_done/zarr.json"),
        r"tiles_done/zarr.json\): not a tiled plate",
    ),
    "tiles_done zarr.json a FIFO": (
        _fifo("tiles_done/zarr.json"),
        r"holds a FIFO tiles_done/zarr.json",
    ),
}


@pytest.mark.parametrize("case", list(CASES))
def test_every_damage_is_the_projects_error_naming_the_store(copy, case):
    damage, message = CASES[case]
    damage(copy)
    with pytest.raises(HologramFileError) as e:
        open_plate_read(copy)
    assert str(copy) in str(e.value), str(e.value)
    assert __import__("re").search(message, str(e.value)), str(e.value)


def held(url):
    """What the store at ``url`` holds, without following a link or opening a FIFO: each
    path's kind, and a regular file's bytes or a link's target."""
    out = {}
    for folder, dirs, files in os.walk(url):
        for name in dirs + files:
            path = os.path.join(folder, name)
            mode = os.lstat(path).st_mode
            content = (
                Path(path).read_bytes()
                if stat.S_ISREG(mode)
                else os.readlink(path)
                if stat.S_ISLNK(mode)
                else None
            )
            out[os.path.relpath(path, url)] = stat.S_IFMT(mode), content
    return out


def test_each_damage_changes_a_store_that_reads_back_unchanged(pristine, tmp_path):
    """Each refusal above is its damage's own: the store undamaged reads back as recorded
    (test_a_whole_store_reads_back_as_recorded), and every damage changes what it holds."""
    for k, (case, (damage, _)) in enumerate(CASES.items()):
        url = tmp_path / str(k) / "p.zarr"
        shutil.copytree(pristine[0], url, symlinks=True)
        before = held(url)
        damage(url)
        assert held(url) != before, case


@pytest.mark.parametrize(
    "case",
    [
        c
        for c in CASES
        if c.startswith(("chunk", "edge", "record")) and "symlink" not in c and "FIFO" not in c
    ],
)
def test_a_damaged_tile_is_named_and_written_again_on_resuming(copy, case):
    """Resuming reads back every tile its record calls written: one whose samples do not match
    is written again (and its record), so the store reads back as recorded."""
    damage, _ = CASES[case]
    damage(copy)
    if "folder" in case:  # the recording refuses what holds other things than files
        with pytest.raises(HologramFileError, match=str(copy)):
            write_store(copy, *scene())
        return
    h = write_store(copy, *scene())  # the same recording: resumes
    assert np.array_equal(open_plate_read(copy), h.object_wave)


@pytest.mark.parametrize("case", [c for c in CASES if "symlink" in c or "FIFO" in c])
def test_a_hostile_store_is_refused_on_resuming_too(copy, case):
    damage, message = CASES[case]
    damage(copy)
    with pytest.raises(HologramFileError, match=message):
        write_store(copy, *scene())


def test_resuming_lists_only_the_damaged_tiles(copy):
    _flip(CHUNK, 100)(copy)
    _remove(RECORD.replace("1/2", "3/0"))(copy)
    plate = store.read_store(copy)
    assert recorder._to_record(plate) == [(1, 2), (3, 0)]


# --- a store belongs to one plate -------------------------------------------------------------


@pytest.mark.parametrize(
    "change, named",
    [
        ({"seed": 4}, r"its seed differ"),
        ({"colours": 0.5}, r"its colours differ"),
        ({"positions": 1.01}, r"its geometry differ"),
    ],
)
def test_another_recording_never_mixes_into_a_store(copy, pristine, change, named):
    """Resuming with other colours, seed or geometry mixed the two scenes (exit 0); it is
    refused naming both recordings, and the store is left as it was."""
    positions, colours = scene()
    seed = change.get("seed", 0)
    positions = positions * change.get("positions", 1)
    colours = colours * change.get("colours", 1)
    with pytest.raises(
        HologramFileError,
        match=named + r": the store holds recording "
        r"[0-9a-f]{12} \(emitters 40, seed 0, method "
        r"direct\), this call is recording "
        r"[0-9a-f]{12}",
    ):
        write_store(copy, positions, colours, seed=seed)
    assert np.array_equal(open_plate_read(copy), pristine[1].object_wave)
    h = write_store(copy, positions, colours, seed=seed, overwrite=True)  # asked: replaced
    assert np.array_equal(open_plate_read(copy), h.object_wave)


def test_a_zarr_group_that_is_not_holos_is_never_written_into(tmp_path):
    """A Zarr group of the user's with an object_wave array had it replaced, exit 0."""
    url = tmp_path / "theirs.zarr"
    group = zarr.open_group(str(url), mode="w")
    group.create_array("object_wave", shape=(4,), dtype="float64")[:] = [1, 2, 3, 4]
    before = {p: p.read_bytes() for p in url.rglob("*") if p.is_file()}
    for overwrite in (False, True):
        with pytest.raises(HologramFileError, match=r"holds data that is not a Holo plate"):
            write_store(url, *scene(), overwrite=overwrite)
    assert {p: p.read_bytes() for p in url.rglob("*") if p.is_file()} == before
    (tmp_path / "folder").mkdir()
    (tmp_path / "folder" / "notes.txt").write_text("mine")
    with pytest.raises(HologramFileError, match=r"folder: cannot be told to be a Holo plate"):
        write_store(tmp_path / "folder", *scene(), overwrite=True)
    assert [p.name for p in (tmp_path / "folder").iterdir()] == ["notes.txt"]


def test_a_second_recording_into_a_locked_store_is_refused_naming_the_first(copy):
    """Two recordings of different scenes into one store at once left one scene, both exit
    0. The first holds the store's lock (an flock, released by the system when its holder
    ends, killed or not); the second is refused, naming the holder."""
    import fcntl

    fd = os.open(copy / LOCK, os.O_RDWR)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        os.pwrite(
            fd,
            json.dumps({"host": "h1", "pid": 4242, "since": "now", "recording": "abc"}).encode(),
            0,
        )
        with pytest.raises(
            HologramFileError,
            match=r"holo.lock\): another recording is "
            r"writing it \(host h1, process 4242",
        ):
            write_store(copy, *scene(seed=9))
    finally:
        os.close(fd)
    write_store(copy, *scene())  # the lock released: the same recording resumes


def test_a_lock_left_by_a_killed_recording_is_free(copy):
    """A holder killed with SIGKILL leaves its lock file naming it, but no lock: the next
    recording takes it."""
    (copy / LOCK).write_text(
        json.dumps({"host": "h1", "pid": 999999, "since": "then", "recording": "abc"})
    )
    write_store(copy, *scene())
    assert (copy / LOCK).read_text() == ""


def test_what_the_lock_and_the_store_hold_are_plain_files(pristine):
    url = pristine[0]
    kinds = {stat.S_IFMT(os.lstat(p).st_mode) for p in url.rglob("*")}
    assert kinds <= {stat.S_IFREG, stat.S_IFDIR}, kinds


def test_a_recording_that_never_started_leaves_no_store_and_no_folder_it_made(tmp_path):
    """A failure before the first tile (here: the first task) removes the store this call
    made, and the folder too when the call made it; a folder that was there stays."""
    positions, colours = scene()

    def failing(*_, **__):
        raise RuntimeError("the cluster went away")

    for url, kept in ((tmp_path / "new.zarr", False), (tmp_path / "empty", True)):
        if kept:
            url.mkdir()
        with pytest.MonkeyPatch.context() as m:
            m.setattr(store.PlateStore, "write_tile", failing)
            with pytest.raises(RuntimeError, match="went away"):
                write_store(url, positions, colours)
        assert url.exists() == kept and (not kept or not list(url.iterdir()))


def test_a_store_at_a_url_is_written_read_and_locked_as_a_folder_is():
    """fsspec's in-process memory filesystem stands in for an object store: the same files,
    records and checks; its lock (no shared locks there) is a file, refused while present."""
    url = "memory://holo-test/p.zarr"
    positions, colours = scene()
    try:
        h = _write_at_url(url, positions, colours)
        assert np.array_equal(open_plate(url).object_wave[...], h.object_wave)
        files = Files(url)
        files.write(LOCK, b'{"host": "h2", "pid": 7, "since": "now", "recording": "x"}')
        with pytest.raises(
            HologramFileError,
            match=r"another recording holds its lock \(host "
            r"h2, process 7.*remove "
            r"memory://holo-test/p.zarr/holo.lock",
        ):
            _write_at_url(url, positions, colours)
    finally:
        import fsspec

        memory = fsspec.filesystem("memory")
        if memory.exists("/holo-test"):
            memory.rm("/holo-test", recursive=True)


def _write_at_url(url, positions, colours):
    """:func:`write_store` past the output check (which refuses memory:// for a recording's
    workers in other processes)."""
    return write_store(url, positions, colours, checked=Files)


@pytest.mark.parametrize("key", [CHUNK, "zarr.json"])
def test_a_device_in_a_store_is_refused_unread(copy, key):
    """A character device (the node of /dev/zero, made where the system allows it) in place
    of a chunk or the group's metadata is refused before anything is read."""
    (copy / key).unlink()
    try:
        os.mknod(copy / key, stat.S_IFCHR | 0o600, os.makedev(1, 5))
    except PermissionError:
        pytest.skip("this system does not let a test make a device node")
    with pytest.raises(HologramFileError, match=rf"{copy}: holds a character device {key}"):
        open_plate_read(copy)
