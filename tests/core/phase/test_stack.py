"""The display's focal stack: the block's transfer function is the angular spectrum's, a
Gaussian beam through it spreads as the analytic beam does, the adjoint is the adjoint, and
the comparison's PSNR and SSIM are those of the slices."""

import math

import numpy as np
import pytest

from holo_core.phase.stack import Optics, compare
from holo_core.propagation import grid
from holo_core.propagation.transfer import transfer_function

LAM, PITCH = 520e-9, 8e-6


def test_the_blocks_transfer_is_the_angular_spectrums():
    """Against transfer_function (float64, the band limit included) on the padded grid, the
    filter's rectangle cut from it: the same values to float32's precision."""
    op = Optics((48, 64), pitch=PITCH, wavelength=LAM, distances=[-4e-3, 7e-3])
    for k, z in enumerate(op.distances):
        full = transfer_function(op.padded, wavelength=LAM, pitch=PITCH, distance=z)
        err = np.abs(full[op.block] - op.transfer(k)).max()
        assert err <= 2e-6, err
    fy = grid.freqs(op.padded[0], PITCH)[op.rows]
    assert np.abs(fy).max() <= 0.5 / (2 * PITCH) and op.rows.size >= op.padded[0] // 2 - 1


def test_a_gaussian_beam_spreads_as_the_analytic_one():
    """A waist of 60 µm (its spectrum 1/(π·w0) = 5.3e3 cycles/m, far inside the filter's
    3.1e4) carried 20 mm: |U| = (w0/w)·exp(−r²/w²), w = w0·√(1 + (z/zR)²), zR = π·w0²/λ
    (paraxial: the next term is (w0/z)²·... ~1e-5 here)."""
    shape, w0, z = (128, 160), 60e-6, 20e-3
    y, x = (grid.coords(n, PITCH) for n in shape)
    r2 = y[:, None] ** 2 + x[None, :] ** 2
    u = np.exp(-r2 / w0**2)
    op = Optics(shape, pitch=PITCH, wavelength=LAM, distances=[z])
    got = op.stack(u)[0]
    zr = math.pi * w0**2 / LAM
    w = w0 * math.sqrt(1 + (z / zr) ** 2)
    want = w0 / w * np.exp(-r2 / w**2)
    err = np.abs(got - want).max()
    assert err <= 2e-4, err


def test_the_adjoint_is_the_adjoint(rng):
    """<A x, y> = <x, Aᴴ y> for A the display to one plane (pupil included)."""
    op = Optics(
        (40, 56), pitch=PITCH, wavelength=LAM, distances=[3e-3], pupil=(0.5e-3, -0.2e-3, 2e-3, 0.1)
    )
    x = (rng.normal(size=op.shape) + 1j * rng.normal(size=op.shape)).astype(np.complex64)
    y = (rng.normal(size=op.shape) + 1j * rng.normal(size=op.shape)).astype(np.complex64)
    ax = op.to_plane(op.spectrum(x), 0)
    ahy = op.back(op.from_plane(y, 0))
    left, right = np.vdot(ax, y), np.vdot(x, ahy)
    assert abs(left - right) <= 1e-5 * abs(left), (left, right)


def test_a_pupil_outside_the_band_is_refused():
    from holo_core.validate import InputError

    with pytest.raises(InputError, match="outside the band"):
        Optics((16, 16), pitch=PITCH, wavelength=LAM, distances=[0.0], pupil=(20e-3, 0, 1e-3, 0.1))


def test_the_comparison_is_the_slices_psnr_and_ssim(rng):
    """A stack at twice the brightness compares as equal (the fit takes the scale); one with
    noise of σ = 0.01 of the peak in each slice has PSNR 40 dB (10·log10(1/σ²))."""
    ref = rng.random((3, 32, 32)) + 0.5
    same = compare(2 * ref, ref)
    assert same.scale == pytest.approx(0.5) and same.psnr_db == [math.inf] * 3
    assert same.ssim == pytest.approx([1.0] * 3)
    noise = rng.normal(size=ref.shape)
    noise -= noise.mean()
    noise *= 0.01 * ref.max() / noise.std()
    c = compare(ref + noise, ref)
    assert c.mean_psnr_db == pytest.approx(40.0, abs=0.1), c.psnr_db


