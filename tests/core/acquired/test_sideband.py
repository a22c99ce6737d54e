"""The sideband filter of acquired off-axis holograms, against the known object wave of
synthetic holograms H = |O + R|² recorded in float64 and stored as float32."""

import math

import numpy as np
import pytest
from accuracy import SIDEBAND, SIDEBAND_FOUND, rel_err

from holo_core.acquired import Aperture, InlineHologramError, find_carrier, sideband
from holo_core.plate import Reference, reconstruct
from holo_core.plate.reference import interfere, reference_wave
from holo_core.propagation import grid
from holo_core.scene import Hologram
from holo_core.validate import InputError, SamplingWarning

LAM, PITCH, N = 633e-9, 4e-6, 256


def band_limited(rng, radius, shape=(N, N)):
    """A random complex wave whose spectrum fills the disc |f| <= radius [1/m], unit rms."""
    fy, fx = grid.freqs(shape[0], PITCH)[:, None], grid.freqs(shape[1], PITCH)[None, :]
    spectrum = (rng.normal(size=shape) + 1j * rng.normal(size=shape)) * (fx**2 + fy**2 <= radius**2)
    u = np.fft.ifft2(spectrum)
    return u / np.sqrt(np.mean(np.abs(u) ** 2))


def recorded(obj, angle, azimuth, amplitude=2.0):
    """The intensity hologram of ``obj`` with the plane reference (angle, azimuth) [rad]."""
    ref = Reference(angle=angle, azimuth=azimuth)
    r = reference_wave(obj.shape, wavelength=LAM, pitch=PITCH, reference=ref, amplitude=amplitude)
    return Hologram(
        intensity=interfere(obj, r)[None],
        wavelengths=(LAM,),
        pitch=PITCH,
        reference_angle=angle,
        reference_azimuth=azimuth,
        reference_amplitudes=(amplitude,),
    )


def angle_for(carrier):
    """The reference angle whose carrier is ``carrier`` [1/m]."""
    return math.asin(carrier * LAM)


@pytest.mark.parametrize("azimuth", [0.0, 0.7, math.pi])
def test_the_metadata_carrier_gives_the_object_wave(rng, azimuth):
    """A diffuse object of band B, a reference at 3.4·B: the filter returns O (measured 3e-8 to
    1e-6; the plain disc without the leakage passes 1.6e-3 to 3.3e-2, worst with the carrier
    along an axis, between bins); the plain R·H of reconstruct() is the object wave plus its
    zero order and twin (measured 1.12 relative L2)."""
    band = 12e3
    obj = band_limited(rng, band)
    h = recorded(obj, angle_for(3.4 * band), azimuth)
    got = sideband(h)
    err = rel_err(got, obj)
    assert err <= SIDEBAND, f"sideband vs object wave: {err:.3g}"
    plain = rel_err(reconstruct(h), obj)
    assert plain > 1.0, f"reconstruct() is expected to keep the twin and zero order: {plain:.3g}"


def test_an_off_grid_carrier_is_found_in_the_spectrum(rng):
    """A weakly scattering transmission sample (undiffracted light plus a diffuse part of 0.1)
    and a carrier between the FFT's bins (70.37, -20.81 bins), found from the array alone.
    The peak of the +1 order is the undiffracted light's, pulled by the object's own lowest
    frequencies by about a twentieth of their amplitude in bins (an object tilt and a
    reference tilt are one and the same to the hologram): measured 4.8e-3 bin, and the object
    wave 9.6e-3 from the truth, the tilt that leaves (3e-8 with the true carrier). Its f_y < 0
    makes it the upper sideband by the stated rule; the default (lower) finds its twin."""
    band = 10e3
    obj = 1.0 + 0.1 * band_limited(rng, band)
    step = 1 / (N * PITCH)
    true = (70.37 * step, -20.81 * step)
    y, x = grid.coords(N, PITCH)[:, None], grid.coords(N, PITCH)[None, :]
    r = 2.0 * np.exp(2j * np.pi * (true[0] * x + true[1] * y))
    h = interfere(obj, r)
    found = find_carrier(h, pitch=PITCH, sideband="upper").frequency  # f_y < 0: the upper one
    miss = max(abs(found[0] - true[0]), abs(found[1] - true[1])) / step
    assert miss <= 1e-2, f"carrier {found} vs {true}: {miss:.3g} bin"
    twin = find_carrier(h, pitch=PITCH).frequency  # the default, lower: the pair's other peak
    assert np.allclose(twin, (-found[0], -found[1]), rtol=1e-9), (twin, found)
    err = rel_err(
        sideband(h, pitch=PITCH, reference_amplitude=2.0, radius=band, sideband="upper"), obj
    )
    assert err <= SIDEBAND_FOUND, f"sideband vs object wave: {err:.3g}"
    exact = rel_err(
        sideband(h, pitch=PITCH, reference_amplitude=2.0, radius=band, carrier=true), obj
    )
    assert exact <= SIDEBAND, f"with the true carrier: {exact:.3g}"


