"""A view's composition on the host (optics/imaging.py assemble, optics/speckle.py box_mean,
plate/view.py _radiance and _spread), done in place in float32, against the same formulas in
float64 NumPy written out plainly here: alpha from the coverage and its 3×3 neighbourhood,
the colour as radiance over coverage, the planar depth from the depth pair's cross image, the
looks' mean radiance and the speckle contrast between looks."""

import numpy as np
import pytest
from accuracy import rel_err

from holo_core.optics.depth import from_cross_spectrum
from holo_core.optics.imaging import COVERAGE_EDGE, COVERAGE_FLOOR, Folded, assemble
from holo_core.optics.speckle import box_mean
from holo_core.plate.composition import _radiance, _spread
from holo_core.scene.camera import Camera, look_at
from holo_core.view import BACKGROUND_DEPTH

IN_PLACE = 2e-6  # float32 steps in place against float64: measured 2e-7 … 6e-7
H, W = 18, 32
WAVELENGTHS = (633e-9, 632.9e-9)
CENTRE = 3.5  # [m]


def box_mean_64(image, r):
    """The (2r+1)² neighbourhood's mean, edges repeated, pixel by pixel in float64."""
    a = np.pad(np.asarray(image, np.float64), r, mode="edge")
    n = 2 * r + 1
    return np.array(
        [
            [a[i : i + n, j : j + n].mean() for j in range(image.shape[1])]
            for i in range(image.shape[0])
        ]
    )


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("r", [1, 2])
def test_the_box_mean_keeps_the_images_type_and_equals_float64(rng, dtype, r):
    image = rng.random((H, W)).astype(dtype)
    out = box_mean(image, r)
    assert out.dtype == dtype
    assert rel_err(out, box_mean_64(image, r)) < (IN_PLACE if dtype == np.float32 else 1e-14)
    assert box_mean(image, 0) is image
    assert box_mean(image.astype(np.int32), 1).dtype == np.float64  # counts are not rounded


def camera():
    return Camera(
        matrix_world=look_at((0.1, 0, 3.0), (0, 0, 0), up=(0, 1, 0)),
        lens=40,
        sensor_width=36,
        resolution=(W, H),
        shift_x=0.1,
    )


def test_the_assembled_view_equals_its_formulas_in_float64(rng):
    cam, exposure = camera(), 0.7
    coverage = np.clip(rng.random((H, W)) * 1.4 - 0.2, 0, 1).astype(np.float32)
    coverage[:, :5] = 0  # an empty strip: background depth there
    radiance = (rng.random((H, W, 3)) * coverage[..., None]).astype(np.float32)
    depth_phase = rng.uniform(-3, 3, (H, W))
    cross = (rng.random((H, W)) * np.exp(1j * depth_phase)).astype(np.complex64)
    colour, alpha, depth, shown, cover = assemble(
        radiance,
        coverage,
        cross,
        camera=cam,
        supersample=1,
        wavelengths=WAVELENGTHS,
        centre=CENTRE,
        exposure=exposure,
    )

    lo, hi = COVERAGE_EDGE
    c64 = coverage.astype(np.float64)
    alpha64 = np.clip((np.maximum(c64, box_mean_64(c64, 1)) - lo) / (hi - lo), 0, 1)
    colour64 = radiance / np.maximum(c64, COVERAGE_FLOOR)[..., None] * exposure
    tx, ty = cam.pixel_tangents()
    ray64 = from_cross_spectrum(cross.astype(np.complex128), wavelengths=WAVELENGTHS, centre=CENTRE)
    depth64 = np.where(alpha64 > 0, ray64 / np.sqrt(1 + tx**2 + ty**2), BACKGROUND_DEPTH)
    for got in (colour, alpha, depth, shown, cover):
        assert got.dtype == np.float32 and got.shape[:2] == (H, W)
    assert rel_err(alpha, alpha64) < IN_PLACE
    assert rel_err(colour, colour64) < IN_PLACE
    assert rel_err(shown, radiance * np.float64(exposure)) < IN_PLACE
    assert np.array_equal(cover, coverage)
    solid = alpha64 > 0
    assert np.array_equal(alpha > 0, solid) and (~solid).any()
    assert np.all(depth[~solid] == np.float32(BACKGROUND_DEPTH))
    assert np.abs(depth[solid] - depth64[solid]).max() < IN_PLACE * CENTRE


def looks_of(rng, n, colours=(0, 1, 2), partner=3):
    """n looks' images at the pixels: colours of a shared surface and the depth partner's
    coverage, each with a residual speckle of its own per look."""
    surface = rng.random((H, W, len(colours)))
    cover = np.clip(rng.random((H, W)) * 1.5, 0, 1)
    looks = []
    for _ in range(n):
        speckle = rng.exponential(size=(len(colours) + 1, H, W)) * 0.1 + 0.9
        power = {
            c: (surface[..., i] * cover * speckle[i]).astype(np.float32)
            for i, c in enumerate(colours)
        }
        power[partner] = (cover * speckle[-1]).astype(np.float32)
        looks.append(Folded(power, None, None))
    return looks, list(colours), partner


@pytest.mark.parametrize("n", [1, 2, 4])
def test_the_looks_radiance_and_speckle_contrast_equal_float64(rng, n):
    looks, colours, z = looks_of(rng, n)
    radiance = _radiance(looks, colours, "mean", 1)
    ref = np.stack(
        [np.mean([look.power[c].astype(np.float64) for look in looks], 0) for c in colours], -1
    )
    assert radiance.dtype == np.float32 and rel_err(radiance, ref) < IN_PLACE
    coverage = np.mean([look.power[z] for look in looks], 0)
    contrast = _spread(looks, colours, z, coverage)
    if n == 1:
        assert np.isnan(contrast)
        return
    lum = np.array(
        [
            np.mean([look.power[c].astype(np.float64) for c in colours], 0)
            / np.maximum(look.power[z], 0.05)
            for look in looks
        ]
    )
    solid = coverage >= 0.75
    ratio = lum.std(0)[solid] / np.sqrt(n) / lum.mean(0)[solid]
    assert abs(contrast - np.median(ratio)) < 1e-5 * np.median(ratio)
    assert np.isnan(_spread(looks, colours, z, np.zeros_like(coverage)))  # nothing solid
