"""The FFT backends: transforms that skip what is known to be zero against NumPy's, and the
FFTW passes' determinism (bit-identical whatever the thread count, and across processes from
a fresh cache, the process that measures the plans included)."""

import hashlib
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

from holo_core.opencl.host_fft import HostFFT

ROOT = pathlib.Path(__file__).resolve().parents[3]
TOL = 2e-6  # float32 FFTs of a few hundred samples, relative to the largest value


def _random(rng, shape):
    return (rng.normal(size=shape) + 1j * rng.normal(size=shape)).astype(np.complex64)


def _close(got, want):
    err = float(np.abs(got - want).max() / np.abs(want).max())
    assert err < TOL, f"relative error {err:.2e}"


@pytest.mark.parametrize("threads", [1, 3])
def test_a_transform_told_where_its_input_is_non_zero_ignores_the_rest(rng, threads):
    """The corners of a grid (a pupil in FFT order, zero-padded) hold the field; the rest holds
    garbage that the transform must take as zero."""
    engine = HostFFT(threads=threads, planner="estimate")
    a = _random(rng, (96, 136))
    rows, cols = ((0, 20), (80, 96)), ((0, 30), (117, 136))
    zeroed = np.zeros_like(a)
    for r0, r1 in rows:
        for c0, c1 in cols:
            zeroed[r0:r1, c0:c1] = a[r0:r1, c0:c1]
    engine.transform(a, "FFTW_FORWARD", nonzero=(rows, cols))
    _close(a, np.fft.fft2(zeroed))


def test_an_inverse_told_which_columns_are_read_gets_those_right(rng):
    engine = HostFFT(threads=2, planner="estimate")
    a = _random(rng, (80, 120))
    want = np.fft.ifft2(a) * a.size
    engine.transform(a, "FFTW_BACKWARD", read=((40, 77),))
    _close(a[:, 40:77], want[:, 40:77])


@pytest.mark.parametrize("backend", ["fftw", "numpy"])
def test_a_stack_is_transformed_plane_by_plane(rng, backend):
    """A (P, H, W) device stack: each plane's 2-D transform, in both directions unnormalised,
    against NumPy's (the inverse's scale is a plane's H·W, not the stack's size)."""
    from holo_core.opencl import get_runtime
    from holo_core.opencl.fft import FFTW, HostNumpy

    rt = get_runtime()
    fft = (FFTW if backend == "fftw" else HostNumpy)(rt)
    a = _random(rng, (3, 40, 56))
    stack = rt.to_device(a)
    fft.forward(stack)
    _close(stack.get(), np.fft.fft2(a))
    fft.backward(stack)
    _close(stack.get(), a * (40 * 56))


def test_the_padded_convolution_equals_numpy(rng):
    """pad, FFT, multiply, inverse FFT, crop in the passes: as NumPy does it in float64."""
    engine = HostFFT(threads=2, planner="estimate")
    field, transfer = _random(rng, (50, 70)), _random(rng, (112, 144))
    out = np.empty_like(field)
    dc = engine.convolve(field, transfer, out)
    big = np.zeros(transfer.shape, complex)
    big[31:81, 37:107] = field
    spectrum = np.fft.fft2(big)
    want = np.fft.ifft2(spectrum * transfer)[31:81, 37:107] * transfer.size
    _close(out, want)
    assert abs(dc - spectrum[0, 0]) < 1e-4 * abs(spectrum).max()


RUN = """
import hashlib, sys
import numpy as np
from holo_core.propagation import angular_spectrum, fresnel
rng = np.random.default_rng(7)
u = (rng.normal(size=(300, 260)) + 1j * rng.normal(size=(300, 260))).astype(np.complex64)
a = angular_spectrum(u, wavelength=633e-9, pitch=2e-6, distance=3e-3, offset=(1e-5, 0))
f = fresnel(u, wavelength=633e-9, pitch=2e-6, distance=-2e-3)
print(hashlib.sha256(a.tobytes() + f.tobytes()).hexdigest())
"""


def _run(cache, threads, planner="measure"):
    """RUN in a process of its own with ``cache`` as its cache folder: (stdout, stderr, where
    its INFO log goes)."""
    env = {
        **os.environ,
        "XDG_CACHE_HOME": str(cache),
        "HOLO_FFT_THREADS": str(threads),
        "HOLO_FFTW_PLANNER": planner,
        "HOLO_FFT": "fftw",
    }
    code = "import logging; logging.basicConfig(level=logging.INFO)\n" + RUN
    r = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600
    )
    assert r.returncode == 0, r.stderr[-3000:]
    return r.stdout, r.stderr


def _digest(cache, threads, planner="measure"):
    return _run(cache, threads, planner)[0].split()[-1]


def test_plans_measured_once_are_found_by_a_later_process(tmp_path, rt):
    """Two processes sharing a fresh cache: the first says it measures its plans, the second
    finds every one of them and measures nothing."""
    if rt.fft.name != "fftw":
        pytest.skip(f"FFTW passes only: this device's FFTs are {rt.fft.name}")
    first = _run(tmp_path, 1)[1].count("measuring a plan")
    again = [line for line in _run(tmp_path, 1)[1].splitlines() if "measuring a plan" in line]
    assert first > 0, "the first process measured no plan: nothing to find again"
    assert not again, f"a later process measured {len(again)} plans again: {again[:2]}"


@pytest.mark.slow
def test_results_are_bit_identical_across_processes_and_thread_counts(tmp_path, rt):
    """From an empty cache, the first process measures the plans it needs and keeps them; the
    next ones, with one thread or three, read them: the same bits. The estimate planner needs
    no cache and gives the same bits with one thread or two."""
    if rt.fft.name != "fftw":
        pytest.skip(f"FFTW passes only: this device's FFTs are {rt.fft.name}")
    first = _digest(tmp_path / "cache", 2)
    assert (tmp_path / "cache" / "holo").is_dir()
    wisdom = sorted((tmp_path / "cache" / "holo").glob("fftw-wisdom-*.pickle"))
    assert wisdom, "no wisdom kept"
    kept = hashlib.sha256(wisdom[0].read_bytes()).hexdigest()
    assert _digest(tmp_path / "cache", 1) == first
    assert _digest(tmp_path / "cache", 3) == first
    assert hashlib.sha256(wisdom[0].read_bytes()).hexdigest() == kept, "plans were re-measured"
    estimated = _digest(tmp_path / "empty", 1, "estimate")
    assert _digest(tmp_path / "empty", 2, "estimate") == estimated