def _point_at(shape, depth):
    """The display's field of a point ``depth`` [m] behind it on the axis: a sample's delta
    on the plane there carried to the display (the whole band: its light fills a cone of
    asin(λ/2p) = 1.9°; Optics' own forward)."""
    delta = np.zeros(shape, np.complex64)
    delta[shape[0] // 2, shape[1] // 2] = 1
    op = Optics(shape, pitch=PITCH, wavelength=LAM, distances=[-depth], band=1.0)
    return op.window(op.spectrum(delta) * op.transfer(0))


def test_an_eye_focused_on_a_point_sees_its_airy_pattern():
    """A point 4 mm behind, a 1 mm pupil 100 mm in front, the eye focused on the point's
    plane: |U| against the analytic Airy amplitude |2·J1(v)/v|, v = π·a·r/(λL), L = 104 mm
    (its first zero 1.22·λL/a = 66 µm, 8.2 samples), within 1 % of the peak over the
    central 3 zeros' radius."""
    from scipy.special import j1

    from holo_core.phase.stack import EyePupil

    shape, depth, a, d = (256, 256), -4e-3, 1e-3, 0.1
    u = _point_at((512, 512), depth)[128:384, 128:384]
    op = Optics(
        shape,
        pitch=PITCH,
        wavelength=LAM,
        distances=[depth],
        band=1.0,
        eye=EyePupil(diameter=a, distance=d),
    )
    seen = op.seen(u)[0]
    focus = seen / seen.max()
    r = _radius(shape)
    v = np.pi * a * r / (LAM * (d - depth))
    airy = np.abs(np.where(v > 0, 2 * j1(v) / np.where(v > 0, v, 1), 1.0))
    near = r <= 3 * 1.22 * LAM * (d - depth) / a
    err = np.abs(focus - airy)[near].max()
    assert err <= 0.01, err


def test_an_eye_focused_nearer_sees_a_point_as_its_cone_cut_by_the_plane():
    """The point 4 mm behind, a 4 mm pupil 100 mm in front focused 3 mm nearer (1 mm
    behind): the light fills the disc the cone from the point to the pupil cuts there,
    a·Δz/L' = 115 µm across (L' = 104 mm; the Airy pattern's 16 µm radius blurs its rim): over
    90 % of it within the disc's radius and the Airy pattern's, under 40 % within half its radius (a
    uniform disc: 25 %)."""
    from holo_core.phase.stack import EyePupil

    shape, depth, a, d = (256, 256), -4e-3, 4e-3, 0.1
    u = _point_at((512, 512), depth)[128:384, 128:384]
    op = Optics(
        shape,
        pitch=PITCH,
        wavelength=LAM,
        distances=[depth + 3e-3],
        band=1.0,
        eye=EyePupil(diameter=a, distance=d),
    )
    blur = op.seen(u)[0].astype(np.float64) ** 2
    r, radius = _radius(shape), a * 3e-3 / (d - depth) / 2
    inside = float(blur[r <= radius + 1.22 * LAM * (d - depth) / a].sum() / blur.sum())
    middle = float(blur[r <= radius / 2].sum() / blur.sum())
    assert inside >= 0.9 and 0.15 <= middle <= 0.4, (inside, middle)


def _radius(shape) -> np.ndarray:
    """[m] from the sample the point sits on."""
    y, x = (grid.coords(n, PITCH) for n in shape)
    return np.hypot(y[:, None] - y[shape[0] // 2], x[None, :] - x[shape[1] // 2])


@pytest.mark.parametrize("towards", [True, False])
def test_an_eye_sees_a_patch_only_where_its_light_heads_into_the_pupil(towards):
    """A patch 0.8 mm off the axis carrying a plane wave: aimed at a 1 mm pupil 100 mm in
    front (frequency (e − x)/(λL)) the eye focused on it sees it (over 80 % of its light),
    aimed as far the other way (−(e − x)/(λL)) it sees under 1 %."""
    from holo_core.phase.stack import EyePupil

    shape, d, a, x0 = (256, 384), 0.1, 1e-3, 0.8e-3
    y, x = (grid.coords(n, PITCH) for n in shape)
    patch = (np.abs(y[:, None]) <= 0.2e-3) & (np.abs(x[None, :] - x0) <= 0.2e-3)
    f = (0 - x0) / (LAM * d) * (1 if towards else -1)
    u = patch * np.exp(2j * np.pi * f * x[None, :])
    op = Optics(
        shape,
        pitch=PITCH,
        wavelength=LAM,
        distances=[0.0],
        band=1.0,
        eye=EyePupil(diameter=a, distance=d),
    )
    share = float((op.seen(u)[0] ** 2).sum() / (np.abs(op.stack(u)[0]) ** 2).sum())
    assert (share >= 0.8) if towards else (share <= 0.01), share


def test_an_eye_too_close_for_the_grid_is_refused():
    from holo_core.phase.stack import EyePupil
    from holo_core.validate import InputError

    with pytest.raises(InputError, match="eye: a pupil 10 mm"):
        Optics(
            (1080, 1920),
            pitch=PITCH,
            wavelength=LAM,
            distances=[-5e-3],
            eye=EyePupil(diameter=4e-3, distance=0.01),
        )
