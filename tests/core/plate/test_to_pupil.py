"""A carrier plate's field at the camera's pupil (holo_core.plate.to_pupil's CarrierPupil)
against an independent route: the carrier plate resampled by a band-limited interpolation
(Dirichlet kernels per axis, this file's own) onto a finer grid centred on the plate,
re-modulated by the carrier, and rendered by the full-band route (the offset angular spectrum
and the spectrum rotation). The views agree, read the samples in place, keep one stack of
spectra over a move, fold their pixels on the device as on the host, and converge in finer
depth layers."""

import dataclasses
import math

import numpy as np
import pytest
from accuracy import rel_err
from plate_scene import SMALL, camera

from holo_core.plate.view import render_view
from holo_core.scene.hologram import Hologram


@pytest.fixture(scope="module")
def plate(carrier_plate):
    return carrier_plate


def dirichlet(new, old, pitch) -> np.ndarray:
    """(len(new), len(old)) band-limited interpolation from samples at ``old`` (``pitch``
    apart) to the positions ``new``: the periodic sinc of N samples (N odd)."""
    n = len(old)
    t = (np.asarray(new)[:, None] - np.asarray(old)[None, :]) / pitch
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.sin(np.pi * t) / (n * np.sin(np.pi * t / n))
    return np.where(np.abs(t) < 1e-12, 1.0, d)


def full_band(h: Hologram, fine: float) -> Hologram:
    """The object wave of a carrier plate on a grid ``fine`` [m] apart centred on the plate,
    zero beyond the carrier's window: its samples interpolated, then re-modulated."""
    rows, cols = h.shape
    x, y = h.carrier.coords(h.pitch, np.arange(rows), np.arange(cols))
    half = max(np.abs(x).max(), np.abs(y).max()) + 4 * fine
    n = 2 * math.ceil(half / fine) + 1
    grid = (np.arange(n) - (n - 1) / 2) * fine
    inside_x = (grid >= x[0]) & (grid <= x[-1])
    inside_y = (grid >= y[0]) & (grid <= y[-1])
    ix, iy = dirichlet(grid[inside_x], x, h.pitch), dirichlet(grid[inside_y], y, h.row_pitch)
    waves = np.zeros((len(h.wavelengths), n, n), np.complex64)
    for c, lam in enumerate(h.wavelengths):
        b = iy @ np.asarray(h.object_wave[c], np.complex128) @ ix.T
        xs, ys = grid[inside_x], grid[inside_y]
        cx, cy, cz = h.carrier.centre
        r = np.sqrt((xs[None] - cx) ** 2 + (ys[:, None] - cy) ** 2 + cz * cz)
        waves[c][np.ix_(inside_y, inside_x)] = b * np.exp(-2j * np.pi / lam * r)
    return Hologram(
        object_wave=waves,
        encoding="complex",
        wavelengths=h.wavelengths,
        pitch=fine,
        channels=h.channels,
        point_density=h.point_density,
        zone=h.zone,
        bounds=h.bounds,
        plate=h.plate,
    )


def test_views_of_the_carrier_and_the_full_band_plate_agree(plate):
    """The same camera sees the carrier plate (demodulated onto its pupil, decimated, a
    non-uniform FFT onto its bins) and its full-band re-modulation (the angular spectrum to
    the pupil's plane, the spectrum rotated onto the camera's): the colour (radiance over
    coverage) PSNR >= 30 dB inside the objects, the coverage's shape (above half its median
    on the objects) IoU >= 0.97, depth within 1 mm. (The two routes calibrate radiance each
    by its own emitter model; the colour and the coverage's shape do not depend on it.)"""
    fine = min(plate.wavelengths) / (2 * 0.45)
    other = full_band(plate, fine)
    cam = camera("left", SMALL)
    a, b = render_view(plate, cam, supersample=2), render_view(other, cam, supersample=2)
    shapes = [
        v.coverage > 0.5 * np.median(v.coverage[v.coverage > 0.25 * v.coverage.max()])
        for v in (a, b)
    ]
    inside = shapes[0] & shapes[1]
    err = a.rgb[inside] - b.rgb[inside]
    p = 20 * np.log10(b.rgb[inside].max() / np.sqrt(np.mean(err**2)))
    j = (shapes[0] & shapes[1]).sum() / (shapes[0] | shapes[1]).sum()
    dz = float(np.median(np.abs(a.depth[inside] - b.depth[inside])))
    print(
        f"carrier against full band: PSNR {p:.1f} dB, IoU {j:.4f}, depth {dz * 1e3:.2f} "
        f"mm, coverage ratio {np.median(a.coverage[inside] / b.coverage[inside]):.3f}"
    )
    assert p >= 30 and j >= 0.97 and dz <= 1e-3, (p, j, dz)


def test_a_view_reads_the_samples_in_place_as_it_would_copy_them(plate):
    """A recorded plate's samples start on a page, so a CPU device's view reads them where
    they are; the same samples elsewhere (unaligned: copied band by band) give the same view
    bit for bit."""
    from holo_core.opencl import get_runtime
    from holo_core.opencl.arrays import host_buffer

    rt = get_runtime()
    assert plate.object_wave.ctypes.data % 4096 == 0
    raw = np.empty(plate.object_wave.nbytes + 8, np.uint8)
    moved = raw[8:].view(np.complex64).reshape(plate.object_wave.shape)
    moved[...] = plate.object_wave
    assert host_buffer(rt, moved) is None
    if rt.is_cpu:
        assert host_buffer(rt, plate.object_wave) is not None
    cam = camera("left", SMALL)
    a = render_view(plate, cam, supersample=2)
    b = render_view(dataclasses.replace(plate, object_wave=moved), cam, supersample=2)
    assert np.array_equal(a.rgb, b.rgb) and np.array_equal(a.depth, b.depth)


def test_views_over_a_move_keep_one_stack_of_spectra(plate):
    """The pupil's spectrum grows and shrinks with the window as the camera moves: its
    spectra (and the spread grids before them, in the same buffer) are one work array grown
    as needed, not one kept per shape met (205 MiB each on the shot of bench/shot.py)."""
    from holo_core.opencl import get_runtime
    from holo_core.optics.imaging import SPECTRA

    rt = get_runtime()
    for eye in ("left", "centre", "right"):
        render_view(plate, camera(eye, SMALL), supersample=2)
    stacks = [k for k in rt.cache if isinstance(k, tuple) and SPECTRA in k]
    assert stacks == [("workspace", SPECTRA)], stacks


def test_a_views_pixels_fold_on_the_device_as_the_fine_images_do_on_the_host(plate):
    """The view folds its fine images to the pixels on the device (PupilImage.fold); a
    composition by maximum and a depth by the brightest look compose the fine images
    themselves on the host. With one look the maximum is the mean: both views' radiance and
    colour agree to float32 rounding, and the brightest look's depth lies within the objects'
    depths seen from the camera."""
    cam = camera("left", SMALL)
    a = render_view(plate, cam, supersample=2)
    b = render_view(plate, cam, supersample=2, composition="max", depth_estimate="brightest")
    assert rel_err(b.radiance, a.radiance) < 1e-5 and rel_err(b.rgb, a.rgb) < 1e-5
    assert np.array_equal(a.alpha, b.alpha)
    near, far = np.percentile(a.depth[a.alpha > 0], [1, 99])
    seen = b.depth[b.alpha > 0]
    assert np.isfinite(seen).all() and np.median(np.abs(seen - a.depth[a.alpha > 0])) < 0.1 * (
        far - near
    ), (near, far)
