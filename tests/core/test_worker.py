"""The worker process (the add-on's compute path): the same pass as in-process, clear reports
when it fails or dies, cancellation within a second, and earlier files left intact."""

import dataclasses
import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest

from holo_core import jobs, runner, worker
from holo_core.job import CameraRoute, Job, Output, PlateRoute
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.mesh import Mesh
from holo_core.scene.plate import Plate
from holo_core.validate import InputError


def cube(size=0.4):
    c = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * size / 2
    faces = [
        [0, 1, 3],
        [0, 3, 2],
        [4, 6, 7],
        [4, 7, 5],
        [0, 4, 5],
        [0, 5, 1],
        [2, 3, 7],
        [2, 7, 6],
        [0, 2, 6],
        [0, 6, 4],
        [1, 5, 7],
        [1, 7, 3],
    ]
    return Mesh(vertices=c, triangles=np.array(faces), colours=np.full((8, 3), 0.8))


def job(tmp_path, *, resolution=(32, 24), iterations=1, route=None, **output):
    """A plate of a cube and its view (or ``route``'s), frame 1 into ``tmp_path/holo``."""
    plate = Plate(
        matrix_world=look_at((0, -1.5, 0), (0, 0, 0), up=(0, 0, 1)), width=0.6, height=0.6
    )
    cam = Camera(matrix_world=look_at((0, -3.0, 0), (0, 0, 0), up=(0, 0, 1)), resolution=resolution)
    out = tmp_path / "holo"
    route = route or PlateRoute(
        plate=plate, supersample=1, holograms=tuple(out / f"h{i}.exr" for i in range(iterations))
    )
    return Job(
        points=(cube(),), camera=cam, route=route, output=Output(folder=out, frame=1, **output)
    )


def _pass(path):
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        return {k: v.pixels.copy() for k, v in f.channels().items()}


def test_worker_renders_what_the_process_itself_renders(tmp_path):
    """The same job in a worker process and in this one: the same pass, bit for bit (same
    device choice, same seeds), and the progress reaches 1."""
    seen, logs = [], []
    there = worker.run(job(tmp_path / "a"), seen.append, lambda *r: logs.append(r))
    here = runner.run(job(tmp_path / "b"))
    assert there.view is None and here.view is not None  # the pass file holds it
    assert there.report.plan.aperture == here.report.plan.aperture > 0
    a, b = _pass(there.pass_path), _pass(here.pass_path)
    assert a.keys() == b.keys()
    for k in a:
        assert np.array_equal(a[k], b[k]), k
    assert np.asarray(a["ViewLayer.Combined.A"]).max() == 1.0, "the cube is missing"
    assert seen and seen[-1] == pytest.approx(1.0) and seen == sorted(seen)
    assert any("sampling" in text for _, text in logs), logs


def _earlier(j):
    out = j.output.folder
    out.mkdir(parents=True)
    files = {p: os.urandom(64) for p in (j.route.holograms[0], j.output.pass_path)}
    for p, data in files.items():
        p.write_bytes(data)
    return files


def _unchanged(files, out):
    for p, data in files.items():
        assert p.read_bytes() == data, f"{p.name} changed by a run that did not finish"
    assert sorted(x.name for x in out.iterdir()) == sorted(p.name for p in files)


def test_cancel_kills_the_worker_within_a_second_and_keeps_earlier_files(tmp_path):
    j = job(tmp_path, resolution=(320, 240), iterations=3)
    files = _earlier(j)
    w = worker.Worker(j)
    while not any(kind == "progress" for kind, _ in w.poll(timeout=0.1)):
        assert not w.finished, "the worker ended before its first progress report"
    t = time.perf_counter()
    w.cancel()
    elapsed = time.perf_counter() - t
    assert w.process.returncode == -signal.SIGKILL and elapsed < 1.0, elapsed
    assert not w.folder.exists()
    _unchanged(files, j.output.folder)


def test_cancel_from_the_progress_callback(tmp_path):
    j = job(tmp_path)
    files = _earlier(j)
    calls = []

    def progress(f):
        calls.append(f)
        if len(calls) > 1:
            raise jobs.Cancelled()

    with pytest.raises(jobs.Cancelled):
        worker.run(j, progress)
    assert len(calls) == 2
    _unchanged(files, j.output.folder)


