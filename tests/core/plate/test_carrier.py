"""A plate stored against its zone's carrier: exactly the full-band plate of the same scene,
re-modulated, and seen alike (plate/carrier.py, plate/to_pupil.py's CarrierPupil).

The carrier plate's samples are resampled here by a band-limited interpolation (Dirichlet
kernels per axis, this file's own) onto a finer grid centred on the plate, re-modulated by
the carrier, and rendered by the full-band route (an object wave centred on the plate, carried
to the pupil by the offset angular spectrum and the spectrum rotation, to_pupil.py): an
independent route to the same image.

The physical field re-modulated from the samples (carrier.physical_field: a Kaiser-windowed
sinc and the exact carrier) is checked against the float64 direct sum of the same emitters
(tests/zone_reference.py) on fine grids, whole and within the zone's own band."""

import dataclasses
import math

import numpy as np
import pytest
from accuracy import PHYSICAL_FIELD, rel_err
from plate_scene import PLATE, camera, meshes
from zone_reference import carrier_plate, object_wave

from holo_core.plate.carrier import demodulate, modulate, physical_field, physical_pitch, window
from holo_core.plate.looks import record_looks, record_plate
from holo_core.plate.reconstruction import reconstruct
from holo_core.plate.recording import look_code
from holo_core.plate.view import render_view
from holo_core.plate.zone_sum import ZoneEmitters
from holo_core.scene.hologram import Hologram
from holo_core.scene.plate import ViewingZone
from holo_core.validate import InputError

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
    cam = camera("left", SCALE)
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
        render_view(plate, camera(eye, SCALE), supersample=2)
    stacks = [k for k in rt.cache if isinstance(k, tuple) and SPECTRA in k]
    assert stacks == [("workspace", SPECTRA)], stacks


def test_a_views_pixels_fold_on_the_device_as_the_fine_images_do_on_the_host(plate):
    """The view folds its fine images to the pixels on the device (PupilImage.fold); a
    composition by maximum and a depth by the brightest look compose the fine images
    themselves on the host. With one look the maximum is the mean: both views' radiance and
    colour agree to float32 rounding, and the brightest look's depth lies within the objects'
    depths seen from the camera."""
    cam = camera("left", SCALE)
    a = render_view(plate, cam, supersample=2)
    b = render_view(plate, cam, supersample=2, composition="max", depth_estimate="brightest")
    assert rel_err(b.radiance, a.radiance) < 1e-5 and rel_err(b.rgb, a.rgb) < 1e-5
    assert np.array_equal(a.alpha, b.alpha)
    near, far = np.percentile(a.depth[a.alpha > 0], [1, 99])
    seen = b.depth[b.alpha > 0]
    assert np.isfinite(seen).all() and np.median(np.abs(seen - a.depth[a.alpha > 0])) < 0.1 * (
        far - near), (near, far)


def test_views_in_finer_depth_layers_converge(plate, monkeypatch):
    """The gather's depth layers (spaced in 1/z so that each one's curvature errs by at most
    LAYER_PHASE at the pupil's rim), each spread, transformed and curved by its own distance
    on the device, converge as they get finer: against a thousandth of LAYER_PHASE (35
    layers here), the default's one layer (a quarter wave at the rim for the samples farthest
    from it) is within 1e-2 and a three-hundredth's (11 layers)
    less than half as far (the error falls as the phase error, to first order: 3.2e-3 and
    8.2e-4 here); the silhouettes are the same."""
    from holo_core.plate import to_pupil
    cam = camera("left", SCALE)
    made, counts, views = to_pupil._Gather._layers, [], []

    def layers(self, wavelength):
        out = made(self, wavelength)
        counts.append(len(out))
        return out

    monkeypatch.setattr(to_pupil._Gather, "_layers", layers)
    for share in (1, 300, 1000):
        monkeypatch.setattr(to_pupil, "LAYER_PHASE", math.pi / 2 / share)
        views.append(render_view(plate, cam, supersample=2))
    assert counts[0] == 1 and counts[-1] > 10, counts
    one, fine, finer = views
    far = rel_err(one.radiance, finer.radiance)
    assert far < 1e-2 and rel_err(fine.radiance, finer.radiance) < 0.5 * far
    assert all(np.array_equal(v.alpha > 0.5, finer.alpha > 0.5) for v in (one, fine))


