"""Device choice, the CLI listing, kernels built once, and the house rules on imports."""

import pathlib
import re
import subprocess
import sys

import numpy as np
import pytest

from holo_core.opencl import all_devices, choose_device

ROOT = pathlib.Path(__file__).resolve().parents[2]


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
    with pytest.raises(ValueError, match=r"HOLO_DEVICE='no-such-device' matches no device; "
                                         r"allowed: 'gpu', 'cpu'"):
        choose_device()


def test_devices_command_lists_what_it_would_use():
    out = subprocess.run([sys.executable, "-m", "holo_core", "devices"], capture_output=True,
                         text=True, check=True, cwd=ROOT).stdout
    assert "would use:" in out and re.search(r"^\s*\d+:\d+ ", out, re.M), out


def test_programs_and_kernels_are_built_once(rt):
    k1 = rt.kernel("spectral", "multiply")
    assert rt.kernel("spectral", "multiply") is k1
    assert rt.program("spectral") is rt.program("spectral")


def test_fft_backend_round_trip(rt, rng):
    a = (rng.normal(size=(48, 40)) + 1j * rng.normal(size=(48, 40))).astype(np.complex64)
    dev = rt.to_device(a)
    rt.fft.forward(dev)
    assert np.allclose(dev.get(), np.fft.fft2(a), atol=1e-3)
    rt.fft.backward(dev)
    assert np.allclose(dev.get() / a.size, a, atol=1e-5)


def _imports(root, pattern):
    return [str(p.relative_to(ROOT)) for p in root.rglob("*.py")
            if re.search(pattern, p.read_text(), re.M)]


def test_core_never_imports_bpy():
    assert _imports(ROOT / "holo_core", r"^\s*(import bpy|from bpy)") == []


def test_pyopencl_only_under_holo_core_opencl():
    hits = _imports(ROOT / "holo_core", r"^\s*(import pyopencl|from pyopencl)")
    assert all(h.startswith("holo_core/opencl/") for h in hits), hits