def test_a_killed_worker_is_a_clear_report(tmp_path):
    """SIGKILL is what the kernel's out-of-memory killer sends."""
    j = job(tmp_path, resolution=(320, 240), iterations=3)
    files = _earlier(j)
    w = worker.Worker(j)
    while not any(kind == "progress" for kind, _ in w.poll(timeout=0.1)):
        pass
    os.kill(w.process.pid, signal.SIGKILL)
    with pytest.raises(
        worker.WorkerError,
        match=r"ended with signal SIGKILL \(killed: out of "
        r"memory\?\)",
    ):
        w.wait()
    _unchanged(files, j.output.folder)


class _Segfault:
    """Unpickled in the worker, reads address 0: a genuine crash in native code."""

    def __reduce__(self):
        import ctypes

        return ctypes.string_at, (0,)


def test_a_crashed_worker_is_a_clear_report(tmp_path, monkeypatch):
    """A segmentation fault (as in a broken OpenCL driver) ends the worker, not the parent."""
    j = job(tmp_path)
    files = _earlier(j)
    plain = Job.to_dict
    monkeypatch.setattr(Job, "to_dict", lambda self: {**plain(self), "crash": _Segfault()})
    with pytest.raises(worker.WorkerError, match=r"signal SIGSEGV \(a crash in native code"):
        worker.run(j)
    _unchanged(files, j.output.folder)


def test_a_raising_worker_reports_its_error_and_writes_nothing(tmp_path):
    j = job(tmp_path)
    files = _earlier(j)
    # the 'current' hologram is the random bytes above: not an EXR
    j = dataclasses.replace(j, route=dataclasses.replace(j.route, record=False))
    with pytest.raises(worker.WorkerError, match=r"h0.exr: not an OpenEXR file"):
        worker.run(j)
    _unchanged(files, j.output.folder)


def test_stop_and_keep_hands_over_a_complete_running_pass(tmp_path):
    """A camera hologram stopped after its first running passes: the pass kept is a whole
    file of that many samples (not the cancelled run's nothing)."""
    j = job(
        tmp_path,
        resolution=(160, 120),
        route=CameraRoute(speckle="LOOKS", samples=64, supersample=1),
    )
    w = worker.Worker(j)
    while not any(kind == "partial" and n >= 2 for kind, n in w.poll(timeout=0.1)):
        assert not w.finished, "the worker ended before its second running pass"
    kept = w.stop_and_keep(tmp_path / "kept.exr")
    assert kept >= 2 and w.process.returncode == -signal.SIGKILL
    p = _pass(tmp_path / "kept.exr")
    assert np.asarray(p["ViewLayer.Combined.A"]).max() == 1.0, "the cube is missing"
    assert (tmp_path / "kept.png").is_file() and not w.folder.exists()


def test_the_cache_folder_reaches_the_worker(tmp_path):
    """The add-on's Cache Folder: the worker keeps its OpenCL kernel cache (and, on CPU
    devices, its FFTW wisdom) under it."""
    cache = tmp_path / "cache"
    assert worker.environment((), None, None, str(cache))["XDG_CACHE_HOME"] == str(cache)
    worker.Worker(job(tmp_path), cache_dir=str(cache)).wait()
    assert any((cache / name).is_dir() for name in ("pyopencl", "holo")), (
        list(cache.iterdir()) if cache.exists() else "no cache folder"
    )


def test_an_unwritable_output_folder_is_refused_before_the_recording(tmp_path, monkeypatch):
    """The add-on's worker refuses a pass or hologram it cannot write with an InputError
    before anything is recorded (/sys is read-only even for root)."""
    recorded = []
    monkeypatch.setattr(runner, "record_planned", lambda *a, **k: recorded.append(1))
    j = job(tmp_path)
    j = dataclasses.replace(
        j,
        output=Output(folder=Path("/sys/holo")),
        route=dataclasses.replace(j.route, holograms=(Path("/sys/holo/h0.exr"),)),
    )
    with pytest.raises(InputError, match="/sys"):
        runner.run(j)
    assert recorded == [], "the recording ran before the output was checked"


def test_a_plate_larger_than_the_disks_room_is_refused_before_the_recording(tmp_path, monkeypatch):
    """A plate's files that would not fit on the disk that takes them are an InputError
    naming the folder, the room they need and the room there is, before anything is
    recorded (a full disk found after the recording lost it: the shot's 16 s)."""
    import shutil

    from holo_core.io import image

    recorded = []
    monkeypatch.setattr(runner, "record_planned", lambda *a, **k: recorded.append(1))
    j = job(tmp_path, iterations=2)
    p = runner.plate_plan(list(j.points), plate=j.route.plate, camera=j.camera).plan
    need = 2 * p.disk_bytes() / p.looks  # two looks
    usage = shutil.disk_usage(tmp_path)
    monkeypatch.setattr(
        image.shutil, "disk_usage", lambda path: usage._replace(free=int(need * 0.99))
    )
    number = r"[\d.]+(e-\d+)?"
    with pytest.raises(
        InputError,
        match=rf"the plate's 2 look\(s\) .* need {number} GiB on "
        rf"disk, and {tmp_path} has {number} GiB free",
    ):
        runner.run(j)
    assert recorded == [], "the recording ran before the disk's room was checked"
    monkeypatch.undo()  # the disk's own room, enough: the plate is recorded and written
    assert runner.run(j).recorded == j.route.holograms


