"""Band-limited angular spectrum against analytic beams and the direct Rayleigh-Sommerfeld sum."""

import warnings

import numpy as np
import pytest
from accuracy import ASM_VS_RS, FLOAT32_PIPELINE, GAUSSIAN_BEAM, rel_err
from beams import gaussian_beam, mesh

from holo_core.propagation import angular_spectrum, rayleigh_sommerfeld, resample, transfer_function
from holo_core.propagation.grid import coords, padded_shape

LAM = 633e-9


@pytest.mark.parametrize("z", [3e-3, -3e-3])
@pytest.mark.parametrize("offset", [(0.0, 0.0), (40e-6, -24e-6)])
def test_gaussian_beam_matches_analytic(z, offset):
    # w0 = 30 µm: paraxial corrections (λ/πw0)² ~ 5e-5; beam stays well inside the window
    pitch, shape, w0 = 1e-6, (256, 320), 30e-6
    x, y = mesh(shape, pitch)
    field = gaussian_beam(x, y, 0.0, w0=w0, wavelength=LAM)
    out = angular_spectrum(field, wavelength=LAM, pitch=pitch, distance=z, offset=offset)
    ref = gaussian_beam(x + offset[0], y + offset[1], z, w0=w0, wavelength=LAM)
    assert rel_err(out, ref) <= GAUSSIAN_BEAM, rel_err(out, ref)


def _square_aperture(n, pitch, half_width):
    x, y = mesh((n, n), pitch)
    return ((np.abs(x) <= half_width) & (np.abs(y) <= half_width)).astype(np.complex64)


def _alias_free_half_width(z, pitch, source_half_width):
    """Half width [m] of the centred output square where the direct sum is alias-free.

    The impulse response at lateral separation ρ has local frequency ρ/(λr); the source pitch
    samples it while that stays below 1/(2·pitch), i.e. ρ <= z / sqrt((2·pitch/λ)² - 1).
    """
    rho = z / np.sqrt((2 * pitch / LAM) ** 2 - 1)
    return rho / np.sqrt(2) - source_half_width


@pytest.mark.slow
@pytest.mark.parametrize(
    "fresnel_number, padding, bound",
    [
        (5.0, 2, ASM_VS_RS["fresnel 1-5"]),
        (2.0, 2, ASM_VS_RS["fresnel 1-5"]),
        (1.0, 2, ASM_VS_RS["fresnel 1-5"]),
        (0.25, 2, ASM_VS_RS["fresnel 0.25"]),
        (0.25, 4, ASM_VS_RS["fresnel 0.25 padded 4x"]),
    ],
)
def test_square_aperture_matches_rayleigh_sommerfeld(fresnel_number, padding, bound):
    # 250 µm square, 512² at 2 µm, 633 nm; N_F = a²/(λz) with a the half width
    n, pitch, a = 512, 2e-6, 125e-6
    z = a * a / (LAM * fresnel_number)
    field = _square_aperture(n, pitch, a)
    asm = angular_spectrum(field, wavelength=LAM, pitch=pitch, distance=z, padding=padding)
    # the reference on every 8th sample of the window, where it is itself alias-free (the
    # direct sum warns otherwise, and warnings are errors here)
    step = 8
    half = min(_alias_free_half_width(z, pitch, a), n * pitch / 2)
    m = int(2 * half / (step * pitch))
    first = (n - step * (m - 1)) // 2
    sub = asm[first::step, first::step][:m, :m]
    centre = coords(n, pitch)[first::step][:m].mean()
    ref = rayleigh_sommerfeld(
        field,
        wavelength=LAM,
        pitch=pitch,
        distance=z,
        out_shape=(m, m),
        out_pitch=step * pitch,
        offset=(centre, centre),
    )
    assert rel_err(sub, ref) <= bound, (fresnel_number, padding, m, rel_err(sub, ref))