@pytest.mark.parametrize("looks", [2, 3])
def test_looks_recorded_together_equal_looks_recorded_alone(looks):
    """record_looks sums every look in one pass: each look equals record_plate's of its code
    (2: the checkerboard pair of one seed, summed once per class of equal code shifts and
    mixed) or of its own seed (3: independent looks, summed as further channels) within
    float32 rounding, 1e-5 of the largest sample (a look alone sums its depth partner in the
    colours' pass, three independent looks theirs apart, and the compiler's fast arithmetic
    rounds the two kernels' shared steps alike only to float32); and its memory budget
    counts every look."""
    kw = {"plate": PLATE, "camera": camera("centre", SCALE), "zone_margin": 0.025}
    together = record_looks(meshes(), looks=looks, seed=4, **kw)
    assert len(together) == looks
    for k, h in enumerate(together):
        code = look_code(k, looks)
        alone = record_plate(meshes(), seed=4 + (0 if code else k), code=code, **kw)
        a, b = h.object_wave, alone.object_wave
        assert np.max(np.abs(a - b)) <= 1e-5 * np.max(np.abs(b)), (k, np.max(np.abs(a - b)))
        assert h.carrier == alone.carrier and h.wavelengths == alone.wavelengths
    one = together[0].object_wave.nbytes  # a look recorded alone fits where all do not
    assert len(record_looks(meshes(), looks=1, budget=(2.5 * one, None), **kw)) == 1
    with pytest.raises(InputError, match="memory budget"):
        record_looks(meshes(), looks=looks, budget=(2.5 * one, None), **kw)


# --- the physical field, re-modulated wherever it is needed --------------------------------

ZONE = ViewingZone(centre=(0.01, -0.005, 0.3), half_extents=(0.03, 0.02, 0.01))
LAMBDA = 5e-6


@pytest.fixture(scope="module")
def emitters():
    """40 emitters 0.25-0.35 m behind the plate, seen from the whole zone."""
    rng = np.random.default_rng(1)
    n = 40
    pos = np.stack([rng.uniform(-0.02, 0.02, n), rng.uniform(-0.02, 0.02, n),
                    rng.uniform(-0.35, -0.25, n)], 1)
    return ZoneEmitters(position=pos, amplitude=rng.normal(size=(n, 1)) + 1j * rng.normal(
        size=(n, 1)), visibility=np.full(n, -1, np.int32), table=np.zeros((0, 3, 5), np.uint8),
        grid=((-0.03, 0.015), (-0.02, 0.01)))


def zone_band_only(o, xs, ys):
    """The spectrum of O's light towards the zone itself (not its soft rim): O demodulated by
    the carrier, Kaiser-windowed (β = 14), kept where both direction cosines lie within the
    zone's own band, the largest turn from the line to its centre to a line to a corner of its
    box, over the region's corners (this file's own, not the planner's)."""
    c, e = np.asarray(ZONE.centre), np.asarray(ZONE.half_extents)
    corners = c + e * np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1)
                                for sz in (-1, 1)])
    unit = lambda v: v / np.linalg.norm(v, axis=-1, keepdims=True)  # noqa: E731
    points = np.array([[x, y, 0.0] for x in xs[[0, -1]] for y in ys[[0, -1]]])
    turn = np.abs(unit(corners[None] - points[:, None]) - unit(c - points)[:, None])
    bx, by = turn[..., 0].max(), turn[..., 1].max()
    r = np.sqrt((xs[None] - c[0]) ** 2 + (ys[:, None] - c[1]) ** 2 + c[2] ** 2)
    b = o * np.exp(2j * np.pi / LAMBDA * r) * np.kaiser(len(ys), 14)[:, None] * \
        np.kaiser(len(xs), 14)[None]
    fx = np.fft.fftfreq(len(xs), xs[1] - xs[0]) * LAMBDA
    fy = np.fft.fftfreq(len(ys), ys[1] - ys[0]) * LAMBDA
    return np.fft.fft2(b) * ((np.abs(fx)[None] <= bx) & (np.abs(fy)[:, None] <= by))


@pytest.mark.parametrize("finer, where, whole, in_band", [
    (2, 0.5, PHYSICAL_FIELD, PHYSICAL_FIELD), (2, 0.3, PHYSICAL_FIELD, PHYSICAL_FIELD),
    (1, 0.5, 1e-3, PHYSICAL_FIELD), (1, 0.3, 3e-2, 1e-3)])
