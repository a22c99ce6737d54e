"""The estimates: each stage a rate times its work plus the set-up said apart; the set-up of a
first run counted only where the kernel cache is cold; a calibration kept for its version and
device alone, a damaged one refused naming its file. (How close the estimates come to the
measured times is bench/estimates.py's: no timed test.)"""

import json
import logging
import os
import subprocess
import sys
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np
import plate_scene
import pytest

from holo_core import estimate
from holo_core.estimate import DEFAULT, Calibration, Estimate
from holo_core.plate.plan import plan, plan_view
from holo_core.plate.plan_summary import summary
from holo_core.scene.plate import ViewingZone

ROOT = Path(__file__).resolve().parents[2]
BOX = np.array([[-0.02, -0.015, -0.33], [0.025, 0.02, -0.28]])
ZONE = ViewingZone(centre=(0.01, -0.005, 0.3), half_extents=(0.04, 0.03, 0.02), pupil=0.05 / 2.8)
MEASURED = replace(
    DEFAULT,
    pairs_per_second=3e9,
    emitter_seconds=5e-5,
    view_factor=1.5,
    write_bytes_per_second=1e8,
    process_plate_seconds=2.5,
    first_plate_seconds=11.0,
)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A cache folder of its own, the device automatic."""
    monkeypatch.delenv("HOLO_DEVICE", raising=False)
    return tmp_path / "cache"


def planned():
    p = plan((0.1, 0.1), BOX, zone=ZONE, pixel_angle=0.036 / 640 / 0.05)
    v = plan_view(
        p,
        position=(0.01, -0.005, 0.3),
        pixel_angle=0.036 / 640 / 0.05,
        pupil=0.05 / 2.8,
        resolution=(640, 360),
    )
    return p, v


def warm_up(cache):
    """The kernel cache filled and the plate route's stamp left, as a worker leaves them."""
    kernels = estimate.kernel_cache(cache)
    kernels.mkdir(parents=True)
    (kernels / "a-program").write_bytes(b"\0")
    estimate.mark_warm("plate", cache_dir=cache)


def test_parts_are_rates_times_work_and_add_up(cache):
    """Each stage is its rate times the plan's work, counted here from the plan's own figures;
    the total is the stages, a new worker's set-up and a first run's."""
    p, v = planned()
    est = estimate.plate(p, v, cache_dir=cache, calibration=(MEASURED, True), load_average=0)
    work = dict(est.work)
    assert work == pytest.approx(
        {
            "job": MEASURED.job_seconds,
            "emitters": MEASURED.emitters_fixed + p.emitters * 5e-5,
            "zone sum": MEASURED.zone_sum_fixed + p.pairs() / 3e9,
            "files": 8 * 4 * p.looks * p.samples / 1e8,
            "view": MEASURED.view_fixed + 1.5 * v.seconds,
        },
        rel=1e-12,
    ), work
    assert est.process == 2.5 and est.first == 11.0
    assert est.seconds == pytest.approx(sum(work.values()) + 2.5 + 11.0, rel=1e-12)
    viewed = estimate.plate(
        p, v, record=False, cache_dir=cache, calibration=(MEASURED, True), load_average=0
    )
    assert [k for k, _ in viewed.work] == ["job", "view"], viewed.work


def test_a_warm_kernel_cache_removes_the_first_runs_set_up(cache):
    """Cold (no stamp, or the kernel cache gone): the first run's set-up is counted; once a
    job of the route has run with this cache, it is not, and the totals differ by exactly it."""
    p, v = planned()
    cal = (MEASURED, True)
    cold = estimate.plate(p, v, cache_dir=cache, calibration=cal, load_average=0)
    warm_up(cache)
    assert estimate.is_warm("plate", cache_dir=cache)
    assert not estimate.is_warm("camera", cache_dir=cache)  # its programs are not the plate's
    warm = estimate.plate(p, v, cache_dir=cache, calibration=cal, load_average=0)
    assert (cold.first, warm.first) == (11.0, 0.0)
    assert cold.seconds - warm.seconds == pytest.approx(11.0, rel=1e-12)
    assert "first time" in cold.words() and "first time" not in warm.words(), warm.words()
    for f in estimate.kernel_cache(cache).iterdir():  # the kernel cache emptied: cold again
        f.unlink()
    assert estimate.plate(p, v, cache_dir=cache, calibration=cal, load_average=0).first == 11.0


