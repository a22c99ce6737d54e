"""Gigapixel plates, small: a plate of 4×4 tiles of 256² recorded as Dask tasks into a Zarr
store equals the plate recorded in memory; a cancelled or killed recording resumes, and a
damaged tile is written again; a view reads only the tiles its window overlaps and equals the
view of the plate in memory; a scheduler that cannot serve fails fast, by name, leaving no
store; the output is checked, and made absolute, before the work."""

import json
import os
import re
import socket
import threading

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")
zarr = pytest.importorskip("zarr")

from stores import cancel_after, settled  # noqa: E402

from holo_core import jobs  # noqa: E402
from holo_core.cluster import TasksLost, client_for  # noqa: E402
from holo_core.io import store  # noqa: E402
from holo_core.io.hologram import HologramFileError, metadata  # noqa: E402
from holo_core.io.tiled_wave import open_plate, tiles_done  # noqa: E402
from holo_core.plate.points import record_points  # noqa: E402
from holo_core.plate.tiles import record_tiled  # noqa: E402
from holo_core.plate.window import window_of  # noqa: E402
from holo_core.validate import InputError  # noqa: E402

SHAPE, PITCH, TILE, WAVELENGTHS = (1024, 1024), 8e-6, 256, (633e-9, 532e-9)


@pytest.fixture(scope="module")
def scene():
    rng = np.random.default_rng(3)
    n = 300
    positions = np.c_[rng.uniform(-4e-3, 4e-3, (n, 2)), rng.uniform(-0.03, -0.02, n)]
    return positions, rng.uniform(0.2, 1, (n, len(WAVELENGTHS)))


@pytest.fixture(scope="module")
def in_memory(scene):
    return record_points(*scene, shape=SHAPE, pitch=PITCH, wavelengths=WAVELENGTHS, method="direct")


def _record(scene, url, scheduler, **kw):
    return record_tiled(
        *scene,
        url=url,
        shape=SHAPE,
        pitch=PITCH,
        wavelengths=WAVELENGTHS,
        tile=TILE,
        scheduler=scheduler,
        **kw,
    )


def test_a_tiled_plate_equals_the_plate_recorded_in_memory(scene, in_memory, scheduler, tmp_path):
    """Every tile is the whole plate's sum cut to its samples: equal to float32 rounding
    (measured: bit-equal), its metadata the EXR's schema, chunked by tile and channel."""
    h = _record(scene, tmp_path / "p.zarr", scheduler)
    ref = in_memory.object_wave
    err = np.abs(h.object_wave[...] - ref).max() / np.abs(ref).max()
    assert err <= 1e-6, err
    group = zarr.open_group(str(tmp_path / "p.zarr"), mode="r")
    assert group["object_wave"].chunks == (1, TILE, TILE)
    assert tiles_done(tmp_path / "p.zarr").all()
    meta = dict(group.attrs["holo"])
    assert meta["encoding"] == "complex" and meta["size_px"] == list(SHAPE)
    assert set(meta) == set(metadata(in_memory)), "one schema for both stores"
    assert np.allclose(meta["bounds_m"], in_memory.bounds)


def test_dask_and_other_tools_open_the_store_as_it_is(scene, scheduler, tmp_path):
    da = pytest.importorskip("dask.array")
    h = _record(scene, tmp_path / "p.zarr", scheduler)
    lazy = da.from_zarr(str(tmp_path / "p.zarr"), component="object_wave")
    assert lazy.chunksize == (1, TILE, TILE)
    assert np.array_equal(lazy[1, 300:700, 100:400].compute(), h.object_wave[1, 300:700, 100:400])


def test_a_cancelled_recording_resumes_and_a_half_written_tile_is_written_again(
    scene, in_memory, scheduler, tmp_path
):
    url = tmp_path / "p.zarr"
    with pytest.raises(jobs.Cancelled):
        _record(scene, url, scheduler, progress=cancel_after(4))
    done = settled(url)  # the tiles already running when cancelled end their write
    assert 4 <= done.sum() < done.size, done.sum()
    with pytest.raises(
        HologramFileError,
        match=r"tiles are not written yet \(tile \(\d, \d\) "
        r"first\); resume",
    ):
        open_plate(url)
    # a tile killed mid-write: samples partly there, its flag unset
    i, j = map(int, np.argwhere(~done)[0])
    r0, r1, c0, c1 = store.tile_window(SHAPE, TILE, i, j)
    zarr.open_group(str(url), mode="r+")["object_wave"][:, r0 : r0 + 10, c0:c1] = 7 + 7j
    h = _record(scene, url, scheduler)
    assert (
        np.abs(h.object_wave[...] - in_memory.object_wave).max()
        <= 1e-6 * np.abs(in_memory.object_wave).max()
    )


