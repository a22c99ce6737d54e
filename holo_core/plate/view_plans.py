"""What a moving camera's views of one held plate share, planned once and reused
(:class:`ViewPlans`, held by :class:`holo_core.PlateViewer`).

A view's sizes follow its camera: the pupil spectrum's bins (the directions its window's light
arrives from) and the decimation's taps (the pupil's band seen from the window's nearest
point). Sized exactly, every new pose would plan new transforms and build new kernels (their
sizes are compiled in); rounded up to a ladder with slack (:func:`slack_len`), nearby cameras
meet the same few sizes. A larger spectrum holds the same light (its extra bins are beyond
the directions any sample arrives from) and longer taps narrow the decimation's transition at
the same stop band, so the view stays the one the exact sizes give, within the non-uniform
FFT's own accuracy (``tests/core/plate/test_viewer.py`` holds it to 50 dB PSNR).
"""

from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np

from ..propagation import grid
from .to_pupil import CarrierPupil
from .view import render_view

SLACK_STEPS = 8  # ladder sizes per octave: a size is rounded up by at most 1/8 (12.5 %)
HELD_PUPILS = 8  # cameras whose pupil plans (decimation designs, gathers) are kept


def slack_len(n: int, steps: int = SLACK_STEPS) -> int:
    """The smallest fast FFT size (:func:`holo_core.propagation.grid.next_fast_len`) at or
    above ``n`` rounded up to a multiple of 2^⌊log2 n⌋ / ``steps``: at most ``steps`` sizes
    an octave, each at most 1/``steps`` larger than asked.

    Examples
    --------
    >>> from holo_core.plate.view_plans import slack_len
    >>> [slack_len(n) for n in (417, 420, 431, 449)]
    [448, 448, 448, 480]
    """
    step = max(1, 2 ** max(0, math.floor(math.log2(max(n, 1))) - int(math.log2(steps))))
    return grid.next_fast_len(-(-n // step) * step)


def slack_taps(n: int, steps: int = SLACK_STEPS) -> int:
    """An odd tap count at or above ``n`` (odd) on a ladder of ``steps`` counts an octave."""
    step = max(2, 2 ** max(0, math.floor(math.log2(max(n, 1))) - int(math.log2(steps))))
    return (-(-(n - 1) // step) * step) | 1


class ViewPlans:
    """The plans a held plate's views share: sizes rounded up with slack
    (:func:`slack_len`, :func:`slack_taps`) and the pupils' plans of the last
    ``HELD_PUPILS`` cameras.

    Examples
    --------
    >>> from holo_core.plate.view_plans import ViewPlans
    >>> plans = ViewPlans()
    >>> plans.spectrum_len(420), plans.taps_len(161)
    (448, 161)
    """

    def __init__(self):
        self._pupils: OrderedDict = OrderedDict()

    def render(self, looks, camera, **options):
        """:func:`holo_core.render_view` of ``looks`` through ``camera`` with ``options``,
        planned with these plans."""
        return render_view(looks, camera, plans=self, **options)

    @staticmethod
    def spectrum_len(n: int) -> int:
        """The bins of a pupil spectrum's side that needs ``n``."""
        return slack_len(n)

    @staticmethod
    def taps_len(n: int) -> int:
        """The decimation filter's taps where ``n`` (odd) are needed."""
        return slack_taps(n)

    def carrier_pupil(self, rt, h, geometry: dict) -> CarrierPupil:
        """The :class:`~holo_core.plate.to_pupil.CarrierPupil` of ``h``'s samples for one
        camera's ``geometry`` (its keywords): the one made for the same geometry before, with
        its decimation designs and gathers, or a new one."""
        key = (
            id(h),
            h.shape,
            tuple(np.asarray(geometry["position"], np.float64).round(12)),
            tuple(np.asarray(geometry["rotation"], np.float64).ravel().round(12)),
            float(geometry["diameter"]),
            float(geometry["bin"]),
            tuple(geometry["shape"]),
            tuple(geometry["window"]),
            tuple(map(float, geometry["centre"])),
        )
        if key in self._pupils:
            self._pupils.move_to_end(key)
            view = self._pupils[key]
            if view.h is h:
                return view
        view = CarrierPupil(rt, h, taps_len=self.taps_len, **geometry)
        self._pupils[key] = view
        while len(self._pupils) > HELD_PUPILS:
            self._pupils.popitem(last=False)
        return view

    def clear(self) -> None:
        """Let go of every plan held."""
        self._pupils.clear()
