"""Plates of meshes recorded (holo_core.plate.looks, the recording's public entry): looks
recorded together equal each look recorded alone; recorded with occlusion against their zone's
carrier, tile by tile as Dask tasks into a Zarr store, they equal the plate recorded in memory
bit for bit; a view of the store reads only the tiles its window overlaps and equals the view of
the plate in memory; a cancelled or killed recording resumes, keeping the tiles written; the
store's digest covers what the samples depend on; the command line records a mesh as such a
plate."""

import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from plate_scene import PLATE, camera, meshes

from holo_core.plate.carrier import physical_field, window
from holo_core.plate.look_codes import look_code
from holo_core.plate.looks import record_looks, record_plate
from holo_core.plate.view import render_view
from holo_core.validate import InputError

pytest.importorskip("distributed")
zarr = pytest.importorskip("zarr")
from stores import cancel_after, settled  # noqa: E402

from holo_core import jobs  # noqa: E402
from holo_core.io import store  # noqa: E402
from holo_core.io.files import LOCK, StoreError  # noqa: E402
from holo_core.io.hologram import metadata, read_hologram  # noqa: E402
from holo_core.io.plate_paths import plate_current, read_plate  # noqa: E402
from holo_core.io.tiled_wave import open_plate, tiles_done  # noqa: E402
from holo_core.plate.window import camera_in_plate, carrier_window, image_corners  # noqa: E402

SCALE, TILE = 0.25, 256  # a plate of 504 x 559 samples: 2 x 3 tiles
ROOT = Path(__file__).resolve().parents[3]
SCENE = {"plate": PLATE, "camera": camera("centre", SCALE), "zone_margin": 0.025}


@pytest.mark.parametrize("looks", [2, 3])
def test_looks_recorded_together_equal_looks_recorded_alone(looks):
    """record_looks sums every look in one pass: each look equals record_plate's of its code
    (2: the checkerboard pair of one seed, summed once per class of equal code shifts and
    mixed) or of its own seed (3: independent looks, summed as further channels) within
    float32 rounding, 1e-5 of the largest sample (a look alone sums its depth partner in the
    colours' pass, three independent looks theirs apart, and the compiler's fast arithmetic
    rounds the two kernels' shared steps alike only to float32); and its memory budget
    counts every look."""
    kw = {"plate": PLATE, "camera": camera("centre", SCALE), "zone_margin": 0.025}
    together = record_looks(meshes(), looks=looks, seed=4, **kw)
    assert len(together) == looks
    for k, h in enumerate(together):
        code = look_code(k, looks)
        alone = record_plate(meshes(), seed=4 + (0 if code else k), code=code, **kw)
        a, b = h.object_wave, alone.object_wave
        assert np.max(np.abs(a - b)) <= 1e-5 * np.max(np.abs(b)), (k, np.max(np.abs(a - b)))
        assert h.carrier == alone.carrier and h.wavelengths == alone.wavelengths
    one = together[0].object_wave.nbytes  # a look recorded alone fits where all do not
    assert len(record_looks(meshes(), looks=1, budget=(2.5 * one, None), **kw)) == 1
    with pytest.raises(InputError, match="memory budget"):
        record_looks(meshes(), looks=looks, budget=(2.5 * one, None), **kw)


@pytest.fixture(scope="module")
def in_memory():
    return record_plate(meshes(), **SCENE)


def _record(url, scheduler, scene=meshes, **kw):
    return record_plate(scene(), **{**SCENE, **kw}, url=url, tile=TILE, scheduler=scheduler)


@pytest.fixture(scope="module")
def recorded(scheduler, tmp_path_factory):
    url = tmp_path_factory.mktemp("plate") / "p.zarr"
    return url, _record(url, scheduler)


def _files(url):
    """Each written file of the store and its modification time [ns]."""
    return {
        p: p.stat().st_mtime_ns
        for p in Path(url).rglob("*")
        if p.is_file() and p.name != LOCK and "zarr.json" not in p.name
    }


