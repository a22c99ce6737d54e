"""Spectrum rotation, placed planes, resampling, Fresnel and Fraunhofer."""

import numpy as np
import pytest
from accuracy import FLOAT32_SUM, GAUSSIAN_BEAM, TILT, rel_err
from beams import gaussian_beam, mesh, rot_x, rot_y

from holo_core.opencl import get_runtime
from holo_core.propagation import (
    angular_spectrum,
    fraunhofer,
    fresnel,
    interpolation_matrix,
    propagate_to_plane,
    rayleigh_sommerfeld,
    resample,
    tilt,
)

LAM = 633e-9


def test_tilted_plane_wave_becomes_a_normal_plane_wave():
    n, pitch = 256, 0.5e-6
    x, _ = mesh((n, n), pitch)
    angle = np.arcsin(40 * LAM / (2 * n * pitch))  # on a frequency bin of the padded grid
    wave = np.exp(1j * 2 * np.pi * np.sin(angle) / LAM * x)
    out = tilt(wave, wavelength=LAM, pitch=pitch, rotation=rot_y(angle))
    centre = out[64:192, 64:192]
    phase = np.angle(centre / centre.mean())
    assert np.std(phase) < 5e-3, np.std(phase)
    assert np.all(np.abs(np.abs(centre) - 1) < 1e-2), (np.abs(centre).min(), np.abs(centre).max())


@pytest.mark.parametrize(
    "rotation, padding",
    [
        (rot_y(np.radians(20)), 2),
        (rot_y(np.radians(20)), 4),
        (rot_x(np.radians(-12)) @ rot_y(np.radians(8)), 2),
    ],
)
def test_tilted_gaussian_beam_is_untilted_on_the_plane_normal_to_it(rotation, padding):
    # the beam travels along the rotated z axis with its waist at the origin; on z = 0 it is
    # sampled from the analytic beam in its own coordinates (p_beam = Mᵀ p)
    n, pitch, w0 = 256, 0.5e-6, 20e-6
    x, y = mesh((n, n), pitch)
    p_beam = np.stack([x, y, np.zeros_like(x)], -1) @ rotation
    field = gaussian_beam(*np.moveaxis(p_beam, -1, 0), w0=w0, wavelength=LAM)
    out = tilt(field, wavelength=LAM, pitch=pitch, rotation=rotation, padding=padding)
    ref = gaussian_beam(x, y, 0.0, w0=w0, wavelength=LAM)
    assert rel_err(out, ref) <= TILT, rel_err(out, ref)


def test_placed_plane_equals_tilt_then_offset_propagation():
    n, pitch, w0 = 192, 0.5e-6, 12e-6
    x, y = mesh((n, n), pitch)
    m = rot_y(np.radians(10))
    p_beam = np.stack([x, y, np.zeros_like(x)], -1) @ m
    field = gaussian_beam(*np.moveaxis(p_beam, -1, 0), w0=w0, wavelength=LAM)
    # the target plane's centre sits on the beam axis 200 µm along it, 5 µm aside in η
    position = m @ np.array([0.0, 5e-6, 200e-6])
    out = propagate_to_plane(field, wavelength=LAM, pitch=pitch, rotation=m, position=position)
    ref = gaussian_beam(x, y + 5e-6, 200e-6, w0=w0, wavelength=LAM)
    assert rel_err(out, ref) <= TILT, rel_err(out, ref)


def test_resample_round_trips_band_limited_fields():
    pitch = 1.0e-6
    x, y = mesh((64, 48), pitch)
    field = np.exp(-(x**2 + y**2) / (8e-6) ** 2) * np.exp(1j * 0.3e6 * x)
    for shape, out_pitch in (
        ((128, 96), pitch / 2),
        ((43, 32), 1.5 * pitch),
        ((100, 80), pitch),
        ((40, 30), pitch),
    ):
        there = resample(field, pitch=pitch, out_shape=shape, out_pitch=out_pitch)
        back = resample(there, pitch=out_pitch, out_shape=(64, 48), out_pitch=pitch)
        # cutting in space keeps only what the small grid held
        inside = (
            (np.abs(x) < 14 * pitch) & (np.abs(y) < 19 * pitch)
            if shape == (40, 30)
            else np.ones_like(x, bool)
        )
        err = rel_err(back[inside], field[inside])
        assert err <= 1e-4, (shape, out_pitch, err)


def test_resample_equals_zero_padding_in_frequency(rng):
    field = rng.normal(size=(63, 63)) + 1j * rng.normal(size=(63, 63))
    spectrum = np.zeros((189, 189), complex)
    spectrum[63:126, 63:126] = np.fft.fftshift(np.fft.fft2(field))
    ref = np.fft.ifft2(np.fft.ifftshift(spectrum)) * 9  # samples at x = x_0 + j·pitch/3
    out = resample(field, pitch=1e-6, out_shape=(189, 189), out_pitch=1e-6 / 3)
    # the centred output grid starts a third of a pitch before the input's first sample
    assert rel_err(out[1:, 1:], ref[:-1, :-1]) <= FLOAT32_SUM, rel_err(out[1:, 1:], ref[:-1, :-1])


