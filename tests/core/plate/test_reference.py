"""The reference wave (holo_core.plate.reference) against its analytic plane wave and the
holograms it records: DC suppression removes the reference term, an off-axis reference
separates the twin image, and an angle the plate cannot sample is refused or warned of."""

import math

import numpy as np
import pytest
from point_sums import LAM, PITCH, cloud

from holo_core.plate.points import record_points
from holo_core.plate.reconstruction import reconstruct
from holo_core.plate.reference import Reference, interfere, reference_wave
from holo_core.propagation import grid
from holo_core.validate import SamplingWarning


def test_dc_suppression_removes_the_reference_term(rng):
    """Fig. 7: the reference term R(|O|² + |R|²) is the reconstruction's component along R."""
    shape, z = (256, 256), -0.05
    ref = Reference(angle=0.03, beam_ratio=4.0)
    holo = record_points(
        cloud(rng, z), np.ones((6, 1)), shape=shape, pitch=PITCH, wavelengths=(LAM,), reference=ref
    )
    r = reference_wave(shape, wavelength=LAM, pitch=PITCH, reference=ref)

    def reference_energy(u):  # energy in the 3x3 spectral bins around R's carrier
        s = np.fft.fft2(u * np.conj(r))
        s = np.fft.fftshift(s)
        c = np.array(shape) // 2
        return float((np.abs(s[c[0] - 1 : c[0] + 2, c[1] - 1 : c[1] + 2]) ** 2).sum())

    plain = reference_energy(reconstruct(holo, dc_suppression=False))
    suppressed = reference_energy(reconstruct(holo, dc_suppression=True))
    db = 10 * math.log10(plain / suppressed)
    assert db >= 20, f"DC suppression lowers the reference term by only {db:.1f} dB"


def test_off_axis_reference_separates_the_twin_image(rng):
    """The object's band is |f| <= D/(λ|z|)-ish; the twin sits at 2 sin ϑ/λ."""
    shape, z = (256, 256), -0.3
    pts = np.c_[rng.uniform(-5e-5, 5e-5, (4, 2)), np.full(4, z)]
    aperture = shape[0] * PITCH
    f_obj = (aperture / 2 + 1e-4) / (LAM * abs(z))
    fy, fx = grid.freqs(shape[0], PITCH)[:, None], grid.freqs(shape[1], PITCH)[None, :]
    band = np.hypot(fx, fy) <= f_obj

    def twin_in_band(angle):
        holo = record_points(
            pts,
            np.ones((4, 1)),
            shape=shape,
            pitch=PITCH,
            wavelengths=(LAM,),
            reference=Reference(angle=angle, beam_ratio=25.0),
        )
        err = np.fft.fft2(reconstruct(holo) - holo.object_wave[0]) * band
        return float(np.linalg.norm(err) / np.linalg.norm(np.fft.fft2(holo.object_wave[0])))

    on_axis = twin_in_band(0.0)
    separated = twin_in_band(math.asin(3.2 * f_obj * LAM))
    assert on_axis > 0.5, f"on axis the twin should overlap the virtual image: {on_axis:.2e}"
    assert separated < 0.05, f"off axis the twin still overlaps: {separated:.2e}"


def test_reference_angle_sampling_condition():
    safe = math.asin(LAM / (2 * PITCH))
    with pytest.raises(ValueError, match=f"largest safe angle is {safe:.4g}"):
        Reference(angle=2 * safe).check(LAM, PITCH)
    with pytest.warns(SamplingWarning):
        Reference(angle=2 * safe, allow_aliasing=True).check(LAM, PITCH)
    Reference(angle=0.9 * safe).check(LAM, PITCH)
    with pytest.raises(ValueError, match=r"reference angle must be in \[0, π/2\)"):
        Reference(angle=2.0)


def test_the_reference_wave_is_its_plane_wave():
    """R = A·exp(ik(x sin ϑ cos φ + y sin ϑ sin φ)) at the pixel centres ((j − (n − 1)/2)·p),
    against float64 NumPy to complex64 rounding, also 10 cm from the centre (over 10^5 rad of
    phase, reduced in float64 before the cast); and H = |O + R|² is the interference of Eq. 16."""
    shape, lam, pitch = (96, 160), 633e-9, 1e-6
    ref = Reference(angle=0.3, azimuth=1.1, beam_ratio=4.0)
    r = reference_wave(shape, wavelength=lam, pitch=pitch, reference=ref, amplitude=2.0)
    y = (np.arange(shape[0]) - (shape[0] - 1) / 2)[:, None] * pitch
    x = (np.arange(shape[1]) - (shape[1] - 1) / 2)[None, :] * pitch
    phase = 2 * np.pi / lam * math.sin(0.3) * (x * math.cos(1.1) + y * math.sin(1.1))
    assert r.dtype == np.complex64 and r.shape == shape
    assert np.abs(r - 2.0 * np.exp(1j * phase)).max() <= 2.0 * 1e-6
    far = reference_wave((1, 21), wavelength=lam, pitch=0.01, reference=ref)  # x = ±0.1 m
    want = np.exp(
        1j * np.remainder(2 * np.pi / lam * math.sin(0.3) * math.cos(1.1) * 0.1, 2 * np.pi)
    )
    assert abs(far[0, 20] - want) <= 1e-6 and abs(far[0, 0] - np.conj(want)) <= 1e-6
    o = np.exp(1j * np.linspace(0, 5, shape[1]))[None, :] * np.ones(shape)
    assert np.allclose(interfere(o, r), np.abs(o + r.astype(np.complex128)) ** 2, rtol=1e-5)