def test_airy_first_zero_of_focused_circular_aperture():
    # D = 0.5 mm, f = 2.5 mm, 0.5 µm pitch: ~8 samples per Airy radius (facts.md: fewer misses)
    n, pitch, f, radius = 1025, 0.5e-6, 2.5e-3, 0.25e-3
    x, y = mesh((n, n), pitch)
    k = 2 * np.pi / LAM
    lens = np.exp(-1j * k * np.sqrt(x**2 + y**2 + f**2))  # Eq. 24
    field = np.where(x**2 + y**2 <= radius**2, lens, 0)
    focus = angular_spectrum(field, wavelength=LAM, pitch=pitch, distance=f)
    row = focus[n // 2, n // 2 :]  # odd n: sample n//2 is on the axis
    signed = np.real(row * np.conj(row[0])) / abs(row[0])
    i = int(np.argmax(signed < 0))
    zero = (i - 1 + signed[i - 1] / (signed[i - 1] - signed[i])) * pitch
    na = radius / np.hypot(radius, f)
    expected = 0.61 * LAM / na
    assert abs(zero / expected - 1) <= 5e-3, (zero, expected)


def test_offset_equals_propagation_then_shift():
    pitch, shape, shift = 1e-6, (200, 256), (12, -7)  # (cols, rows) in samples
    x, y = mesh(shape, pitch)
    field = gaussian_beam(x, y, 0.0, w0=15e-6, wavelength=LAM)
    offset = (shift[0] * pitch, shift[1] * pitch)
    shifted = angular_spectrum(field, wavelength=LAM, pitch=pitch, distance=2e-3, offset=offset)
    plain = angular_spectrum(field, wavelength=LAM, pitch=pitch, distance=2e-3)
    # output sample (i, j) of the offset plane sits where the plain one has (i+dy, j+dx)
    a = shifted[20:-20, 20:-20]
    b = plain[20 + shift[1] : shape[0] - 20 + shift[1], 20 + shift[0] : shape[1] - 20 + shift[0]]
    assert rel_err(a, b) <= FLOAT32_PIPELINE, rel_err(a, b)


def _band_limited_noise(rng, shape, pitch, fmax):
    """Compact random field whose spectrum is negligible (< e^-9 in amplitude) beyond fmax."""
    x, y = mesh(shape, pitch)
    compact = np.exp(-((x / (shape[1] * pitch / 8)) ** 2 + (y / (shape[0] * pitch / 8)) ** 2))
    noise = (rng.normal(size=shape) + 1j * rng.normal(size=shape)) * compact
    fy = np.fft.fftfreq(shape[0], pitch)[:, None]
    fx = np.fft.fftfreq(shape[1], pitch)[None, :]
    return np.fft.ifft2(np.fft.fft2(noise) * np.exp(-9 * (fx**2 + fy**2) / fmax**2))


def test_forward_then_backward_is_identity_inside_the_band(rng):
    # z short enough that the spread field (angles <= λ·fmax ~ 0.06) stays in the window
    pitch, shape, z = 1e-6, (256, 256), 0.4e-3
    field = _band_limited_noise(rng, shape, pitch, fmax=0.1 / pitch)
    there = angular_spectrum(field, wavelength=LAM, pitch=pitch, distance=z)
    back = angular_spectrum(there, wavelength=LAM, pitch=pitch, distance=-z)
    assert rel_err(back, field) <= FLOAT32_PIPELINE, rel_err(back, field)


def test_energy_is_conserved_inside_the_band(rng):
    pitch, shape = 1e-6, (256, 256)
    field = _band_limited_noise(rng, shape, pitch, fmax=0.1 / pitch)
    out = angular_spectrum(field, wavelength=LAM, pitch=pitch, distance=2e-3)
    ratio = np.sum(np.abs(out) ** 2) / np.sum(np.abs(field) ** 2)
    assert abs(ratio - 1) <= FLOAT32_PIPELINE, ratio


def test_light_travels_towards_plus_z_and_offset_is_x_y():
    # a beam tilted towards +x drifts to +x when carried to +z (exp(+ikr), exp(-iωt))
    pitch, shape, z, angle = 1e-6, (128, 256), 2e-3, 0.02
    x, y = mesh(shape, pitch)
    beam = gaussian_beam(x, y, 0.0, w0=15e-6, wavelength=LAM) * np.exp(
        1j * 2 * np.pi * np.sin(angle) / LAM * x
    )
    out = np.abs(angular_spectrum(beam, wavelength=LAM, pitch=pitch, distance=z)) ** 2
    x_mean = np.sum(out * x) / np.sum(out)
    assert abs(x_mean - z * np.tan(angle)) < 0.5 * pitch, (x_mean, z * np.tan(angle))
    # offset (x0, y0) = (+30 µm, 0): a beam centred at x = +30 µm lands at the centre column
    beam = gaussian_beam(x - 30e-6, y, 0.0, w0=10e-6, wavelength=LAM)
    out = (
        np.abs(
            angular_spectrum(beam, wavelength=LAM, pitch=pitch, distance=1e-4, offset=(30e-6, 0.0))
        )
        ** 2
    )
    row, col = np.unravel_index(np.argmax(out), out.shape)
    assert (
        abs(coords(shape[1], pitch)[col]) <= pitch / 2
        and abs(coords(shape[0], pitch)[row]) <= pitch / 2
    )


def test_device_pipeline_equals_float64_numpy(rng, rt):
    shape, pitch, z, offset = (200, 160), 1.5e-6, 4e-3, (20e-6, -10e-6)
    field = rng.normal(size=shape) + 1j * rng.normal(size=shape)
    dev = rt.to_device(field.astype(np.complex64))
    out = angular_spectrum(dev, wavelength=LAM, pitch=pitch, distance=z, offset=offset)
    assert out.__class__.__name__ == "Array" and out.shape == shape  # device in, device out
    padded = padded_shape(shape, 2)
    r0, c0 = (padded[0] - shape[0]) // 2, (padded[1] - shape[1]) // 2
    big = np.zeros(padded, complex)
    big[r0 : r0 + shape[0], c0 : c0 + shape[1]] = field
    tf = transfer_function(padded, wavelength=LAM, pitch=pitch, distance=z, offset=offset)
    ref = np.fft.ifft2(np.fft.fft2(big) * tf)[r0 : r0 + shape[0], c0 : c0 + shape[1]]
    assert rel_err(out.get(), ref) <= FLOAT32_PIPELINE, rel_err(out.get(), ref)
    host = angular_spectrum(field, wavelength=LAM, pitch=pitch, distance=z, offset=offset)
    assert isinstance(host, np.ndarray) and np.array_equal(host, out.get())


def test_transfer_function_is_stable_for_large_kz():
    # k·z ~ 1e6 rad: the stable form agrees with a direct float64 evaluation far from cut-off
    shape, pitch, z = (64, 64), 2e-6, 0.1
    tf = transfer_function(shape, wavelength=LAM, pitch=pitch, distance=z, band_limit=False)
    fy, fx = np.fft.fftfreq(64, pitch)[:, None], np.fft.fftfreq(64, pitch)[None, :]
    direct = np.exp(1j * 2 * np.pi * z * np.sqrt(1 / LAM**2 - fx**2 - fy**2))
    assert np.max(np.abs(tf - direct)) < 1e-8


def test_unlimited_transfer_beyond_alias_free_distance_warns_with_the_limit():
    from holo_core.validate import SamplingWarning

    field = np.ones((64, 64), np.complex64)
    with pytest.warns(SamplingWarning, match=r"alias-free limit \d"):
        angular_spectrum(field, wavelength=LAM, pitch=2e-6, distance=1.0, band_limit=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # band limited: no warning at the same distance
        angular_spectrum(field, wavelength=LAM, pitch=2e-6, distance=1.0)


def test_resample_then_propagate_keeps_the_beam():
    # finer output pitch through resample, then ASM: equals the analytic beam on the fine grid
    pitch, shape, w0, z = 2e-6, (96, 96), 30e-6, 1e-3
    x, y = mesh(shape, pitch)
    field = gaussian_beam(x, y, 0.0, w0=w0, wavelength=LAM)
    fine = resample(field, pitch=pitch, out_shape=(192, 192), out_pitch=pitch / 2)
    out = angular_spectrum(fine, wavelength=LAM, pitch=pitch / 2, distance=z)
    xf, yf = mesh((192, 192), pitch / 2)
    ref = gaussian_beam(xf, yf, z, w0=w0, wavelength=LAM)
    assert rel_err(out, ref) <= GAUSSIAN_BEAM, rel_err(out, ref)
