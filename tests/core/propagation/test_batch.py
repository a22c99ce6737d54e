"""Fields and batches through the propagations: a Field carries its optics in and out, stays on
the device, and batches over distances and wavelengths equal the planes computed one by one."""

import math

import numpy as np
import pytest
from accuracy import FLOAT32_PIPELINE, GAUSSIAN_BEAM, rel_err
from beams import gaussian_beam, rot_y

from holo_core import to_device
from holo_core.optics.lens import thin_lens
from holo_core.propagation import angular_spectrum, fraunhofer, fresnel, grid, resample, tilt
from holo_core.scene import Field
from holo_core.validate import InputError

LAM, PITCH = 633e-9, 2e-6


def beam(shape=(64, 96), pitch=(PITCH, PITCH), w0=20e-6):
    x, y = grid.coords(shape[1], pitch[0])[None, :], grid.coords(shape[0], pitch[1])[:, None]
    return gaussian_beam(x, y, 0.0, w0=w0, wavelength=LAM).astype(np.complex64)


def test_a_field_carries_its_optics_and_stays_on_the_device(rt):
    f = Field(samples=to_device(beam()), wavelength=LAM, pitch=PITCH)
    out = angular_spectrum(f, distance=1e-3, offset=(1e-5, 0.0))
    assert out.on_device and out.wavelength == LAM and out.pitch == (PITCH, PITCH)
    assert np.allclose(out.pose[:3, 3], (1e-5, 0.0, 1e-3)), out.pose
    want = angular_spectrum(beam(), wavelength=LAM, pitch=PITCH, distance=1e-3, offset=(1e-5, 0.0))
    assert np.array_equal(out.samples.get(), want)
    with pytest.raises(InputError, match="wavelength comes with the Field"):
        angular_spectrum(f, wavelength=LAM, distance=1e-3)


def test_a_focus_sweep_is_one_call(rt):
    """100 distances in one call on the device, each plane what one call makes."""
    u = to_device(beam())
    z = np.linspace(-2e-3, 2e-3, 100)
    stack = angular_spectrum(u, wavelength=LAM, pitch=PITCH, distance=z)
    assert stack.shape == (100, 64, 96)
    for i in (0, 37, 99):
        one = angular_spectrum(u, wavelength=LAM, pitch=PITCH, distance=z[i]).get()
        assert np.array_equal(stack[i].get(), one), i
    f = angular_spectrum(Field(samples=u, wavelength=LAM, pitch=PITCH), distance=z)
    assert f.batch_shape == (100,) and np.allclose(f.pose[:, 2, 3], z)
    assert np.allclose(f[37].pose[2, 3], z[37]) and f[37].samples.shape == (64, 96)


def test_wavelengths_and_distances_broadcast():
    """A stack of three colours with their wavelengths, at two distances: (2, 3) planes."""
    lam = np.array([633e-9, 532e-9, 473e-9])
    u = np.stack([beam()] * 3)
    z = np.array([[1e-3], [2e-3]])
    out = angular_spectrum(Field(samples=u, wavelength=lam, pitch=PITCH), distance=z)
    assert out.batch_shape == (2, 3) and np.array_equal(out.wavelengths()[1], lam)
    for i, j in ((0, 0), (1, 2)):
        one = angular_spectrum(u[j], wavelength=lam[j], pitch=PITCH, distance=z[i, 0])
        assert np.array_equal(out.samples[i, j], one), (i, j)
    with pytest.raises(InputError, match="batch shapes do not broadcast"):
        angular_spectrum(u, wavelength=lam[:2], pitch=PITCH, distance=1e-3)


