"""The workflow around the sideband filter, against analytic phases and a float64 NumPy wave:
unwrapping, tilt and background removal, refocus and autofocus."""

import numpy as np
import pytest
from accuracy import rel_err

from holo_core.acquired import (
    METRICS,
    autofocus,
    depth_of_focus,
    fit_phase,
    refocus,
    remove_background,
    remove_tilt,
    unwrap,
)
from holo_core.validate import InputError

LAM, PITCH, N = 633e-9, 4e-6, 256


def grid_xy(n=N):
    c = (np.arange(n) - (n - 1) / 2) / n
    return c[None, :], c[:, None]


def smooth_phase():
    """A bump of 60 rad on a tilt and a curvature: neighbours differ by less than π."""
    x, y = grid_xy()
    return 60 * np.exp(-(x**2 + y**2) / (2 * 0.15**2)) + 25 * x - 12 * y + 30 * (x**2 + y**2)


def test_unwrapping_gives_back_the_phase_exactly():
    """Least squares, then whole turns: the unwrapped phase is the true one up to a constant
    number of turns, to float64 round-off."""
    truth = smooth_phase()
    got = unwrap(np.exp(1j * truth))
    offset = got - truth
    assert np.ptp(offset) <= 1e-9, np.ptp(offset)
    assert abs(offset.mean() / (2 * np.pi) - round(offset.mean() / (2 * np.pi))) <= 1e-9


def test_a_tilt_and_a_background_are_taken_away():
    """A phase object on a tilt (a residual carrier) and a curvature (a residual spherical
    wave): the plane fitted over the object-free region takes the tilt, the second-order
    polynomial the curvature too, leaving the object's phase up to a constant."""
    x, y = grid_xy()
    obj = 1.5 * np.exp(-(x**2 + y**2) / (2 * 0.05**2))
    tilt, curvature = 40 * x + 17 * y, 25 * (x**2 + y**2) - 8 * x * y
    outside = np.hypot(x, y) > 0.25
    flat = remove_tilt(np.exp(1j * (obj + tilt)), mask=outside)
    err = np.angle(flat * np.exp(-1j * obj))
    assert np.ptp(err) <= 1e-5, np.ptp(err)
    clean = remove_background(np.exp(1j * (obj + tilt + curvature)), mask=outside)
    err = np.angle(clean * np.exp(-1j * obj))
    assert np.ptp(err) <= 1e-5, np.ptp(err)
    fitted = fit_phase(np.exp(1j * (tilt + curvature)), order=2)
    assert np.ptp(fitted - (tilt + curvature)) <= 1e-6


def test_a_background_wave_divides():
    rng = np.random.default_rng(1)
    background = np.exp(1j * rng.normal(size=(8, 8))) * 2
    obj = np.exp(0.3j)
    assert np.allclose(remove_background(obj * background, background), obj, atol=1e-6)
    holed = background.copy()
    holed[3, 4] = 0
    with pytest.raises(InputError, match="background vanishes at 1 samples"):
        remove_background(background, holed)


def _amplitude_object(z, bead=False):
    """Bars and a disc (an amplitude object; or a bead of 6 µm alone) carried z [m] by the
    exact angular spectrum in float64 NumPy on a 2x grid: the wave on the hologram."""
    n = 2 * N
    c = (np.arange(n) - (n - 1) / 2) * PITCH
    x, y = c[None, :], c[:, None]
    bars = (
        (np.abs(x) < 120e-6) & (np.abs(y) < 120e-6) & (np.floor((x + 120e-6) / 40e-6) % 2 == 0)
    ) | (np.hypot(x - 60e-6, y + 160e-6) < 25e-6)
    if bead:
        bars = np.hypot(x, y) < 6e-6
    f = np.fft.fftfreq(n, PITCH)
    f2 = f[None, :] ** 2 + f[:, None] ** 2
    kz = np.sqrt(np.maximum(1 / LAM**2 - f2, 0))
    band = 0.5 * (1 - np.tanh((np.sqrt(f2) - 60e3) / 3e3))
    wave = np.fft.ifft2(np.fft.fft2(bars.astype(float)) * np.exp(2j * np.pi * z * kz) * band)
    lo = n // 4
    return wave[lo : lo + N, lo : lo + N], bars[lo : lo + N, lo : lo + N]


@pytest.mark.parametrize(
    "metric, bead", [(m, False) for m in sorted(set(METRICS) - {"peak"})] + [("peak", True)]
)
def test_autofocus_finds_the_distance_within_its_depth_of_focus(metric, bead):
    """The wave of an object 6.3 mm behind the hologram (band 60e3 1/m: depth of focus
    λ/NA² = 0.44 mm), searched from 4 to 9 mm in 0.1 mm steps: each metric finds it within
    one depth of focus (measured: 0 off). The peak intensity is a metric for point objects
    (a bead): on the bars, diffraction makes brighter peaks 1.2 mm away."""
    z0 = 6.3e-3
    wave, _ = _amplitude_object(z0, bead)
    dof = depth_of_focus(LAM, 60e3)
    found = autofocus(
        wave, wavelength=LAM, pitch=PITCH, distances=-np.arange(4e-3, 9e-3, 1e-4), metric=metric
    )
    print(
        f"{metric}: {-found.distance * 1e3:.2f} mm for {z0 * 1e3:.2f} (depth of focus "
        f"{dof * 1e3:.2f} mm)"
    )
    assert abs(-found.distance - z0) <= dof, (metric, found.distance)


def test_refocus_brings_the_object_back():
    """Refocused by the project's angular spectrum, the wave is the object's own (the float64
    band-limited bars) within the float32 pipeline and the band's edge."""
    z0 = 6.3e-3
    wave, _ = _amplitude_object(z0)
    back, _ = _amplitude_object(0.0)
    got = refocus(wave, wavelength=LAM, pitch=PITCH, distance=-z0)
    inner = (slice(64, -64), slice(64, -64))
    assert rel_err(got[inner], back[inner]) <= 1e-3, rel_err(got[inner], back[inner])
