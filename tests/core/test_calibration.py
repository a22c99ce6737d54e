"""The calibration's fits (holo_core.calibration): a stage's fixed cost and rate through a small
and a larger reference."""

import pytest

from holo_core.calibration import _fit


def test_a_stage_whose_time_grows_with_its_work_is_fitted_through_both_references():
    rate, fixed = _fit((1.0, 1.0), (10.0, 5.5), default_rate=9.0)
    assert rate == pytest.approx(0.5) and fixed == pytest.approx(0.5)


def test_a_stage_both_references_spend_on_fixed_cost_takes_the_larger_ones_rate():
    """Files of 2 MB and 40 MB written in 0.06 s and 0.07 s: their difference is noise, and a
    slope through it would write 480 MB in 0.2 s, where the larger's own rate (570 MB/s, the
    upper bound) says 0.9 s."""
    rate, fixed = _fit((2e6, 0.06), (4e7, 0.07), default_rate=1 / 3e8)
    assert rate == pytest.approx(0.07 / 4e7) and fixed == pytest.approx(0.06 - 0.07 / 20)
    assert fixed + 4.8e8 * rate == pytest.approx(0.9, abs=0.05)


def test_a_larger_reference_that_took_no_longer_keeps_the_default_rate():
    rate, fixed = _fit((1.0, 0.5), (10.0, 0.4), default_rate=0.01)
    assert rate == 0.01 and fixed == pytest.approx(0.49)