def test_an_anisotropic_pitch_propagates_the_analytic_beam():
    """A Gaussian beam sampled at 2 µm x 3 µm, carried 2 mm: the paraxial formula within
    GAUSSIAN_BEAM (w0 >> λ), by the angular spectrum and by Fresnel."""
    pitch, shape, z = (2e-6, 3e-6), (96, 128), 2e-3
    x, y = grid.coords(shape[1], pitch[0])[None, :], grid.coords(shape[0], pitch[1])[:, None]
    src = gaussian_beam(x, y, 0.0, w0=25e-6, wavelength=LAM)
    ref = gaussian_beam(x, y, z, w0=25e-6, wavelength=LAM)
    for method in (angular_spectrum, fresnel):
        out = method(Field(samples=src, wavelength=LAM, pitch=pitch), distance=z, padding=2)
        err = rel_err(out.samples, ref)
        assert err <= GAUSSIAN_BEAM, f"{method.__name__}: {err:.3g}"


def test_a_lens_collimates_the_point_at_its_focus():
    """A spherical wave from a point f = 5 mm in front, through a lens of that focal length:
    the phase becomes flat (exp(ikf)), to float32."""
    f, n = 5e-3, 128
    x, y = np.meshgrid(grid.coords(n, PITCH), grid.coords(n, PITCH))
    r = np.sqrt(x * x + y * y + f * f)
    sphere = np.exp(2j * np.pi / LAM * np.remainder(r, LAM)) / r * f
    out = thin_lens(Field(samples=sphere, wavelength=LAM, pitch=PITCH), focal_length=f)
    flat = np.exp(2j * np.pi / LAM * math.remainder(f, LAM)) * f / r
    err = rel_err(out.samples, flat)
    assert err <= FLOAT32_PIPELINE, f"{err:.3g}"


def test_the_far_field_and_the_tilt_update_pitch_and_pose():
    f = Field(samples=beam((64, 96)), wavelength=LAM, pitch=PITCH)
    far = fraunhofer(f, distance=0.5)
    assert far.pitch == pytest.approx((LAM * 0.5 / (96 * PITCH), LAM * 0.5 / (64 * PITCH)))
    tilted = tilt(f, rotation=rot_y(0.1))
    assert np.allclose(tilted.pose[:3, :3], rot_y(0.1))
    finer = resample(f, out_shape=(128, 192), out_pitch=PITCH / 2)
    assert finer.pitch == (PITCH / 2, PITCH / 2) and finer.shape == (128, 192)


def test_the_memory_of_a_batch_is_checked_first(monkeypatch):
    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "64M")
    with pytest.raises(InputError, match=r"4000 planes of 64x96 needs"):
        angular_spectrum(beam(), wavelength=LAM, pitch=PITCH, distance=np.zeros(4000) + 1e-3)


def test_field_checks_and_summary(rt):
    with pytest.raises(InputError, match=r"wavelength must be in .*633 looks like nanometres"):
        Field(samples=np.ones((4, 4)), wavelength=633, pitch=PITCH)
    with pytest.raises(InputError, match="wavelength must be a number"):
        Field(samples=np.ones((2, 4, 4)), wavelength=[LAM] * 3, pitch=PITCH)
    with pytest.raises(InputError, match="samples must be"):
        Field(samples=np.ones(4), wavelength=LAM, pitch=PITCH)
    f = Field(samples=to_device(np.ones((2, 4, 6))), wavelength=[LAM, 532e-9], pitch=(PITCH, 3e-6))
    text = repr(f)
    assert text.startswith("Field(batch 2 of 4x6, λ 532/633 nm, pitch 2 µm x 3 µm, device "), text
    assert f.to_numpy().samples.shape == (2, 4, 6) and not f.to_numpy().on_device
    assert f[1].wavelength == 532e-9 and f.size == (6 * PITCH, 12e-6)


def test_a_batch_over_an_empty_field_is_the_projects_error():
    """A batch of two wavelengths over a 0x0 field is the project's error naming the field's
    shape, not a failed reshape."""
    with pytest.raises(
        InputError,
        match=r"field must be \(\.\.\., H, W\) with H, W >= 1; got "
        r"shape \(0, 0\)",
    ):
        angular_spectrum(
            np.zeros((0, 0), np.complex64), wavelength=[633e-9, 532e-9], pitch=1e-6, distance=1e-4
        )