def test_a_plates_iterations_are_coded_looks_of_one_seed(tmp_path):
    """Two iterations of a plate are the checkerboard pair of one seed (look_code): the first
    is the seed's plain recording, the second its coded partner, within float32 rounding
    (1e-5 of the largest sample: recorded together, the pair is summed by the classes of
    equal code shifts and mixed); bare points refuse a code (their looks take independent
    seeds)."""
    from holo_core.io.hologram import read_hologram
    from holo_core.plate.record import record_hologram

    j = job(tmp_path, iterations=2, render=False)
    result = runner.run(j)
    assert result.recorded == j.route.holograms and result.pass_path is None
    a, b = (read_hologram(p) for p in j.route.holograms)
    assert not np.array_equal(a.object_wave, b.object_wave), "the looks are one recording"
    same = dict(plate=j.route.plate, camera=j.camera, seed=0)
    for code, look in ((None, a), ((3, 2), b)):
        h = record_hologram(list(j.points), code=code, **same)
        assert np.max(np.abs(h.object_wave - look.object_wave)) <= 1e-5 * np.max(
            np.abs(h.object_wave)
        ), code
    with pytest.raises(InputError, match="code applies to plates of meshes"):
        record_hologram(
            (np.array([[0.0, 0.0, -1.0]]), np.ones((1, 3))),
            plate=j.route.plate,
            resolution=64,
            code=(1, 2),
        )


def _moved(j, frame, x):
    """``j`` as frame ``frame``, its camera moved to ``x`` [m] and the plate read, not
    recorded."""
    cam = dataclasses.replace(j.camera, matrix_world=look_at((x, -3.0, 0), (0, 0, 0), up=(0, 0, 1)))
    return dataclasses.replace(
        j,
        camera=cam,
        route=dataclasses.replace(j.route, record=False),
        output=dataclasses.replace(j.output, frame=frame),
    )


def test_a_resident_worker_renders_the_next_frames_from_the_plate_it_holds(tmp_path):
    """A render's frames in the process kept between them: the first records the plate, the
    next render from it held in memory (said in the log; the same process), each pass equal
    bit for bit to a fresh worker's that reads the files; a plate file written again since
    is read again; release() ends the process."""
    first = job(tmp_path, iterations=2)
    logs = []
    try:
        worker.run(first, resident=True)
        pid = worker._resident.popen.pid
        frames = [_moved(first, 2, 0.05), _moved(first, 3, -0.05)]
        for j in frames:
            kept = worker.run(j, on_log=lambda *r: logs.append(r[1]), resident=True)
            fresh = worker.run(
                dataclasses.replace(
                    j, output=dataclasses.replace(j.output, folder=tmp_path / "fresh")
                )
            )
            a, b = _pass(kept.pass_path), _pass(fresh.pass_path)
            assert all(np.array_equal(a[k], b[k]) for k in a), "the held plate's view differs"
        assert worker._resident.popen.pid == pid, "a frame started a process of its own"
        assert sum("held in memory from the job before: 2 of 2" in t for t in logs) == 2, logs
        # the plate recorded again (another seed) by another process: read again
        again = dataclasses.replace(
            first,
            route=dataclasses.replace(first.route, seed=7),
            output=dataclasses.replace(first.output, render=False),
        )
        runner.run(again)
        logs.clear()
        kept = worker.run(frames[0], on_log=lambda *r: logs.append(r[1]), resident=True)
        fresh = worker.run(
            dataclasses.replace(
                frames[0], output=dataclasses.replace(frames[0].output, folder=tmp_path / "fresh")
            )
        )
        assert not any("held in memory" in t for t in logs), logs
        a, b = _pass(kept.pass_path), _pass(fresh.pass_path)
        assert all(np.array_equal(a[k], b[k]) for k in a), "the rewritten plate was not read"
        process = worker._resident.popen
    finally:
        worker.release()
    assert process.poll() is not None and worker._resident is None


