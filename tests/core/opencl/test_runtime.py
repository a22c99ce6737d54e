"""Device choice (probed devices only), the CLI listing, packaged drivers, kernels built once,
and the house rules on imports."""

import os
import pathlib
import re
import subprocess
import sys
import time

import numpy as np
import pytest

from holo_core.opencl import all_devices, choose_device, device_table, runtime
from holo_core.opencl.icd import packaged_drivers
from holo_core.propagation.convolution import PROGRAM

ROOT = pathlib.Path(__file__).resolve().parents[3]


def test_device_choice_by_type_index_and_name():
    devices = all_devices()
    assert devices, "OpenCL sees no device (PoCL should provide one)"
    p, d, first = devices[0]
    assert choose_device(f"{p}:{d}").int_ptr == first.int_ptr
    assert choose_device(first.name[:6]).name == first.name
    cpu = [dev for _, _, dev in devices if "CPU" in str(dev.type) or dev.type & 2]
    if cpu:
        assert choose_device("cpu").type & 2


def test_default_prefers_a_gpu_else_a_cpu(monkeypatch):
    monkeypatch.delenv("HOLO_DEVICE", raising=False)
    dev = choose_device()
    has_gpu = any(d.type & 4 for _, _, d in all_devices())
    assert bool(dev.type & 4) == has_gpu


def test_unknown_device_names_the_variable_and_the_choices(monkeypatch):
    monkeypatch.setenv("HOLO_DEVICE", "no-such-device")
    with pytest.raises(
        ValueError,
        match=r"HOLO_DEVICE='no-such-device' names no usable device; "
        r"allowed: 'gpu', 'cpu'.*Usable: \d+:\d+ ",
    ):
        choose_device()


def test_devices_command_lists_each_status_and_what_it_would_use():
    out = subprocess.run(
        [sys.executable, "-m", "holo_core", "devices"],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    ).stdout
    assert re.search(r"^\s*\d+:\d+ .*: usable\s+<- would use$", out, re.M), out
    assert len(re.findall(r"^\s*\d+:\d+ ", out, re.M)) == len(all_devices()), out


def _broken(monkeypatch, source):
    """Every probe runs ``source`` instead of the real probe (results not cached)."""
    monkeypatch.setattr(runtime, "_PROBE", source)
    monkeypatch.setattr(runtime, "_probed", {})


def test_a_device_whose_probe_fails_is_skipped_with_its_reason(monkeypatch, caplog):
    monkeypatch.delenv("HOLO_DEVICE", raising=False)
    _broken(monkeypatch, "__kernel void probe(__global float *x) { this is not C; }")
    with pytest.raises(
        RuntimeError,
        match=r"no usable OpenCL device \(\d+:\d+ .*: "
        r"(BuildProgramFailure|RuntimeError|LogicError)",
    ):
        choose_device()
    assert "skipped" in caplog.text
    assert all(status != "usable" and not chosen for _, status, chosen in device_table())


def _usable():
    """The names of the devices whose real probe passes (a driver that cannot build any
    program on this CPU, as PoCL's LLVM 14 on Zen 5, never reaches the probe's result)."""
    return {name for name, status, _ in device_table() if status == "usable"}


def test_a_device_with_a_wrong_probe_result_is_skipped(monkeypatch):
    usable = _usable()
    _broken(monkeypatch, runtime._PROBE.replace("cmul(cexpi(x[i])", "cmul(cexpi(1.1f * x[i])"))
    rows = [(name, status) for name, status, _ in device_table() if name in usable]
    assert rows and all(s.startswith("wrong probe result") for _, s in rows), rows


def test_a_failed_device_gives_way_to_the_next_and_a_choice_of_it_lists_what_works(monkeypatch):
    monkeypatch.delenv("HOLO_DEVICE", raising=False)
    usable = len(_usable())
    devices = sorted(all_devices(), key=lambda t: runtime._rank(t[2]))
    first = devices[0][2]
    monkeypatch.setattr(runtime, "_probed", {first.int_ptr: "broken on purpose"})
    if usable > 1:
        assert choose_device().int_ptr != first.int_ptr
    spec = f"{devices[0][0]}:{devices[0][1]}"
    with pytest.raises(
        ValueError,
        match=rf"HOLO_DEVICE='{spec}' names no usable device "
        rf"\({spec} .*: broken on purpose\).*Usable: ",
    ):
        choose_device(spec)


def test_packaged_intel_runtime_is_found_and_registered():
    """Where intel-opencl-rt is installed (Linux x86-64), its library is named in the vendor
    folder the loader reads, and OpenCL lists its platform."""
    drivers = packaged_drivers()
    if "intel-cpu.icd" not in drivers:
        pytest.skip("intel-opencl-rt is not installed for this platform")
    folder = pathlib.Path(os.environ["OCL_ICD_VENDORS"])
    assert (folder / "intel-cpu.icd").read_text().strip() == drivers["intel-cpu.icd"]
    assert any("intel" in dev.platform.name.lower() for _, _, dev in all_devices())


def test_core_and_physics_tests_never_load_blender(tmp_path):
    """pytest imports the repository root (the extension's entry point) for every test: that
    must not import bpy, so the core's tests run where Blender cannot."""
    (tmp_path / "spy.py").write_text(
        "import sys\n"
        "def pytest_sessionfinish(session):\n"
        f"    with open({str(tmp_path / 'bpy.txt')!r}, 'w') as f:\n"
        "        f.write(str('bpy' in sys.modules))\n"
    )
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "-p",
            "spy",
            "tests/core/test_validation.py",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env={
            **os.environ,
            "PYTHONPATH": os.pathsep.join(
                [str(tmp_path)] + [p for p in [os.environ.get("PYTHONPATH")] if p]
            ),
        },
    )
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert (tmp_path / "bpy.txt").read_text() == "False"