def test_the_physical_field_equals_the_direct_sum_of_the_emitters(emitters, finer, where, whole,
                                                                  in_band):
    """physical_field (B interpolated band-limited, re-modulated by the exact carrier) on a
    401² grid at 0.9 × physical_pitch, in the window's middle (0.5) and off it (0.3 of its
    width and height), against O summed directly (float64 NumPy, the same emitters and
    windows towards the zone, no carrier). With B sampled twice as finely as the plan samples
    it, the two agree to the zone sum's own float32 error everywhere (measured 9.2e-6 and
    1.0e-5): the re-modulation is exact. At the plan's sampling they agree within the zone's
    own band (the light that reaches the zone, not its soft rim) to 8.0e-6 in the middle,
    3.9e-4 off it; over the whole field 3.3e-4 and 1.3e-2. What is left is the samples' own
    aliasing: B's spectrum reaches past the band they are sampled for (the windows' soft rims;
    9e-6 of its energy lies beyond, measured on a twice finer grid)."""
    h = carrier_plate(emitters, ZONE, LAMBDA, finer)
    x0, y0, x1, y1 = window(h)
    fine = 0.9 * physical_pitch(h)
    cx, cy = x0 + where * (x1 - x0), y0 + where * (y1 - y0)
    f = physical_field(h, pitch=fine, region=(cx - 200 * fine, cy - 200 * fine,
                                              cx + 200 * fine, cy + 200 * fine))
    assert f.shape == (401, 401) and f.wavelength == LAMBDA and f.pitch == (fine, fine)
    centre = f.pose[:2, 3]
    xs, ys = (centre[a] + (np.arange(401) - 200) * fine for a in (0, 1))
    want = object_wave(emitters, ZONE, LAMBDA, xs, ys)[0]
    got = np.asarray(f.samples, np.complex128)
    err, err_band = rel_err(got, want), rel_err(zone_band_only(got, xs, ys),
                                                 zone_band_only(want, xs, ys))
    print(f"B {finer}x the plan's sampling, at {where}: whole field {err:.2e}, within the "
          f"zone's band {err_band:.2e}")
    assert err <= whole and err_band <= in_band, (err, err_band)


def test_the_physical_field_is_sampled_as_its_band_needs(emitters):
    """At its default pitch (physical_pitch over the region) O's spectrum stays inside the
    grid's Nyquist band: its energy in the outer tenth of either axis's band is at most
    1e-8 of the whole (the middle 1.6 mm of the window; measured below)."""
    h = carrier_plate(emitters, ZONE, LAMBDA)
    x0, y0, x1, y1 = window(h)
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    f = physical_field(h, region=(cx - 8e-4, cy - 8e-4, cx + 8e-4, cy + 8e-4))
    s = np.abs(np.fft.fft2(f.samples * np.kaiser(f.shape[0], 14)[:, None]
                           * np.kaiser(f.shape[1], 14)[None])) ** 2
    fy, fx = (np.abs(np.fft.fftfreq(n)) for n in f.shape)
    outer = (fx[None] > 0.45) | (fy[:, None] > 0.45)
    share = s[outer].sum() / s.sum()
    print(f"{f.shape} at {f.pitch[0]:.3g} m: {share:.2e} of the energy in the outer tenth")
    assert share <= 1e-8, share


def test_reconstruct_gives_a_complex_plates_object_wave(emitters):
    """A carrier plate's: the physical field on physical_field's default grid; a plate
    without a carrier: its samples."""
    h = carrier_plate(emitters, ZONE, LAMBDA)
    assert np.array_equal(reconstruct(h), physical_field(h).samples)
    full = Hologram(object_wave=h.object_wave, encoding="complex", wavelengths=h.wavelengths,
                    pitch=h.pitch)
    assert np.array_equal(reconstruct(full), h.object_wave[0])
    f = physical_field(full, region=(-1e-3, -2e-3, 1e-3, 2e-3))
    rows = np.abs((np.arange(full.shape[0]) - (full.shape[0] - 1) / 2) * h.pitch) <= 2e-3
    cols = np.abs((np.arange(full.shape[1]) - (full.shape[1] - 1) / 2) * h.pitch) <= 1e-3
    assert np.array_equal(f.samples, h.object_wave[0][np.ix_(rows, cols)])


@pytest.mark.parametrize("kw, problem", [
    ({"pitch": 0}, r"pitch must be in"),
    ({"region": (0.01, 0, 0, 0.01)}, r"region must be \(x0, y0, x1, y1\) \[m\] with x0 <= x1"),
    ({"region": (0, 0, 1, 1), "pitch": 1e-7}, (r"the physical field's 10000001x10000001 "
                                                r"samples at 1e-07 m \(ask a region or a "
                                                r"coarser pitch\) needs")),
    ({"channel": 3}, r"channel must be"),
])
def test_bad_physical_fields_are_refused_naming_the_field(emitters, kw, problem):
    h = carrier_plate(emitters, ZONE, LAMBDA)
    with pytest.raises(InputError, match=problem):
        physical_field(h, **kw)


def test_a_zone_sum_that_comes_back_not_finite_records_nothing(monkeypatch):
    """A device whose zone sum comes back with NaN (its arithmetic failed) stops the
    recording with the rows where it happened; no plate is returned, so none is written."""
    from holo_core.plate import zone_sum

    summed = zone_sum.ZoneSum.on_device

    def failed(self, row0, *args):
        out = summed(self, row0, *args)
        if row0 >= 256:
            out.fill(np.complex64(np.nan))
        return out

    monkeypatch.setattr(zone_sum.ZoneSum, "on_device", failed)
    kw = {"plate": PLATE, "camera": camera("centre", SCALE), "zone_margin": 0.025}
    with pytest.raises(RuntimeError, match="non-finite samples in rows 256-"):
        record_looks(meshes(), looks=2, seed=4, **kw)