def test_resample_kernel_equals_float64_matrix_product(rng):
    field = rng.normal(size=(40, 50)) + 1j * rng.normal(size=(40, 50))
    ky = interpolation_matrix(40, 1e-6, 31, 1.3e-6)
    kx = interpolation_matrix(50, 1e-6, 39, 1.3e-6)
    out = resample(field, pitch=1e-6, out_shape=(31, 39), out_pitch=1.3e-6)
    assert rel_err(out, ky @ field @ kx.T) <= FLOAT32_SUM, rel_err(out, ky @ field @ kx.T)


def test_fresnel_equals_angular_spectrum_in_the_paraxial_regime():
    pitch, shape, w0 = 2e-6, (128, 128), 40e-6
    x, y = mesh(shape, pitch)
    field = gaussian_beam(x, y, 0.0, w0=w0, wavelength=LAM)
    a = angular_spectrum(field, wavelength=LAM, pitch=pitch, distance=2e-3)
    f = fresnel(field, wavelength=LAM, pitch=pitch, distance=2e-3)
    assert rel_err(f, a) <= GAUSSIAN_BEAM, rel_err(f, a)


def test_fraunhofer_equals_rayleigh_sommerfeld_in_the_far_field():
    # z = 0.5 m: the source-side phase k·ρs²/(2z) that Fraunhofer drops is 2.4e-3 rad here
    pitch, n, z = 2e-6, 256, 0.5
    x, y = mesh((n, n), pitch)
    aperture = ((np.abs(x) <= 10e-6) & (np.abs(y) <= 10e-6)).astype(np.complex64)
    far, (px, py) = fraunhofer(aperture, wavelength=LAM, pitch=pitch, distance=z)
    assert py == px == pytest.approx(LAM * z / (n * pitch))

    # paraxial centre (ρ <= 3.5 mm: the dropped k·ρ⁴/(8z³) term stays below 2e-3 rad)
    m = 8
    ref = rayleigh_sommerfeld(
        aperture, wavelength=LAM, pitch=pitch, distance=z, out_shape=(m, m), out_pitch=px
    )
    got = far[n // 2 - m // 2 : n // 2 + m // 2, n // 2 - m // 2 : n // 2 + m // 2]
    assert rel_err(got, ref) <= 2e-3, rel_err(got, ref)


def test_the_far_field_pitch_is_x_then_y():
    """A 64-row, 96-column field: the far field's x pitch (along its 96 columns) is
    λz/(96·pitch), its y pitch λz/(64·pitch), as every pitch pair is (x, y)."""
    pitch, z = 2e-6, 0.5
    _, (px, py) = fraunhofer(
        np.ones((64, 96), np.complex64), wavelength=LAM, pitch=pitch, distance=z
    )
    assert (px, py) == pytest.approx((LAM * z / (96 * pitch), LAM * z / (64 * pitch)))


def test_rayleigh_sommerfeld_kernel_equals_float64_numpy(rng):
    pitch, z = 1e-6, 300e-6
    field = rng.normal(size=(12, 10)) + 1j * rng.normal(size=(12, 10))
    out = rayleigh_sommerfeld(
        field,
        wavelength=LAM,
        pitch=pitch,
        distance=-z,
        out_shape=(9, 7),
        out_pitch=1.5e-6,
        offset=(3e-6, -2e-6),
    )
    xs, ys = mesh((12, 10), pitch)
    xo, yo = mesh((9, 7), 1.5e-6)
    dx = (xo.ravel() + 3e-6)[:, None] - xs.ravel()[None, :]
    dy = (yo.ravel() - 2e-6)[:, None] - ys.ravel()[None, :]
    r = np.sqrt(dx**2 + dy**2 + z**2)
    k = 2 * np.pi / LAM
    h = np.conj(z / (2 * np.pi * r**2) * (1 / r - 1j * k) * np.exp(1j * k * r))  # backwards
    ref = (h @ field.ravel() * pitch**2).reshape(9, 7)
    assert rel_err(out, ref) <= FLOAT32_SUM, rel_err(out, ref)


def test_rayleigh_sommerfeld_defaults_to_the_source_grid(rng):
    # zero samples are skipped, but the default output stays the whole source grid
    field = np.zeros((32, 24), complex)
    field[10:14, 5:9] = rng.normal(size=(4, 4))
    kw = dict(wavelength=LAM, pitch=1e-6, distance=300e-6)
    out = rayleigh_sommerfeld(field, **kw)
    assert out.shape == field.shape
    assert rel_err(out, rayleigh_sommerfeld(field, **kw, out_shape=field.shape)) == 0
    device = rayleigh_sommerfeld(get_runtime().to_device(field.astype(np.complex64)), **kw)
    assert rel_err(device.get(), out) <= FLOAT32_SUM


def test_direct_sum_warns_where_it_is_aliased():
    from holo_core.validate import SamplingWarning

    with pytest.warns(SamplingWarning, match="needs \\|distance\\| >= "):
        rayleigh_sommerfeld(np.ones((64, 64)), wavelength=LAM, pitch=2e-6, distance=1e-4)