def test_the_stamp_is_this_devices(cache, monkeypatch):
    """A stamp left on another device does not make this one warm."""
    warm_up(cache)
    monkeypatch.setenv("HOLO_DEVICE", "gpu")
    assert not estimate.is_warm("plate", cache_dir=cache)
    assert estimate.is_warm("plate", device="", cache_dir=cache)


def test_a_calibration_is_kept_and_read_back_for_its_version_and_device(cache):
    path = estimate.save(MEASURED, cache_dir=cache)
    assert path == cache / "holo" / estimate.FILE
    assert estimate.load(cache_dir=cache) == (MEASURED, True)
    assert estimate.load(device="gpu", cache_dir=cache) == (DEFAULT, False)


@pytest.mark.parametrize("field, value", [("version", "0.0.1"), ("device", "gpu")])
def test_a_calibration_of_another_version_or_device_is_ignored(cache, field, value, caplog):
    path = estimate.save(MEASURED, cache_dir=cache)
    data = json.loads(path.read_text())
    data[field] = value
    path.write_text(json.dumps(data))
    with caplog.at_level(logging.INFO, "holo_core.estimate"):
        assert estimate.load(cache_dir=cache) == (DEFAULT, False)
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING], caplog.text
    assert str(path) in caplog.text and value in caplog.text, caplog.text


@pytest.mark.parametrize(
    "text",
    ["{not json", json.dumps({"version": "x", "device": ""}), "BAD_RATE", "MISSING_RATE", "\udcff"],
)
def test_a_bad_calibration_is_refused_with_a_warning_naming_it(cache, text, caplog):
    path = estimate.save(MEASURED, cache_dir=cache)
    data = json.loads(path.read_text())
    if text == "BAD_RATE":
        data["rates"]["pairs_per_second"] = -1.0
        text = json.dumps(data)
    elif text == "MISSING_RATE":
        del data["rates"]["view_factor"]
        text = json.dumps(data)
    if text == "\udcff":
        path.write_bytes(b"\xff\xfe{")
    else:
        path.write_text(text)
    with caplog.at_level(logging.WARNING, "holo_core.estimate"):
        assert estimate.load(cache_dir=cache) == (DEFAULT, False)
    warned = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warned) == 1 and str(path) in warned[0], warned


@pytest.mark.parametrize(
    "field, value",
    [
        ("pairs_per_second", 0.0),
        ("job_seconds", -1.0),
        ("view_factor", float("nan")),
        ("process_camera_seconds", True),
    ],
)
def test_a_calibration_refuses_what_is_not_a_rate(field, value):
    with pytest.raises(ValueError, match=field):
        Calibration(**{**asdict(DEFAULT), field: value})


def test_other_work_on_the_machine_scales_every_part_by_its_fair_share(cache):
    """A load of L other runnable processes on C CPUs leaves a job that would use them all
    C / (C + L) of them: every part takes 1 + L / C times as long, and the words say so."""
    assert estimate.slowdown(0.0, 2) == 1.0 and estimate.slowdown(3.0, 2) == 2.5
    p, v = planned()
    idle = estimate.plate(p, v, cache_dir=cache, calibration=(MEASURED, True), load_average=0)
    busy = estimate.plate(p, v, cache_dir=cache, calibration=(MEASURED, True), load_average=3.0)
    k = busy.slowdown
    assert k == pytest.approx(estimate.slowdown(3.0)) and k > 1
    assert busy.seconds == pytest.approx(k * idle.seconds, rel=1e-12)
    assert [s for _, s in busy.work] == pytest.approx([k * s for _, s in idle.work], rel=1e-12)
    assert "times an idle machine's time" in busy.words(), busy.words()
    assert "idle" not in idle.words(), idle.words()