def test_the_metadata_picks_the_plus_one_order_out_of_the_pair(rng):
    """A reference tilted towards -x, its angle known only roughly (5 % off): the spectrum
    search near the metadata's carrier finds the +1 order, not the twin, and refines the
    carrier; without the metadata the rule's lower sideband (f_y > 0, or f_y = 0 and f_x >= 0)
    is taken for the carrier, which is the twin here (the conjugate object), as it says."""
    band = 10e3
    obj = 1.0 + 0.1 * band_limited(rng, band)
    angle = angle_for(40e3)
    h = recorded(obj, angle, math.pi)
    rough = Hologram(
        intensity=h.intensity,
        wavelengths=(LAM,),
        pitch=PITCH,
        reference_angle=angle * 1.05,
        reference_azimuth=math.pi,
        reference_amplitudes=(2.0,),
    )
    err = rel_err(sideband(rough, carrier="spectrum", radius=band), obj)
    assert err <= SIDEBAND_FOUND, f"+1 order from rough metadata: {err:.3g}"
    twin = rel_err(
        sideband(h.intensity[0], pitch=PITCH, reference_amplitude=2.0, radius=band), obj.conj()
    )
    assert twin <= SIDEBAND_FOUND, f"without metadata, the twin: {twin:.3g}"
    fx, fy = find_carrier(h.intensity[0], pitch=PITCH).frequency
    assert fx > 0 and abs(fx - 40e3) < 10 and abs(fy) < 10, (fx, fy)


def test_the_recorded_band_is_the_default_radius(rng):
    """A hologram that states its band (sin θ) is filtered to it."""
    band = 12e3
    obj = band_limited(rng, band)
    h = recorded(obj, angle_for(3.4 * band), 0.3)
    import dataclasses

    stated = dataclasses.replace(h, band=band * LAM)
    err = rel_err(sideband(stated), obj)
    assert err <= SIDEBAND, f"{err:.3g}"


def test_bad_settings_are_refused(rng):
    h = recorded(band_limited(rng, 10e3), angle_for(40e3), 0.0)
    flat = np.ones((N, N))
    with pytest.raises(InputError, match="pitch must be given"):
        sideband(flat)
    with pytest.raises(InputError, match="carrier 'reference' needs a Hologram"):
        sideband(flat, pitch=PITCH, carrier="reference")
    with pytest.raises(InputError, match="no fringes"):
        sideband(flat, pitch=PITCH)
    with pytest.raises(InputError, match="carrier must be off-axis"):
        sideband(h, carrier=(0.0, 0.0))
    with pytest.raises(InputError, match="carrier must be within the Nyquist"):
        sideband(h, carrier=(1e6, 0.0))
    with pytest.raises(InputError, match=r"radius must be <= \|carrier\|"):
        sideband(h, radius=50e3)
    with pytest.raises(InputError, match="carrier must be one of"):
        sideband(h, carrier="peak")
    with pytest.raises(InputError, match="real intensity array"):
        sideband(flat + 0j, pitch=PITCH)
    with pytest.warns(SamplingWarning, match="reaches past half the way to the zero order"):
        sideband(h, radius=25e3)


def test_an_inline_hologram_is_recognised_and_said_so(rng):
    """A reference on the axis: the orders overlap at zero frequency. The sideband filter took
    a patch of the object's own spectrum for the +1 order (0.955 off) without a word; now
    the spectrum's even spread around zero is recognised, whether the carrier is searched or
    given."""
    obj = 1.0 + 0.3 * band_limited(rng, 12e3)
    h = interfere(obj, 2.0 * np.ones((N, N)))
    with pytest.raises(
        InlineHologramError,
        match=r"hologram looks in-line: .* holds "
        r"[0-9.]+ times the energy of the same disc",
    ):
        sideband(h, pitch=PITCH)
    with pytest.raises(InlineHologramError, match="looks in-line"):
        sideband(h, pitch=PITCH, carrier=(40e3, 0.0))
    off_axis = recorded(band_limited(rng, 12e3), angle_for(40e3), 0.3)
    assert find_carrier(off_axis).contrast > 100


