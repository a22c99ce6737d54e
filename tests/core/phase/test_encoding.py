"""Double-phase encoding: the mean of each checkerboard pair is the complex sample, and a
low-pass of the phase-only pattern gives back a smooth field."""

import numpy as np
import pytest

from holo_core.phase import double_phase
from holo_core.validate import InputError


def smooth(rng, n, band):
    """A real field whose spectrum fills |f| <= band [cycles/sample], scaled to [-1, 1]."""
    f = np.fft.fftfreq(n)
    r = np.fft.ifft2(rng.normal(size=(n, n)) * (f[:, None] ** 2 + f[None, :] ** 2 <= band**2)).real
    return r / np.abs(r).max()


def test_each_checkerboard_pair_averages_to_the_sample():
    """exp(i(φ + α)) and exp(i(φ − α)), α = arccos A, average to A·exp(iφ) exactly."""
    c = 0.37 * np.exp(1.1j) * np.ones((4, 6))
    th = double_phase(c, max_amplitude=1.0)
    pair = (np.exp(1j * th[:, :-1]) + np.exp(1j * th[:, 1:])) / 2
    assert np.abs(pair - c[:, 1:]).max() <= 1e-12
    assert np.all(np.abs(th) <= np.pi)


def test_a_low_pass_gives_back_a_smooth_field(rng):
    """A field of amplitude 0.6 ± 0.3 and phase ± 3 rad, band-limited to 1/32 cycle per
    sample: the pattern low-passed to a quarter cycle per sample is the field (measured
    1.2e-8; 2e-3 at a band of 1/16, where sin α·exp(iφ) starts to reach the pass band)."""
    n = 128
    c = (0.6 + 0.3 * smooth(rng, n, 1 / 32)) * np.exp(3j * smooth(rng, n, 1 / 32))
    u = np.exp(1j * double_phase(c, max_amplitude=1.0))
    f = np.fft.fftfreq(n)
    low = np.fft.ifft2(np.fft.fft2(u) * (f[:, None] ** 2 + f[None, :] ** 2 <= 0.25**2))
    err = np.linalg.norm(low - c) / np.linalg.norm(c)
    assert err <= 1e-6, f"{err:.3g}"


def test_amplitudes_above_the_maximum_are_refused():
    with pytest.raises(InputError, match="exceeds max_amplitude"):
        double_phase(np.full((2, 2), 2.0 + 0j), max_amplitude=1.0)
    with pytest.raises(InputError, match="all zero"):
        double_phase(np.zeros((2, 2)))
    assert np.allclose(double_phase(np.full((2, 2), 2.0 + 0j)), [[0, 0], [0, 0]])
