"""A plate stored against its zone's carrier (holo_core.plate.carrier): the modulation is exact
and invertible, and the physical field re-modulated from the samples (carrier.physical_field: a
Kaiser-windowed sinc and the exact carrier) equals the float64 direct sum of the same emitters
(tests/zone_reference.py) on fine grids, whole and within the zone's own band, sampled as its
band needs; bad fields are refused by name."""

import math

import numpy as np
import pytest
from accuracy import PHYSICAL_FIELD, rel_err
from zone_reference import carrier_plate, object_wave

from holo_core.plate.carrier import demodulate, modulate, physical_field, physical_pitch, window
from holo_core.scene.plate import ViewingZone
from holo_core.validate import InputError


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
    want = complex(b[1, 39, 49]) * complex(
        np.exp(-1j * np.remainder(2 * np.pi / 7e-6 * r, 2 * np.pi))
    )
    assert abs(o[1, 39, 49] - want) < 1e-5 * abs(want)


ZONE = ViewingZone(centre=(0.01, -0.005, 0.3), half_extents=(0.03, 0.02, 0.01))
LAMBDA = 5e-6


def zone_band_only(o, xs, ys):
    """The spectrum of O's light towards the zone itself (not its soft rim): O demodulated by
    the carrier, Kaiser-windowed (β = 14), kept where both direction cosines lie within the
    zone's own band, the largest turn from the line to its centre to a line to a corner of its
    box, over the region's corners (this file's own, not the planner's)."""
    c, e = np.asarray(ZONE.centre), np.asarray(ZONE.half_extents)
    corners = c + e * np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    unit = lambda v: v / np.linalg.norm(v, axis=-1, keepdims=True)  # noqa: E731
    points = np.array([[x, y, 0.0] for x in xs[[0, -1]] for y in ys[[0, -1]]])
    turn = np.abs(unit(corners[None] - points[:, None]) - unit(c - points)[:, None])
    bx, by = turn[..., 0].max(), turn[..., 1].max()
    r = np.sqrt((xs[None] - c[0]) ** 2 + (ys[:, None] - c[1]) ** 2 + c[2] ** 2)
    b = (
        o
        * np.exp(2j * np.pi / LAMBDA * r)
        * np.kaiser(len(ys), 14)[:, None]
        * np.kaiser(len(xs), 14)[None]
    )
    fx = np.fft.fftfreq(len(xs), xs[1] - xs[0]) * LAMBDA
    fy = np.fft.fftfreq(len(ys), ys[1] - ys[0]) * LAMBDA
    return np.fft.fft2(b) * ((np.abs(fx)[None] <= bx) & (np.abs(fy)[:, None] <= by))


@pytest.mark.parametrize(
    "finer, where, whole, in_band",
    [
        (2, 0.5, PHYSICAL_FIELD, PHYSICAL_FIELD),
        (2, 0.3, PHYSICAL_FIELD, PHYSICAL_FIELD),
        (1, 0.5, 1e-3, PHYSICAL_FIELD),
        (1, 0.3, 3e-2, 1e-3),
    ],
)
def test_the_physical_field_equals_the_direct_sum_of_the_emitters(
    emitters, finer, where, whole, in_band
):
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
    f = physical_field(
        h, pitch=fine, region=(cx - 200 * fine, cy - 200 * fine, cx + 200 * fine, cy + 200 * fine)
    )
    assert f.shape == (401, 401) and f.wavelength == LAMBDA and f.pitch == (fine, fine)
    centre = f.pose[:2, 3]
    xs, ys = (centre[a] + (np.arange(401) - 200) * fine for a in (0, 1))
    want = object_wave(emitters, ZONE, LAMBDA, xs, ys)[0]
    got = np.asarray(f.samples, np.complex128)
    err, err_band = (
        rel_err(got, want),
        rel_err(zone_band_only(got, xs, ys), zone_band_only(want, xs, ys)),
    )
    print(
        f"B {finer}x the plan's sampling, at {where}: whole field {err:.2e}, within the "
        f"zone's band {err_band:.2e}"
    )
    assert err <= whole and err_band <= in_band, (err, err_band)


def test_the_physical_field_is_sampled_as_its_band_needs(emitters):
    """At its default pitch (physical_pitch over the region) O's spectrum stays inside the
    grid's Nyquist band: its energy in the outer tenth of either axis's band is at most
    1e-8 of the whole (the middle 1.6 mm of the window; measured below)."""
    h = carrier_plate(emitters, ZONE, LAMBDA)
    x0, y0, x1, y1 = window(h)
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    f = physical_field(h, region=(cx - 8e-4, cy - 8e-4, cx + 8e-4, cy + 8e-4))
    s = (
        np.abs(
            np.fft.fft2(
                f.samples * np.kaiser(f.shape[0], 14)[:, None] * np.kaiser(f.shape[1], 14)[None]
            )
        )
        ** 2
    )
    fy, fx = (np.abs(np.fft.fftfreq(n)) for n in f.shape)
    outer = (fx[None] > 0.45) | (fy[:, None] > 0.45)
    share = s[outer].sum() / s.sum()
    print(f"{f.shape} at {f.pitch[0]:.3g} m: {share:.2e} of the energy in the outer tenth")
    assert share <= 1e-8, share


@pytest.mark.parametrize(
    "kw, problem",
    [
        ({"pitch": 0}, r"pitch must be in"),
        ({"region": (0.01, 0, 0, 0.01)}, r"region must be \(x0, y0, x1, y1\) \[m\] with x0 <= x1"),
        (
            {"region": (0, 0, 1, 1), "pitch": 1e-7},
            (
                r"the physical field's 10000001x10000001 "
                r"samples at 1e-07 m \(ask a region or a "
                r"coarser pitch\) needs"
            ),
        ),
        ({"channel": 3}, r"channel must be"),
    ],
)
def test_bad_physical_fields_are_refused_naming_the_field(emitters, kw, problem):
    h = carrier_plate(emitters, ZONE, LAMBDA)
    with pytest.raises(InputError, match=problem):
        physical_field(h, **kw)