@pytest.mark.parametrize(
    "edge, window, at_radius, at_centre",
    [
        ("hard", "none", 1.0, 1.0),
        ("tanh", "none", 0.5, 1.0),
        ("cosine", "none", 0.5, 1.0),
        ("hard", "hann", 0.0, 1.0),
        ("hard", "hamming", 0.08, 1.0),
        ("hard", "gaussian", math.exp(-2), 1.0),
        ("hard", "butterworth", 0.5, 1.0),
    ],
)
def test_the_aperture_weights_are_the_stated_functions(edge, window, at_radius, at_centre):
    """At the centre, the radius R and 1.06 R (the edge's width w = 0.1 R): holospy's tanh is
    ½ at R and ½(1 − tanh(0.06/0.05)) beyond, the raised cosine ½ at R and 0 from R + w/2;
    the windows their textbook values at R."""
    a = Aperture(radius=0.3, edge=edge, width=0.1, window=window)
    fx = np.array([0.0, 0.3e3, 0.3e3 * 1.06])
    w = a.weights(fx, np.zeros(3), 0.3e3)
    assert w[0] == pytest.approx(at_centre) and w[1] == pytest.approx(at_radius, abs=1e-12)
    beyond = {"hard": 0.0, "tanh": 0.5 * (1 - math.tanh(0.06 / 0.05)), "cosine": 0.0}[edge]
    if window == "none":
        assert w[2] == pytest.approx(beyond, abs=1e-12), (edge, w)


def test_a_radius_in_any_unit_is_the_same_filter(rng):
    """The same aperture as a fraction of |f_R|, in 1/mm and as an angle in mrad (f = sin θ/λ)
    gives the same object wave."""
    band, fc = 10e3, 40e3
    h = recorded(band_limited(rng, band), angle_for(fc), 0.0)
    r = 0.3 * fc
    by_fraction = sideband(h, aperture=Aperture(radius=0.3))
    by_frequency = sideband(h, aperture=Aperture(radius=r / 1e3, unit="1/mm"))
    by_angle = sideband(h, aperture=Aperture(radius=math.asin(r * LAM) * 1e3, unit="mrad"))
    assert rel_err(by_frequency, by_fraction) <= 1e-6
    assert rel_err(by_angle, by_fraction) <= 1e-6


def test_subtracting_the_beams_intensities_takes_the_zero_order_away(rng):
    """An object band of |f_R|/2.5: its zero order |O|² (twice as wide) reaches into the
    sideband's aperture. With |O|² and |R|² subtracted (the object beam's and the reference
    beam's own frames), the plain filter (no leakage passes) keeps the object wave alone."""
    fc = 40e3
    obj = band_limited(rng, fc / 2.5)
    h = recorded(obj, angle_for(fc), 0.3)
    plain = rel_err(sideband(h, iterations=0, radius=fc / 2.5), obj)
    frames = [np.abs(obj) ** 2, np.full((N, N), 4.0)]
    cleaned = rel_err(sideband(h, iterations=0, radius=fc / 2.5, subtract=frames), obj)
    print(f"zero order overlapping: {plain:.3g}; subtracted: {cleaned:.3g}")
    assert cleaned < plain / 3, (cleaned, plain)


def test_a_vacuum_hologram_divides_the_reference_wave_away():
    """A curved, tilted reference (a spherical wave's quadratic phase, as a misaligned lab
    has) and a smooth phase object: the filtered wave keeps the reference's curvature; divided
    by the vacuum hologram's filtered wave (the same optics without the object), the object's
    transmission comes back (measured 5.3e-3 inside, limited by the filter's band; 1.46
    without the division)."""
    y, x = grid.coords(N, PITCH)[:, None], grid.coords(N, PITCH)[None, :]
    phase = 2.0 * np.exp(-(x**2 + y**2) / (2 * (80 * PITCH) ** 2))
    transmission = np.exp(1j * phase)
    edge = N / 2 * PITCH  # the curvature's local frequency reaches 5e3 1/m there
    r = 2.0 * np.exp(2j * np.pi * 40e3 * x + 1j * np.pi * 5e3 * (x**2 + y**2) / edge)
    h, vacuum = interfere(transmission, r), interfere(np.ones((N, N)), r)
    got = sideband(
        h,
        pitch=PITCH,
        reference_hologram=vacuum,
        reference_amplitude=2.0,
        aperture=Aperture(radius=0.5),
    )
    inner = (slice(32, -32), slice(32, -32))
    err = rel_err(got[inner], transmission[inner])
    assert err <= 1e-2, f"{err:.3g}"
    without = rel_err(
        sideband(h, pitch=PITCH, reference_amplitude=2.0, aperture=Aperture(radius=0.5))[inner],
        transmission[inner],
    )
    assert without > 0.5, f"{without:.3g}"