def test_a_cancelled_resident_job_ends_its_process_and_the_next_starts_afresh(tmp_path):
    j = job(tmp_path, resolution=(320, 240), iterations=3)
    try:
        w = worker.Worker(j, resident=True)
        while not any(kind == "progress" for kind, _ in w.poll(timeout=0.1)):
            assert not w.finished, "the worker ended before its first progress report"
        w.cancel()
        assert w.process.returncode == -signal.SIGKILL and worker._resident is None
        result = worker.run(job(tmp_path / "next"), resident=True)
        assert result.pass_path.is_file() and worker._resident.popen.poll() is None
    finally:
        worker.release()


def test_a_serving_worker_ends_when_its_parent_goes_or_it_is_left_idle(tmp_path):
    """Its stdin closed (the parent ended) or no job for the idle time: it ends, freeing what
    it held."""
    import subprocess
    import sys

    env = worker.environment()
    for code, close in (("runner.serve(idle=600)", True), ("runner.serve(idle=0.5)", False)):
        p = subprocess.Popen(
            [sys.executable, "-c", f"from holo_core import runner; {code}"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            env=env,
        )
        if close:
            p.stdin.close()
        try:
            assert p.wait(timeout=20) == 0
        finally:
            p.kill()
            p.wait()
            for stream in (p.stdin, p.stdout):
                stream.close()


def test_a_resident_worker_near_its_idle_end_is_not_handed_a_job(tmp_path):
    """A kept process idle for nearly IDLE_SECONDS may be ending on its own: the next job
    goes to a fresh one, and the old one is closed."""
    try:
        worker.run(job(tmp_path / "a"), resident=True)
        old = worker._resident
        old.idle_since -= worker.IDLE_SECONDS - worker.IDLE_GRACE
        worker.run(job(tmp_path / "b"), resident=True)
        assert worker._resident is not old and old.popen.poll() is not None
    finally:
        worker.release()


def test_the_core_s_warnings_reach_the_report(tmp_path):
    """A view that resolves less than its plate was recorded for (the camera stopped down
    from f/2.8 to f/8): the core's Python warning is in the job's report, which the add-on
    shows; the camera it was recorded for reports none of it."""
    made = job(tmp_path)
    cam = dataclasses.replace(made.camera, lens=50.0, fstop=2.8, focus_distance=3.0)
    made = dataclasses.replace(made, points=(), triangles=(cube(),), camera=cam)
    first = runner.run(made)
    assert not [w for w in first.report.warnings if "resolves" in w], first.report.warnings
    stopped = dataclasses.replace(
        made,
        camera=dataclasses.replace(cam, fstop=8.0),
        route=dataclasses.replace(made.route, record=False),
    )
    said = [w for w in runner.run(stopped).report.warnings if "resolves" in w]
    assert len(said) == 1 and "where a sharp view resolves 0.5" in said[0], said


def test_a_plate_replaced_by_another_scenes_valid_plate_is_refused_never_rendered(tmp_path):
    """A plate file replaced by another scene's valid plate under its name (a farm folder
    synced from another shot, a file copied by hand, a restored backup) was rendered as this
    scene's, exit 0. A plate carries the digest of the recording it is; the worker reading it
    for another recording refuses it, naming the file, and writes no pass."""
    from holo_core.io.hologram import recording_of

    ours, theirs = "a1" * 8, "b2" * 8

    def named(j, recording, **route):
        return dataclasses.replace(
            j, route=dataclasses.replace(j.route, recording=recording, **route)
        )

    mine = named(job(tmp_path / "mine", render=False), ours)
    other = named(
        dataclasses.replace(job(tmp_path / "other", render=False), points=(cube(0.25),)), theirs
    )
    for j in (mine, other):
        runner.run(j)
    plate = mine.route.holograms[0]
    assert recording_of(plate) == ours and recording_of(other.route.holograms[0]) == theirs
    again = named(mine, ours, record=False)
    again = dataclasses.replace(again, output=dataclasses.replace(again.output, render=True))
    assert runner.run(again).pass_path.is_file()  # its own plate: rendered
    plate.write_bytes(other.route.holograms[0].read_bytes())
    frame2 = dataclasses.replace(again, output=dataclasses.replace(again.output, frame=2))
    with pytest.raises(
        worker.WorkerError,
        match=rf"{plate}: holds recording {theirs}, not "
        rf"{ours} \(this scene's\): another "
        rf"recording's plate under this name is never "
        rf"rendered",
    ):
        worker.run(frame2)
    assert not frame2.output.pass_path.exists()