@pytest.mark.skipif(not Path("/proc/stat").is_file(), reason="the CPUs' ticks are Linux's")
def test_the_present_load_counts_other_work_now_not_the_minute_before():
    """busy_cpus: a process spinning on one CPU while the sample is taken counts as about one
    busy CPU (other work on the machine may add to it, never take from it); once it has
    ended it no longer counts, where the 1-minute load average would still hold most of it."""
    import subprocess
    import sys
    import time

    cpus = len(os.sched_getaffinity(0))
    spin = subprocess.Popen(
        [sys.executable, "-c", "import time\nt = time.time()\nwhile time.time() - t < 3: pass"]
    )
    try:
        time.sleep(0.5)
        busy = estimate.busy_cpus(0.5)
    finally:
        spin.wait()
    assert 0.7 <= busy <= cpus + 1e-9, busy
    after = estimate.busy_cpus(0.5)
    assert 0.0 <= after <= cpus + 1e-9 and after < busy - 0.4, (busy, after)


def test_the_words_say_the_set_up_apart():
    est = Estimate(work=(("a", 3.0), ("b", 1.6)), process=2.4, first=4.0, calibrated=True)
    assert est.words() == (
        "about 11 s (of which 4 s the first time on this machine, 2 s starting the worker)"
    )
    bare = Estimate(work=(("a", 3.0),), calibrated=False)
    assert bare.words().startswith("about 3 s; by default rates"), bare.words()


def test_the_plan_states_the_first_frames_time_with_its_set_up(cache):
    """The planner's time line is the estimate's words (a cold cache: the first time said)."""
    estimate.save(MEASURED, cache_dir=cache)
    p, v = planned()
    lines = summary(
        p,
        v,
        lens="50 mm f/2.8",
        resolution=(640, 360),
        plate_size=(0.1, 0.1),
        camera=(0.01, -0.005, 0.3),
        cache_dir=cache,
        load_average=0,
    )
    said = estimate.plate(p, v, cache_dir=cache, load_average=0).words()
    time = next(line for line in lines if line.startswith("time"))
    assert said in time and "11 s the first time on this machine" in time, time


def test_a_camera_pass_costs_its_fine_pixels_once_and_each_look():
    """Speckle: Looks costs the fine pixels once and each look; Exact, one pass of them."""
    exact = estimate.camera(
        (640, 360),
        samples=16,
        supersample=2,
        warm=True,
        calibration=(MEASURED, True),
        load_average=0,
    )
    assert dict(exact.work)["camera pass"] == pytest.approx(
        MEASURED.exact_fixed + 640 * 360 * 4 * MEASURED.exact_pixel_seconds, rel=1e-12
    )
    est = estimate.camera(
        (640, 360),
        samples=16,
        supersample=2,
        speckle="LOOKS",
        warm=True,
        calibration=(MEASURED, True),
        load_average=0,
    )
    assert dict(est.work)["camera pass"] == pytest.approx(
        MEASURED.camera_fixed
        + 640 * 360 * 4 * (MEASURED.camera_pixel_seconds + 16 * MEASURED.camera_look_seconds),
        rel=1e-12,
    )
    assert est.process == MEASURED.process_camera_seconds and est.first == 0.0


