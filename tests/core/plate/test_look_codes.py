"""Each look's emitter phases (holo_core.plate.look_codes): the codes of n looks, and the
classes of emitters that coded looks shift alike, from which every look's phases follow
exactly (one zone sum serves the looks)."""

import numpy as np
import pytest

from holo_core.plate.look_codes import code_classes, emitter_phases, look_code, look_seed
from holo_core.validate import InputError


class _Emitters:
    """The fields of a plate's emitters that their phases read: lattice cells (i, j), keys."""

    def __init__(self, cells, keys):
        self.cell, self.key, self.count, self.ids = cells, keys, None, None

    def __len__(self):
        return len(self.cell)


def test_codes_of_square_counts_and_the_checkerboard_pair():
    """m² looks are the m² shifts of one seed; two are the checkerboard pair (looks 0 and 3 of
    m = 2); other counts are independent seeds, one a look."""
    assert [look_code(k, 4) for k in range(4)] == [(0, 2), (1, 2), (2, 2), (3, 2)]
    assert [look_code(k, 9) for k in (0, 4, 8)] == [(0, 3), (4, 3), (8, 3)]
    assert [look_code(k, 2) for k in range(2)] == [(0, 2), (3, 2)]
    assert look_code(0, 1) is None and look_code(2, 3) is None
    codes = (None, None, None)
    assert [look_seed(5, codes, k) for k in range(3)] == [5, 6, 7]
    assert [look_seed(5, ((0, 2), (3, 2)), k) for k in range(2)] == [5, 5]
    with pytest.raises(InputError, match="look must be an integer in \\[0, 1\\]"):
        look_code(2, 2)


@pytest.mark.parametrize("looks", [2, 4, 9])
def test_every_coded_look_is_the_first_times_its_class_factor(looks):
    """exp(iφ_l) = exp(iφ_0)·mixing[l, class] for every emitter and look, to float64
    rounding; the shift between looks is 2π/m times k1·Δi + k2·Δj on the lattice."""
    rng = np.random.default_rng(4)
    em = _Emitters(rng.integers(-50, 50, (500, 2)), rng.integers(0, 2**62, 500, dtype=np.int64))
    codes = [look_code(k, looks) for k in range(looks)]
    classes, mixing = code_classes(em, codes)
    m = codes[0][1]
    assert mixing.shape[0] == looks and classes.max() < mixing.shape[1] <= m * m
    first = np.exp(1j * emitter_phases(em, 11, codes[0]))
    for k, code in enumerate(codes):
        got = np.exp(1j * emitter_phases(em, 11, code))
        np.testing.assert_allclose(got, first * mixing[k, classes], atol=1e-12)
    assert code_classes(em, [None, None]) == (None, None)
