"""A phase SLM's codes: the nearest code to a wanted phase on the display's line (2π or 3π,
inverted or not) and through a measured table, never outside the bit depth."""

import math

import numpy as np
import pytest

from holo_core.phase.display import Display
from holo_core.phase.levels import Quantiser, quantise, response, shown
from holo_core.phase.slm import PhaseTable
from holo_core.validate import InputError


def display(**kw):
    return Display(name="lab", resolution=(8, 8), pitch=8e-6, **kw)


def wrapped_error(a, b):
    return np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))))


@pytest.mark.parametrize("bits", [1, 8, 10, 16])
@pytest.mark.parametrize("inverted", [False, True])
def test_codes_stay_in_the_bit_depth_and_within_half_a_step(rng, bits, inverted):
    """Any phase (here ±50 rad) becomes a code in 0 .. 2^b − 1 whose phase is within half a
    step 2π/2^b of it, modulo 2π."""
    d = display(bit_depth=bits, inverted=inverted)
    want = rng.uniform(-50, 50, 20000)
    codes = quantise(want, d)
    assert codes.dtype == np.uint16 and codes.min() >= 0 and codes.max() <= 2**bits - 1
    err = wrapped_error(shown(codes, d), want).max()
    assert err <= math.pi / 2**bits * (1 + 1e-9), err


def test_the_line_and_its_inversion():
    d = display(bit_depth=8)
    assert response(d)[[0, 1, 255]] == pytest.approx(
        [0, 2 * math.pi / 256, 255 * 2 * math.pi / 256]
    )
    assert quantise([0.0, 2 * math.pi - 1e-3, math.pi], d).tolist() == [0, 0, 128]
    inv = display(bit_depth=8, inverted=True)
    assert quantise([math.pi / 2], inv).tolist() == [192]  # −192·2π/256 = −3π/2 ≡ π/2


def test_a_3pi_range_keeps_phases_inside_it_unwrapped():
    """On a 3π line a phase of 2.5π is shown as 2.5π (code 213), not 0.5π; one outside the
    range, 3.5π, wraps to 1.5π."""
    d = display(bit_depth=8, phase_range=3 * math.pi)
    c = quantise([2.5 * math.pi, 0.5 * math.pi, 3.5 * math.pi], d)
    assert shown(c, d) == pytest.approx(
        [2.5 * math.pi, 0.5 * math.pi, 1.5 * math.pi], abs=3 * math.pi / 256
    )
    assert shown(c, d)[0] > 2 * math.pi


def test_a_measured_table_is_followed_code_by_code(rng):
    """A non-linear, decreasing table spanning 2.2π: each phase maps to the code whose
    measured phase is nearest it (inside the table's span) or nearest it modulo 2π (outside),
    against a brute-force search over all 256 codes."""
    k = np.arange(256)
    phases = 2.2 * math.pi * (1 - (k / 255) ** 1.3)
    table = PhaseTable(wavelength=520e-9, phases=phases, source="green.csv")
    want = rng.uniform(-3 * math.pi, 3 * math.pi, 4000)
    got = quantise(want, display(bit_depth=8), table)
    inside = (want >= phases.min()) & (want <= phases.max())
    distance = np.where(
        inside[:, None],
        np.abs(phases[None, :] - want[:, None]),
        wrapped_error(phases[None, :], want[:, None]),
    )
    brute = np.argmin(distance, axis=1)
    assert np.allclose(
        distance[np.arange(want.size), got], distance[np.arange(want.size), brute], atol=1e-12
    )
    assert wrapped_error(phases[got], want).max() <= np.diff(phases).__abs__().max()


def test_non_finite_phases_and_codes_beyond_the_depth_are_refused():
    with pytest.raises(InputError, match="finite"):
        Quantiser(response(display()))([0.0, np.nan])
    with pytest.raises(InputError, match=r"codes must be in 0\.\.255"):
        shown(np.array([0, 256]), display())


@pytest.mark.parametrize("phase_range", [2 * np.pi, 3 * np.pi])
@pytest.mark.parametrize("inverted", [False, True])
def test_the_binned_codes_are_the_bisections(rng, phase_range, inverted):
    """Quantiser's bins against bisection in the sorted phases (levels._nearest over the
    codes, and their copies a wave below and above beyond the span): the same code for 2
    million phases over ±5π, the codes' own phases and the midpoints between them (the ties)
    included, on the line and on a measured-like table (a random monotone curve)."""
    from holo_core.phase.levels import _nearest

    curve = response(display(bit_depth=8, phase_range=phase_range, inverted=inverted))
    table = np.sort(rng.uniform(0, phase_range, curve.size))
    for c in (curve, table):
        q = Quantiser(c)
        mids = (np.sort(c)[1:] + np.sort(c)[:-1]) / 2
        t = np.concatenate(
            [
                rng.uniform(-5 * np.pi, 5 * np.pi, 2_000_000),
                c,
                mids,
                np.nextafter(mids, np.inf),
                np.nextafter(mids, -np.inf),
            ]
        )
        inside = (t >= c.min()) & (t <= c.max())
        want = np.empty(t.shape, np.uint16)
        want[inside] = _nearest(t[inside], *q.inside)
        low = c.min()
        want[~inside] = _nearest(low + np.mod(t[~inside] - low, 2 * np.pi), *q.around)
        got = q(t)
        assert np.array_equal(got, want), int(np.sum(got != want))