def test_a_tiled_plate_of_meshes_equals_the_plate_recorded_in_memory(in_memory, recorded):
    """Each tile is ZoneSum.region of its block from the same emitters, amplitudes and
    visibility tables (found once on the client): bit-equal to the plate summed in memory in
    bands of rows; the store holds the EXR's metadata with the carrier, chunked by tile."""
    url, h = recorded
    assert h.shape == in_memory.shape == (504, 559)
    assert np.array_equal(h.object_wave[...], in_memory.object_wave)
    assert h.carrier == in_memory.carrier and h.zone.centre == in_memory.zone.centre
    group = zarr.open_group(str(url), mode="r")
    assert group["object_wave"].chunks == (1, TILE, TILE)
    assert tiles_done(url).shape == (2, 3) and tiles_done(url).all()
    meta = dict(group.attrs["holo"])
    assert meta == metadata(in_memory), "one schema, the carrier included"


class _Reads:
    """The tiles a store's reads touch (patched into its PlateStore)."""

    def __init__(self, monkeypatch):
        self.tiles, read = set(), store.PlateStore.read_tile

        def counted(plate, c, i, j):
            self.tiles.add((i, j))
            return read(plate, c, i, j)

        monkeypatch.setattr(store.PlateStore, "read_tile", counted)


