"""The images leave the device folded to the camera's pixels (optics/imaging.py fold_look):
each pixel's mean |A|² and the depth pair's mean u1·conj(u2) over its s×s fine pixels,
against float64 NumPy on the same fine images."""

import numpy as np
import pytest
from accuracy import rel_err

from holo_core.opencl import get_runtime
from holo_core.optics.imaging import fold_look

FOLD = 1e-6  # float32 sums of s² terms against float64: measured 3e-8


@pytest.mark.parametrize("s", [1, 2, 3])
def test_the_pixels_are_the_means_of_their_fine_pixels(rng, s):
    rt = get_runtime()
    rows, cols = 7, 11
    fine = {c: (rng.normal(size=(rows * s, cols * s)) + 1j * rng.normal(size=(rows * s, cols * s)))
            for c in range(4)}
    folded = fold_look(rt, {c: rt.to_device(a, np.complex64) for c, a in fine.items()},
                       same=[0, 2], partner=3, supersample=s, keep_fine=True)

    def means(a):
        return a.reshape(rows, s, cols, s).mean((1, 3))

    for c, a in fine.items():
        assert folded.power[c].shape == (rows, cols)
        assert rel_err(folded.power[c], means(np.abs(a) ** 2)) < FOLD, c
        assert rel_err(folded.fine[c], a) < FOLD, c
    assert rel_err(folded.cross, means((fine[0] + fine[2]) * np.conj(fine[3]))) < FOLD
    alone = fold_look(rt, {0: rt.to_device(fine[0], np.complex64)}, same=[0], partner=None,
                      supersample=s)
    assert alone.cross is None and alone.fine is None
    assert np.array_equal(alone.power[0], folded.power[0])