def test_the_scheduler_comes_from_the_environment(
    scene, in_memory, scheduler, tmp_path, monkeypatch
):
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", scheduler)
    h = _record(scene, tmp_path / "p.zarr", None)
    assert (
        np.abs(h.object_wave[...] - in_memory.object_wave).max()
        <= 1e-6 * np.abs(in_memory.object_wave).max()
    )


class _Counting:
    """A chunked array's reads, counted by the tiles they touch."""

    def __init__(self, array):
        self.array, self.shape, self.ndim, self.tiles = array, array.shape, array.ndim, set()

    def __getitem__(self, key):
        _, rows, cols = key
        self.tiles |= {
            (i, j)
            for i in range(rows.start // TILE, (rows.stop - 1) // TILE + 1)
            for j in range(cols.start // TILE, (cols.stop - 1) // TILE + 1)
        }
        return self.array[key]


def test_a_window_reads_only_the_tiles_it_overlaps(scene, in_memory, scheduler, tmp_path):
    h = _record(scene, tmp_path / "p.zarr", scheduler)
    counted = _Counting(h.object_wave)
    window = (300, 520, -40, 200)  # beyond the plate's left edge too
    u = window_of(counted, window, 1)
    assert np.array_equal(u, window_of(in_memory.object_wave[1], window))
    assert counted.tiles == {(1, 0), (2, 0)}


def test_another_plate_in_the_store_is_refused_and_bad_tiles_are_named(scene, scheduler, tmp_path):
    url = tmp_path / "p.zarr"
    _record(scene, url, scheduler)
    with pytest.raises(HologramFileError, match=r"holds another recording \(its sampling differ"):
        record_tiled(
            *scene,
            url=url,
            shape=SHAPE,
            pitch=2 * PITCH,
            wavelengths=WAVELENGTHS,
            tile=TILE,
            scheduler=scheduler,
        )
    with pytest.raises(InputError, match=r"tile must be a multiple of 64"):
        record_tiled(
            *scene,
            url=tmp_path / "q.zarr",
            shape=SHAPE,
            pitch=PITCH,
            wavelengths=WAVELENGTHS,
            tile=300,
        )
    assert not (tmp_path / "q.zarr").exists(), "a refused recording creates nothing"
    zarr.open_group(str(url), mode="r+").attrs["holo"] = {
        **json.loads(json.dumps(dict(zarr.open_group(str(url), mode="r").attrs["holo"]))),
        "pitch_m": -1,
    }
    with pytest.raises(HologramFileError, match="pitch_m"):
        open_plate(url)


def test_the_command_line_records_a_tiled_plate_on_the_scheduler_and_reads_it(
    scheduler, tmp_path, capsys
):
    """``record MESH -o NAME.zarr --tile --scheduler``, then ``info`` and ``render`` of the
    store: the same commands as for an EXR file."""
    from holo_core.__main__ import main

    (tmp_path / "tri.obj").write_text("v -0.002 -0.002 0\nv 0.002 -0.002 0\nv 0 0.002 0\nf 1 2 3\n")
    url = tmp_path / "tri.zarr"
    assert (
        main(
            [
                "record",
                str(tmp_path / "tri.obj"),
                "-o",
                str(url),
                "--method",
                "direct",
                "--resolution",
                "512",
                "512",
                "--wavelengths",
                "633",
                "--distance",
                "0.02",
                "--tile",
                "256",
                "--scheduler",
                scheduler,
                "--max-points",
                "2000",
            ]
        )
        == 0
    )
    assert tiles_done(url).shape == (2, 2) and tiles_done(url).all()
    assert "Dask dashboard: http" in capsys.readouterr().out
    assert main(["info", str(url)]) == 0
    assert json.loads(capsys.readouterr().out)["encoding"] == "complex"
    assert (
        main(["render", str(url), "-o", str(tmp_path / "view.exr"), "--resolution", "64", "64"])
        == 0
    )
    assert (tmp_path / "view.exr").stat().st_size > 0


def test_a_damaged_tile_is_written_again_when_the_recording_resumes(
    scene, in_memory, scheduler, tmp_path
):
    url = tmp_path / "p.zarr"
    _record(scene, url, scheduler)
    chunk = url / "object_wave" / "c" / "1" / "2" / "3"
    chunk.write_bytes(chunk.read_bytes()[:-8] + b"\0" * 8)
    with pytest.raises(
        HologramFileError,
        match=r"tile \(2, 3\) channel 1: its samples do not "
        r"match their checksum",
    ):
        open_plate(url).object_wave[...]
    h = _record(scene, url, scheduler)  # the same call: resumes, writes tile (2, 3) again
    assert np.array_equal(h.object_wave[...], open_plate(url).object_wave[...])
    assert (
        np.abs(h.object_wave[...] - in_memory.object_wave).max()
        <= 1e-6 * np.abs(in_memory.object_wave).max()
    )


# --- the scheduler fails fast and by name; nothing is left behind ----------------------------


@pytest.fixture
def endpoint():
    """A local TCP endpoint that misbehaves: ``endpoint("silent")`` accepts connections and
    never answers, ``"closed"`` refuses them, ``"garbage"`` answers bytes no scheduler sends."""
    sockets = []

    def make(kind):
        s = socket.socket()
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        if kind == "closed":
            s.close()
            return f"tcp://127.0.0.1:{port}"
        s.listen(4)
        sockets.append(s)
        if kind == "garbage":

            def answer():
                conn, _ = s.accept()
                with conn:
                    conn.sendall(b"\xff" * 64)

            threading.Thread(target=answer, daemon=True).start()
        return f"tcp://127.0.0.1:{port}"

    yield make
    for s in sockets:
        s.close()


@pytest.mark.parametrize(
    "kind, problem",
    [
        ("silent", r"no answer within 0.5 s \(is it a Dask scheduler\?\)"),
        ("closed", r"refuses connections \(is a scheduler running there\?\)"),
        (
            "garbage",
            r"answers, but not as a Dask scheduler \(its first message claims "
            r"18446744073709551615 bytes\)",
        ),
        ("address", r"not a scheduler address"),
        ("unknown", r"unknown host 'no-such-host.invalid'"),  # a name reserved never to resolve
    ],
)
def test_a_scheduler_that_cannot_serve_fails_fast_by_name_and_leaves_no_store(
    scene, tmp_path, endpoint, monkeypatch, kind, problem
):
    """A silent port hung (killed at 150 s), a refused one waited 30 s for an OSError, garbage
    ended in MemoryError (3.07 EiB), each leaving a store behind; an unknown host and an
    address that is not one are named too. The timeout is 10 s
    (CONNECT_TIMEOUT); 0.5 s here."""
    from holo_core import cluster

    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", 0.5)
    address = {
        "address": "tcp://127.0.0.1:not-a-port",
        "unknown": "tcp://no-such-host.invalid:8786",
    }.get(kind) or endpoint(kind)
    with pytest.raises(InputError, match=rf"scheduler {address}: {problem}"):
        _record(scene, tmp_path / "p.zarr", address)
    assert not list(tmp_path.iterdir()), "a recording that never started leaves nothing"


def test_a_relative_store_is_written_where_the_user_is_not_where_the_workers_are(
    scheduler, tmp_path, monkeypatch, capsys
):
    """``-o NAME.zarr --scheduler`` resolved NAME.zarr in the workers' folder (the tiles
    landed in another store); the path is made absolute before it is sent."""
    from holo_core.__main__ import main

    (tmp_path / "tri.obj").write_text("v -0.002 -0.002 0\nv 0.002 -0.002 0\nv 0 0.002 0\nf 1 2 3\n")
    workers = os.getcwd()  # the cluster's processes started here
    monkeypatch.chdir(tmp_path)
    assert (
        main(
            [
                "record",
                "tri.obj",
                "-o",
                "rel.zarr",
                "--method",
                "direct",
                "--resolution",
                "256",
                "256",
                "--wavelengths",
                "633",
                "--distance",
                "0.02",
                "--tile",
                "128",
                "--scheduler",
                scheduler,
                "--max-points",
                "500",
            ]
        )
        == 0
    ), capsys.readouterr().err
    assert tiles_done(tmp_path / "rel.zarr").all()
    assert not os.path.exists(os.path.join(workers, "rel.zarr"))


@pytest.mark.parametrize(
    "output, problem",
    [
        ("{tmp}/a_file", r"a_file: is a file, not a store folder"),
        (
            "/sys/p.zarr",
            r"/sys/p.zarr: its folder /sys is not writable",
        ),  # read-only, even for root
        ("memory://p.zarr", r"memory://p.zarr: a memory:// store lives in one process"),
        (
            "nosuchprotocol://bucket/p.zarr",
            r"nosuchprotocol://bucket/p.zarr: not a store address "
            r"fsspec knows",
        ),
    ],
)
def test_the_output_is_checked_before_the_work(scene, tmp_path, monkeypatch, output, problem):
    """A regular file in the way, a read-only folder, memory:// and an unknown protocol ended
    in five exception types after the cluster started; each is one InputError naming it."""
    from holo_core import cluster

    def never(*_, **__):
        raise AssertionError("the work started before the output was checked")

    monkeypatch.setattr(cluster, "client_for", never)
    (tmp_path / "a_file").write_text("mine")
    with pytest.raises(InputError, match=problem):
        _record(scene, output.format(tmp=tmp_path), None)
    assert [p.name for p in tmp_path.iterdir()] == ["a_file"]
    assert (tmp_path / "a_file").read_text() == "mine"


def test_a_protocol_whose_package_is_missing_is_named(scene, tmp_path, monkeypatch):
    import fsspec

    def missing(url, **_):
        raise ImportError("Install s3fs to access S3")

    monkeypatch.setattr(fsspec.core, "url_to_fs", missing)
    with pytest.raises(
        InputError,
        match=r"s3://bucket/p.zarr: its protocol needs a package "
        r"that is not installed \(Install s3fs",
    ):
        _record(scene, "s3://bucket/p.zarr", None)


@pytest.mark.parametrize(
    "args, problem",
    [
        (
            ["-o", "{tmp}/p.zarr", "--scheduler", "closed"],
            r"scheduler tcp://127.0.0.1:\d+: refuses "
            r"connections",
        ),
        (["-o", "memory://p.zarr"], r"memory://p.zarr: a memory:// store lives in one process"),
        (["-o", "{tmp}/a_file.zarr"], r"a_file.zarr: is a file, not a store folder"),
    ],
)
def test_the_command_line_says_each_in_one_line_before_the_work(
    tmp_path, endpoint, capsys, args, problem
):
    from cli import run_cli

    (tmp_path / "tri.obj").write_text("v -0.002 -0.002 0\nv 0.002 -0.002 0\nv 0 0.002 0\nf 1 2 3\n")
    (tmp_path / "a_file.zarr").write_text("mine")
    args = [a.format(tmp=tmp_path) if a != "closed" else endpoint("closed") for a in args]
    status, out, err = run_cli(
        capsys,
        "record",
        tmp_path / "tri.obj",
        *args,
        "--method",
        "direct",
        "--resolution",
        256,
        256,
        "--wavelengths",
        633,
        "--distance",
        0.02,
    )
    assert status == 2 and err.count("\n") == 1 and re.search(problem, err), (status, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file.zarr", "tri.obj"]


# --- the cluster: lost in the project's words, listening on loopback alone -------------------


def test_a_recording_whose_cluster_is_lost_names_the_store_the_tiles_kept_and_the_way_on(
    scene, in_memory, scheduler, tmp_path
):
    """The scheduler gone after the first tile ended in Dask's ``FutureCancelledError``
    alone; it is said with the store, the tiles it keeps and how to go on, and the same call
    on another cluster resumes it."""
    url = tmp_path / "p.zarr"
    cluster = distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
    )
    with cluster, pytest.raises(TasksLost) as lost:
        _record(scene, url, cluster.scheduler_address, progress=lambda f: cluster.close())
    said = re.fullmatch(
        rf"the recording lost its Dask workers or scheduler \(.+\); {url} "
        rf"keeps (\d+) of 16 tiles; run the same recording again to resume "
        rf"it",
        str(lost.value),
    )
    assert said, str(lost.value)
    assert 1 <= int(said[1]) <= tiles_done(url).sum() < 16, (said[1], tiles_done(url).sum())
    h = _record(scene, url, scheduler)
    assert (
        np.abs(h.object_wave[...] - in_memory.object_wave).max()
        <= 1e-6 * np.abs(in_memory.object_wave).max()
    )


def _listening(process) -> set:
    """The (address, port) pairs ``process`` and its children listen on (TCP)."""
    psutil = pytest.importorskip("psutil")
    return {
        tuple(c.laddr)
        for p in (process, *process.children(recursive=True))
        for c in p.net_connections("tcp")
        if c.status == psutil.CONN_LISTEN
    }


def _new_addresses(process, before) -> set:
    return {ip for ip, _ in _listening(process) - before}


def test_the_local_cluster_listens_on_loopback_alone(monkeypatch):
    """The default cluster's dashboard listened on every interface (``:0``): anyone on the
    studio's network could watch a recording's tasks, logs and profiles. Its scheduler,
    workers and dashboard listen on 127.0.0.1 only, unless ``HOLO_DASK_HOST`` names
    another."""
    psutil = pytest.importorskip("psutil")
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    monkeypatch.delenv("HOLO_DASK_HOST", raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    me = psutil.Process()
    before = _listening(me)
    with client_for() as client:
        assert client.dashboard_link.startswith("http://127.0.0.1:"), client.dashboard_link
        assert _new_addresses(me, before) == {"127.0.0.1"}, _listening(me) - before
    monkeypatch.setenv("HOLO_DASK_HOST", "0.0.0.0")  # named: published as asked
    with client_for():
        assert "0.0.0.0" in _new_addresses(me, before), _listening(me) - before