def test_a_view_of_the_store_reads_its_window_only_and_equals_the_view_in_memory(
    in_memory, recorded, monkeypatch
):
    """The left camera's window (rows 111-397, columns 35-388) overlaps 4 of the 6 tiles: only
    those are read, and its view equals the view of the plate in memory, bit for bit."""
    url, _ = recorded
    reads = _Reads(monkeypatch)
    cam = camera("left", SCALE)
    view = render_view(open_plate(url), cam, supersample=2)
    rotation, position = camera_in_plate(in_memory, cam)
    r0, r1, c0, c1 = carrier_window(
        in_memory, position, rotation, cam.aperture_diameter, image_corners(cam, rotation)
    )
    overlapped = {
        (i, j)
        for i in range(r0 // TILE, (r1 - 1) // TILE + 1)
        for j in range(c0 // TILE, (c1 - 1) // TILE + 1)
    }
    assert reads.tiles == overlapped and len(overlapped) == 4, (reads.tiles, (r0, r1, c0, c1))
    ref = render_view(in_memory, cam, supersample=2)
    for name in ("rgb", "alpha", "depth"):
        assert np.array_equal(getattr(view, name), getattr(ref, name)), name


def test_a_cancelled_recording_resumes_keeping_the_tiles_written(in_memory, tmp_path, monkeypatch):
    """A recording cancelled after its second tile keeps the tiles written; the same call
    writes only the others, and the plate equals the plate in memory. One worker thread in
    this process, each tile slowed to 0.3 s, so that the cancel lands before the last tiles
    whatever the machine's load."""
    import distributed

    from holo_core.plate import recording

    region = recording.PlateRecording.region

    def slow(self, *args):
        time.sleep(0.3)
        return region(self, *args)

    monkeypatch.setattr(recording.PlateRecording, "region", slow)
    url = tmp_path / "p.zarr"
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address="127.0.0.1:0"
    ) as cluster:
        with pytest.raises(jobs.Cancelled):
            _record(url, cluster.scheduler_address, progress=cancel_after(2))
        done = settled(url)  # the tiles already running when cancelled end their write
        assert 2 <= done.sum() < done.size, done.sum()
        before = _files(url)
        h = _record(url, cluster.scheduler_address)
    assert np.array_equal(h.object_wave[...], in_memory.object_wave)
    after = _files(url)
    assert all(after[p] == t for p, t in before.items()), "a tile written was written again"
    assert len(after) > len(before)


KILLED = textwrap.dedent("""
    import sys, time
    sys.path[:0] = [{tests!r}]
    import distributed
    from plate_scene import PLATE, camera, meshes
    from holo_core.plate import looks, recording
    region = recording.PlateRecording.region

    def slow(self, *args):  # a tile a second: the kill lands mid-recording
        time.sleep(1.0)
        return region(self, *args)

    if __name__ == "__main__":
        recording.PlateRecording.region = slow  # the workers share this process
        with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                      dashboard_address=":0") as cluster:
            looks.record_plate(meshes(), plate=PLATE, camera=camera("centre", {scale}),
                               zone_margin=0.025, url={url!r}, tile={tile},
                               scheduler=cluster.scheduler_address)
""")


def test_a_killed_recording_resumes(in_memory, scheduler, tmp_path):
    """The recording's process is killed (SIGKILL) after its first tiles: its lock is free (an
    flock dies with its holder), the tiles it wrote are kept, and the same call completes the
    plate, equal to the plate in memory."""
    url = tmp_path / "p.zarr"
    script = tmp_path / "killed.py"
    script.write_text(
        KILLED.format(tests=str(ROOT / "tests"), scale=SCALE, url=str(url), tile=TILE)
    )
    proc = subprocess.Popen(
        [sys.executable, str(script)],
        start_new_session=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 240
        while not _a_tile_written(url):
            assert proc.poll() is None, proc.stderr.read()
            assert time.monotonic() < deadline, "no tile written in 240 s"
            time.sleep(0.2)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        proc.stderr.close()
    done = tiles_done(url)
    assert 1 <= done.sum() < done.size, done
    before = _files(url)
    h = _record(url, scheduler)
    assert np.array_equal(h.object_wave[...], in_memory.object_wave)
    assert all(_files(url)[p] == t for p, t in before.items() if "tiles_done" in str(p))


def test_the_scheduler_comes_from_the_environment(in_memory, scheduler, tmp_path, monkeypatch):
    """No scheduler given: DASK_SCHEDULER_ADDRESS names the cluster (a farm's), as Dask's own
    clients take it: an address where nothing listens is refused naming it (no local cluster
    instead), the module's cluster records the plate recorded in memory."""
    import socket

    with socket.socket() as s:  # a port just freed: nothing listens there
        s.bind(("127.0.0.1", 0))
        nowhere = f"tcp://127.0.0.1:{s.getsockname()[1]}"
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", nowhere)
    with pytest.raises(InputError, match=re.escape(nowhere)):
        _record(tmp_path / "p.zarr", None)
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", scheduler)
    h = _record(tmp_path / "p.zarr", None)
    assert np.array_equal(h.object_wave[...], in_memory.object_wave)


def _a_tile_written(url) -> bool:
    """Whether the store at ``url`` holds a written tile yet: a store still being made (its
    group there, its metadata not yet: not a plate) holds none."""
    try:
        return bool(tiles_done(url).any())
    except StoreError:
        return False


def _moved(dx):
    def scene():
        cube, sphere = meshes()
        return [replace(cube, vertices=cube.vertices + [dx, 0, 0]), sphere]

    return scene


def _recoloured():
    cube, sphere = meshes()
    return [cube, replace(sphere, texture=sphere.texture[..., ::-1])]


@pytest.mark.parametrize(
    "change, kw, part",
    [
        ("a cube moved 10 µm", {"scene": _moved(1e-5)}, "meshes"),
        ("the sphere's texture", {"scene": _recoloured}, "meshes"),
        ("the zone", {"zone_margin": 0.03}, "zone"),
        ("the seed", {"seed": 1}, "seed"),
        ("the coded look", {"code": (3, 2)}, "code"),
        ("the wavelength (the plan)", {"wavelength": 4.1e-5}, "plan"),
    ],
)
def test_the_digest_covers_what_the_samples_depend_on(recorded, scheduler, change, kw, part):
    """Resuming into the store with any of these changed is refused, naming the part (before
    any tile is summed), and the store is left as it was."""
    url, _ = recorded
    before = _files(url)
    with pytest.raises(
        InputError,
        match=rf"holds another recording \(its [^)]*\b{part}\b"
        rf"[^)]*differ",
    ):
        _record(url, scheduler, **kw)
    assert _files(url) == before


def test_a_tile_that_does_not_align_with_the_emitters_block_lists_is_refused(tmp_path):
    with pytest.raises(InputError, match=r"tile must be a multiple of 256 samples"):
        record_plate(meshes(), **SCENE, url=tmp_path / "p.zarr", tile=320)
    assert not list(tmp_path.iterdir())


SQUARES_OBJ = (
    "".join(  # two coloured squares 3 cm across, one 2 cm behind the other
        f"v {x:g} {y:g} {z:g} {r} {g} {b}\n"
        for z, dx, (r, g, b) in ((0.0, 0.0, (0.9, 0.2, 0.1)), (-0.02, 0.012, (0.1, 0.4, 0.9)))
        for x, y in (
            (dx - 0.015, -0.015),
            (dx + 0.015, -0.015),
            (dx + 0.015, 0.015),
            (dx - 0.015, 0.015),
        )
    )
    + "f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n"
)


def test_the_command_line_records_a_mesh_as_a_carrier_plate(scheduler, tmp_path, capsys):
    """``record MESH -o NAME.zarr`` records the plate of meshes against its zone's carrier (the
    camera and zone options as ``plan`` takes them), as ``-o NAME.exr`` does in memory: the
    two hold the same samples; ``render`` views the store from its zone's centre."""
    from cli import run_cli

    (tmp_path / "sq.obj").write_text(SQUARES_OBJ)
    common = ("--distance", 0.3, "--camera", 0, 0, 0.3, "--resolution", 160, 90, "--lens", 50)
    status, out, err = run_cli(
        capsys,
        "record",
        tmp_path / "sq.obj",
        "-o",
        tmp_path / "p.zarr",
        *common,
        "--tile",
        TILE,
        "--scheduler",
        scheduler,
    )
    assert status == 0, err
    assert "Dask dashboard: http" in out and "samples" in out
    status, _, err = run_cli(
        capsys, "record", tmp_path / "sq.obj", "-o", tmp_path / "p.exr", *common
    )
    assert status == 0, err
    tiled, whole = open_plate(tmp_path / "p.zarr"), read_hologram(tmp_path / "p.exr")
    assert tiled.carrier is not None and tiled.carrier == whole.carrier
    assert np.array_equal(tiled.object_wave[...], whole.object_wave)
    status, _, err = run_cli(
        capsys, "render", tmp_path / "p.zarr", "-o", tmp_path / "v.exr", "--resolution", 64, 36
    )
    assert status == 0 and (tmp_path / "v.exr").stat().st_size > 0, err


@pytest.mark.parametrize(
    "args, problem",
    [
        (["--pitch", "8e-6"], r"--pitch applies to point sums \(--method auto, direct or wrp\)"),
        (
            ["--method", "direct", "--camera", "0", "0", "0.3"],
            r"--camera applies to a plate of meshes \(--method zone, the default\)",
        ),
    ],
)
def test_options_of_the_other_route_are_refused_on_one_line(tmp_path, capsys, args, problem):
    from cli import run_cli

    (tmp_path / "sq.obj").write_text(SQUARES_OBJ)
    status, _, err = run_cli(capsys, "record", tmp_path / "sq.obj", "-o", tmp_path / "p.exr", *args)
    assert status == 2 and err.count("\n") == 1 and re.search(problem, err), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sq.obj"]


def test_the_physical_field_of_a_store_reads_only_the_tiles_under_its_region(
    in_memory, recorded, monkeypatch
):
    """physical_field over the window's first fifth along each axis reads the samples within
    the kernel's reach of it, all in tile (0, 0), and equals the field of the plate in memory."""
    url, _ = recorded
    reads = _Reads(monkeypatch)
    x0, y0, x1, y1 = window(in_memory)
    region = (x0, y0, x0 + 0.2 * (x1 - x0), y0 + 0.2 * (y1 - y0))
    tiled = physical_field(open_plate(url), 2, region=region)
    assert reads.tiles == {(0, 0)}
    assert np.array_equal(tiled.samples, physical_field(in_memory, 2, region=region).samples)


def test_looks_recorded_together_in_tiles_equal_them_in_memory(scheduler, tmp_path):
    """record_looks into one store a look sums every tile's looks in one task: each store
    equals that look in memory bit for bit; a look recorded alone finds its store whole (the
    same recording: nothing written again); four coded looks, whose first and last are the
    pair's, fill the two new stores and leave the pair's as they were, each new look within
    float32 rounding (1e-5 of the largest sample) of the look recorded alone (the looks
    together are summed by classes of equal code shifts and mixed)."""
    from holo_core.plate.look_codes import look_code
    from holo_core.plate.looks import record_looks

    urls = [tmp_path / f"look{k}.zarr" for k in range(2)]
    tiled = record_looks(meshes(), looks=2, urls=urls, tile=TILE, scheduler=scheduler, **SCENE)
    for h, want in zip(tiled, record_looks(meshes(), looks=2, **SCENE)):
        assert np.array_equal(h.object_wave[...], want.object_wave)
    before = [_files(u) for u in urls]
    alone = _record(urls[1], scheduler, code=look_code(1, 2))
    assert _files(urls[1]) == before[1]
    assert np.array_equal(alone.object_wave[...], tiled[1].object_wave[...])
    four = [urls[0], tmp_path / "a.zarr", tmp_path / "b.zarr", urls[1]]
    more = record_looks(meshes(), looks=4, urls=four, tile=TILE, scheduler=scheduler, **SCENE)
    assert [_files(u) for u in urls] == before
    for k in (1, 2):
        got, want = (
            more[k].object_wave[...],
            record_plate(meshes(), code=look_code(k, 4), **SCENE).object_wave,
        )
        assert np.max(np.abs(got - want)) <= 1e-5 * np.max(np.abs(want))


def test_the_pipeline_records_a_plate_beyond_memory_in_tiles(scheduler, tmp_path, monkeypatch):
    """A job's plate whose one look exceeds the memory budget is recorded tile by tile on Dask
    (the route's scheduler) into NAME.zarr beside each NAME.exr, no EXR written (one whose
    tiles exceed it too is refused as it is planned); its pass is the in-memory route's bit
    for bit; the next job finds the store whole and reads it. Either route makes one plan a
    job, checked once against the budget: the runner's checks, the recording and its tiles
    read that very plan."""
    from holo_core import runner
    from holo_core.job import Job, Output, PlateRoute
    from holo_core.plate import looks, tiles
    from holo_core.plate.plan import PlatePlan

    cam = camera("centre", SCALE)

    def job(folder, **route):
        holograms = (folder / "h.exr",)
        return Job(
            points=tuple(meshes()),
            camera=cam,
            output=Output(folder=folder, frame=1),
            route=PlateRoute(
                plate=PLATE, holograms=holograms, supersample=2, scheduler=scheduler, **route
            ),
        )

    assert runner._plan(job(tmp_path / "a"))[1] is None
    with pytest.raises(
        InputError,
        match=r"needs 0\.\d+ GiB of memory a tile at a time; the "
        r"memory budget is 0\.000931 GiB",
    ):
        runner._plan(job(tmp_path / "a", memory_budget=1e6))  # its tiles exceed it too
    made, checked, planned, read = [], [], [], []
    init, check, plan_job = PlatePlan.__init__, PlatePlan.check_recording, runner._plan
    monkeypatch.setattr(
        PlatePlan, "__init__", lambda p, *a, **k: made.append(1) or init(p, *a, **k)
    )
    monkeypatch.setattr(
        PlatePlan, "check_recording", lambda p, *a, **k: checked.append(1) or check(p, *a, **k)
    )
    monkeypatch.setattr(runner, "_plan", lambda j: planned.append(plan_job(j)) or planned[-1])
    for module in (looks, tiles):
        prepare = module.prepare_plate
        monkeypatch.setattr(
            module, "prepare_plate", lambda pl, _f=prepare, **k: read.append(pl.plan) or _f(pl, **k)
        )
    whole = runner.run(job(tmp_path / "a"))
    assert (len(made), len(checked)) == (1, 1), (
        f"the job in memory made {len(made)} plans and checked {len(checked)}"
    )
    monkeypatch.setattr(PlatePlan, "needs_tiles", lambda plan, limit: True)
    tiled = runner.run(job(tmp_path / "b"))
    assert (len(made), len(checked)) == (2, 2), (
        f"the tiled job made {len(made) - 1} plans and checked {len(checked) - 1}"
    )
    assert [p for p, _ in planned] and all(
        got is p.plan for got, (p, _) in zip(read, planned, strict=True)
    ), "the recording read another plan than the runner's"
    assert planned[-1][1] == [str(tmp_path / "b" / "h.zarr")]
    assert not (tmp_path / "b" / "h.exr").exists() and plate_current(tmp_path / "b" / "h.exr")
    assert np.array_equal(
        read_plate(tmp_path / "b" / "h.exr").object_wave[...],
        read_hologram(tmp_path / "a" / "h.exr").object_wave,
    )
    assert np.array_equal(tiled.view.rgb, whole.view.rgb)
    again = runner.run(job(tmp_path / "b", record=False))
    assert np.array_equal(again.view.rgb, whole.view.rgb)
