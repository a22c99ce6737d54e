"""The sideband filter of acquired off-axis holograms (issue 28, item 4), against the known
object wave of synthetic holograms H = |O + R|² recorded in float64 and stored as float32."""

import math

import numpy as np
import pytest
from accuracy import SIDEBAND, SIDEBAND_FOUND, rel_err

from holo_core.plate import Reference, find_carrier, reconstruct, sideband
from holo_core.plate.record import interfere, reference_wave
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
    return Hologram(intensity=interfere(obj, r)[None], wavelengths=(LAM,), pitch=PITCH,
                    reference_angle=angle, reference_azimuth=azimuth,
                    reference_amplitudes=(amplitude,))


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
    wave 9.6e-3 from the truth, the tilt that leaves (3e-8 with the true carrier)."""
    band = 10e3
    obj = 1.0 + 0.1 * band_limited(rng, band)
    step = 1 / (N * PITCH)
    true = (70.37 * step, -20.81 * step)
    y, x = grid.coords(N, PITCH)[:, None], grid.coords(N, PITCH)[None, :]
    r = 2.0 * np.exp(2j * np.pi * (true[0] * x + true[1] * y))
    h = interfere(obj, r)
    found = find_carrier(h, pitch=PITCH)
    miss = max(abs(found[0] - true[0]), abs(found[1] - true[1])) / step
    assert miss <= 1e-2, f"carrier {found} vs {true}: {miss:.3g} bin"
    err = rel_err(sideband(h, pitch=PITCH, reference_amplitude=2.0, radius=band), obj)
    assert err <= SIDEBAND_FOUND, f"sideband vs object wave: {err:.3g}"
    exact = rel_err(sideband(h, pitch=PITCH, reference_amplitude=2.0, radius=band,
                             carrier=true), obj)
    assert exact <= SIDEBAND, f"with the true carrier: {exact:.3g}"


def test_the_metadata_picks_the_plus_one_order_out_of_the_pair(rng):
    """A reference tilted towards -x, its angle known only roughly (5 % off): the spectrum
    search near the metadata's carrier finds the +1 order, not the twin, and refines the
    carrier; without the metadata the reference is read as tilted towards +x, which gives the
    twin (the conjugate object), as the docstring says."""
    band = 10e3
    obj = 1.0 + 0.1 * band_limited(rng, band)
    angle = angle_for(40e3)
    h = recorded(obj, angle, math.pi)
    rough = Hologram(intensity=h.intensity, wavelengths=(LAM,), pitch=PITCH,
                     reference_angle=angle * 1.05, reference_azimuth=math.pi,
                     reference_amplitudes=(2.0,))
    err = rel_err(sideband(rough, carrier="spectrum", radius=band), obj)
    assert err <= SIDEBAND_FOUND, f"+1 order from rough metadata: {err:.3g}"
    twin = rel_err(sideband(h.intensity[0], pitch=PITCH, reference_amplitude=2.0, radius=band),
                   obj.conj())
    assert twin <= SIDEBAND_FOUND, f"without metadata, the twin: {twin:.3g}"
    fx, fy = find_carrier(h.intensity[0], pitch=PITCH)
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
    with pytest.raises(InputError, match="radius must be <= |carrier|"):
        sideband(h, radius=50e3)
    with pytest.raises(InputError, match="carrier must be one of"):
        sideband(h, carrier="peak")
    with pytest.raises(InputError, match="real intensity array"):
        sideband(flat + 0j, pitch=PITCH)
    with pytest.warns(SamplingWarning, match="overlaps the zero order"):
        sideband(h, radius=20e3)