def test_programs_and_kernels_are_built_once(rt):
    k1 = rt.kernel(PROGRAM, "multiply")
    assert rt.kernel(PROGRAM, "multiply") is k1
    assert rt.program(PROGRAM) is rt.program(PROGRAM)


def test_fft_backend_round_trip(rt, rng):
    a = (rng.normal(size=(48, 40)) + 1j * rng.normal(size=(48, 40))).astype(np.complex64)
    dev = rt.to_device(a)
    rt.fft.forward(dev)
    assert np.allclose(dev.get(), np.fft.fft2(a), atol=1e-3)
    rt.fft.backward(dev)
    assert np.allclose(dev.get() / a.size, a, atol=1e-5)


HOLD_LOCK = """
import os, sys, time
fd = os.open(sys.argv[1], os.O_CREAT | os.O_WRONLY | os.O_EXCL)  # as pyopencl takes it
print("held", flush=True)
time.sleep(600)
"""
NEVER_WAIT = """
import sys, time
class Waited(BaseException):
    pass
sleep = time.sleep
def never(seconds):  # pyopencl waits on its cache lock in steps of 50 ms
    if sys._getframe(1).f_globals["__name__"].startswith("pyopencl"):
        raise Waited(f"pyopencl waited {seconds} s on its cache lock")
    sleep(seconds)
time.sleep = never
from holo_core.opencl import get_runtime
print("device", get_runtime().device.name)
"""


@pytest.fixture
def cache_lock(tmp_path, monkeypatch):
    """pyopencl's program-cache lock in a cache of the test's own (XDG_CACHE_HOME)."""
    if sys.platform != "linux":
        pytest.skip("the XDG cache folder is Linux's")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    lock = runtime.cache_lock()
    lock.parent.mkdir(parents=True)
    return lock


def _holder(lock):
    """A process holding ``lock`` as pyopencl does, until it is killed."""
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD_LOCK, str(lock)], stdout=subprocess.PIPE, text=True
    )
    assert holder.stdout.readline().strip() == "held"
    return holder


def _killed(holder):
    holder.kill()
    holder.wait()
    holder.stdout.close()


def test_a_killed_workers_cache_lock_costs_the_next_process_no_wait(cache_lock):
    """A worker killed while it held pyopencl's program-cache lock (a cancelled pass): the
    next process's first build (the device probe) finds the lock gone and never waits on
    it, however recent the kill (pyopencl waited a minute, then failed the build)."""
    _killed(_holder(cache_lock))
    assert cache_lock.exists()
    run = subprocess.run(
        [sys.executable, "-c", NEVER_WAIT],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
        cwd=ROOT,
        env={**os.environ, "HOLO_DEVICE": ""},
    )
    assert run.returncode == 0 and "device" in run.stdout, run.stderr[-2000:]
    assert "stale OpenCL program-cache lock" in run.stderr, run.stderr[-2000:]
    assert not cache_lock.exists()


def test_a_living_holders_cache_lock_stays_however_old(cache_lock):
    """A lock a living process holds open stays, even older than STALE_LOCK (a long build);
    once its holder is killed, it goes."""
    holder = _holder(cache_lock)
    try:
        old = time.time() - 2 * runtime.STALE_LOCK
        os.utime(cache_lock, (old, old))
        runtime.clear_stale_cache_lock()
        assert cache_lock.exists(), "a living holder's lock was removed"
    finally:
        _killed(holder)
    runtime.clear_stale_cache_lock()
    assert not cache_lock.exists()


def test_a_gpu_keeps_one_copy_of_an_array_it_reads_while_the_array_lives(monkeypatch):
    """arrays.resident on a device that is not a CPU (a runtime told it is not): the array is
    copied once and read from the copy, made read-only while the copy is kept, the copy
    dropped with the array, and the least recently used copy dropped to fit the budget (its
    array writable again). On a CPU it is the array's own memory."""
    import gc

    import pyopencl as cl

    from holo_core.opencl import arrays

    rt = runtime.Runtime(choose_device())
    if rt.is_cpu:
        arrays.resident(rt, np.ones(4, np.complex64))
        assert "resident" not in rt.cache  # a CPU reads the array itself: no copies kept
    rt.__dict__["is_cpu"] = False  # the cached property, as on a GPU
    rng = np.random.default_rng(3)
    a = (rng.standard_normal((3, 64, 48)) + 1j * rng.standard_normal((3, 64, 48))).astype(
        np.complex64
    )
    buf = arrays.resident(rt, a)
    assert arrays.resident(rt, a) is buf and not a.flags.writeable
    back = np.empty_like(a)
    cl.enqueue_copy(rt.queue, back, buf)
    assert np.array_equal(back, a)
    with pytest.raises(ValueError):
        a[0, 0, 0] = 1
    monkeypatch.setattr(arrays, "RESIDENT_SHARE", 1.5 * a.nbytes / rt.device.global_mem_size)
    b = a.copy()
    b.flags.writeable = True
    assert arrays.resident(rt, b) is not None
    assert a.flags.writeable and list(rt.cache["resident"]) == [id(b)]  # a's copy made room
    del b
    gc.collect()
    assert not rt.cache["resident"]  # b's copy went with it
    assert arrays.resident(rt, np.zeros((6, 64, 48), np.complex64)) is None  # over the budget
