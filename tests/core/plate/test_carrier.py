"""A plate stored against its zone's carrier: exactly the full-band plate of the same scene,
re-modulated, and seen alike (plate/carrier.py, plate/to_pupil.py's CarrierPupil).

The carrier plate's samples are resampled here by a band-limited interpolation (Dirichlet
kernels per axis, this file's own) onto a finer grid centred on the plate, re-modulated by
the carrier, and rendered by the full-band route (an object wave centred on the plate, carried
to the pupil by the offset angular spectrum and the spectrum rotation, to_pupil.py): an
independent route to the same image."""

import math

import numpy as np
import pytest
from accuracy import rel_err
from plate_scene import PLATE, camera, meshes

from holo_core.plate.carrier import demodulate, modulate
from holo_core.plate.record import record_plate
from holo_core.plate.view import render_view
from holo_core.scene.hologram import Hologram

SCALE = 0.25   # the plate scene's camera at 160x90: a plate of about 640x640 samples


@pytest.fixture(scope="module")
def plate():
    return record_plate(meshes(), plate=PLATE, camera=camera("centre", SCALE), zone_margin=0.025)


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
    return Hologram(object_wave=waves, encoding="complex", wavelengths=h.wavelengths,
                    pitch=fine, channels=h.channels, point_density=h.point_density,
                    zone=h.zone, bounds=h.bounds, plate=h.plate)


def test_modulation_is_exact_and_invertible(rng):
    """O = B·exp(−ik|x − c|) and back, the phase formed in float64: the round trip returns
    the samples to float32 rounding."""
    from holo_core.scene.plate import Carrier
    carrier = Carrier(centre=(0.01, -0.02, 1.7), origin=(-0.3, -0.2), row_pitch=2e-4)
    b = (rng.normal(size=(2, 40, 50)) + 1j * rng.normal(size=(2, 40, 50))).astype(np.complex64)
    o = modulate(b, carrier, wavelength=7e-6, pitch=5e-5)
    assert rel_err(demodulate(o, carrier, wavelength=7e-6, pitch=5e-5), b) < 1e-6
    x, y = carrier.coords(5e-5, [39], [49])
    r = math.sqrt((x[0] - 0.01) ** 2 + (y[0] + 0.02) ** 2 + 1.7**2)
    want = complex(b[1, 39, 49]) * complex(np.exp(-1j * np.remainder(2 * np.pi / 7e-6 * r,
                                                                     2 * np.pi)))
    assert abs(o[1, 39, 49] - want) < 1e-5 * abs(want)


def test_views_of_the_carrier_and_the_full_band_plate_agree(plate):
    """The same camera sees the carrier plate (demodulated onto its pupil, decimated, a
    non-uniform FFT onto its bins) and its full-band re-modulation (the angular spectrum to
    the pupil's plane, the spectrum rotated onto the camera's): the colour (radiance over
    coverage) PSNR >= 30 dB inside the objects, the coverage's shape (above half its median
    on the objects) IoU >= 0.97, depth within 1 mm. (The two routes calibrate radiance each
    by its own emitter model; the colour and the coverage's shape do not depend on it.)"""
    fine = min(plate.wavelengths) / (2 * 0.45)
    other = full_band(plate, fine)
    cam = camera("left", SCALE)
    a, b = render_view(plate, cam, supersample=2), render_view(other, cam, supersample=2)
    shapes = [v.coverage > 0.5 * np.median(v.coverage[v.coverage > 0.25 * v.coverage.max()])
              for v in (a, b)]
    inside = shapes[0] & shapes[1]
    err = a.rgb[inside] - b.rgb[inside]
    p = 20 * np.log10(b.rgb[inside].max() / np.sqrt(np.mean(err**2)))
    j = (shapes[0] & shapes[1]).sum() / (shapes[0] | shapes[1]).sum()
    dz = float(np.median(np.abs(a.depth[inside] - b.depth[inside])))
    print(f"carrier against full band: PSNR {p:.1f} dB, IoU {j:.4f}, depth {dz * 1e3:.2f} "
          f"mm, coverage ratio {np.median(a.coverage[inside] / b.coverage[inside]):.3f}")
    assert p >= 30 and j >= 0.97 and dz <= 1e-3, (p, j, dz)