def test_a_cold_camera_pass_counts_the_plans_of_the_lengths_it_transforms():
    """FFTW's measuring of a length grows with the ways it factors (τ(L)^1.5 a problem, and
    FFT_PROBLEMS problems a length): 1440 = 2⁵·3²·5 (36 divisors) costs 36^1.5 / 4^1.5 = 27
    times 343 = 7³; each length counts once, and only where the cache is cold."""
    assert [estimate.divisors(n) for n in (1, 7, 343, 1440, 3600)] == [1, 2, 4, 36, 45]
    one = estimate.fft_plans([343], MEASURED)
    assert one == pytest.approx(estimate.FFT_PROBLEMS * MEASURED.fft_plan_seconds * 8)
    assert estimate.fft_plans([1440, 1440], MEASURED) == pytest.approx(27 * one)
    kw = {"samples": 16, "supersample": 2, "calibration": (MEASURED, True), "load_average": 0}
    cold = estimate.camera((640, 360), warm=False, lengths=(343, 1440), **kw)
    assert cold.first == pytest.approx(MEASURED.first_camera_seconds + 28 * one)
    assert estimate.camera((640, 360), warm=True, lengths=(343, 1440), **kw).first == 0.0


def test_a_camera_jobs_lengths_are_its_optics_grids_found_without_a_driver():
    """A camera job's FFT lengths are those of the optics its emitters' depths choose (the
    pupil's grid, its images' twice as fine, and their read grid for Speckle: Exact), found
    by pure arithmetic: the estimate, in Blender's process, loads neither OpenCL nor FFTW."""
    code = (
        "import sys\n"
        "sys.path.insert(0, 'tests')\n"
        "import plate_scene\n"
        "from holo_core import estimate\n"
        "from holo_core.job import CameraRoute, Job, Output\n"
        "job = Job(camera=plate_scene.camera(scale=0.25), route=CameraRoute(),\n"
        "          triangles=tuple(plate_scene.meshes()), output=Output(folder='out'))\n"
        "print(list(estimate.camera_lengths(job)))\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in "
        "('pyopencl', 'pyfftw', 'pyvkfft', 'holo_core') and ('opencl' in m or 'fft' in m)))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    ).stdout.splitlines()
    assert out[1] == "[]", out
    lengths = eval(out[0])
    from holo_core.camera.optics import choose_optics, read_shape
    from holo_core.camera.raster import depth_range

    cam = plate_scene.camera(scale=0.25)
    h, w = choose_optics(cam, depth_range(plate_scene.meshes(), cam)).shape
    assert lengths == list(dict.fromkeys([h, w, 2 * h, 2 * w, *read_shape((2 * h, 2 * w))]))


def test_a_sets_parts_add_up_and_each_parts_files_are_written_beside_the_next_sum(cache):
    """estimate.plate_set: the emitters found for each lattice and seen from each part, every
    part's set-up and zone sum (its files' digest beside it), and of the files only what
    outlasts the next part's sum, the last part's whole; Plan Plate's set line says it in
    words."""
    from holo_core.plate.path import SetPlan

    p, _ = planned()
    rates = replace(MEASURED, write_bytes_per_second=p.disk_bytes() / 4.0)  # 4 s a part
    s = SetPlan(plans=(p, p, p), length=0.3, lattices=2)
    est = estimate.plate_set(s, calibration=(rates, True), warm=True, load_average=0)
    work = dict(est.work)
    found = rates.emitters_fixed + p.emitters * rates.emitter_seconds
    summed = rates.zone_sum_fixed + p.pairs() / rates.pairs_per_second
    assert work["emitters"] == pytest.approx(
        2 * found + 3 * p.emitters * estimate.VISIBILITY_SECONDS
    )
    assert work["parts"] == pytest.approx(3 * estimate.PART_SECONDS)
    assert work["zone sums"] == pytest.approx(
        3 * (summed + p.disk_bytes() / estimate.DIGEST_BYTES_PER_SECOND)
    )
    assert work["files"] == pytest.approx(2 * max(4.0 - summed, 0.0) + 4.0)
    assert est.seconds == pytest.approx(sum(work.values()) + rates.process_plate_seconds)
    assert "records in about" in s.describe(est)
    assert "development machine" in s.describe()
