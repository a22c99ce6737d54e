"""Helpers of the tiled stores' tests: a recording cancelled after some tiles, and the tiles
written once the tasks already running have ended."""

import time

import numpy as np

from holo_core import jobs
from holo_core.io.tiled_wave import tiles_done


def cancel_after(n):
    """A progress callback that cancels the recording at its ``n``-th call (``n`` tiles done)."""
    calls = []

    def progress(fraction):
        calls.append(fraction)
        if len(calls) == n:
            raise jobs.Cancelled()

    return progress


def settled(url) -> np.ndarray:
    """The store's written tiles once they stop changing (the tasks running when a recording
    was cancelled end their write)."""
    done, before = tiles_done(url), None
    while before is None or not np.array_equal(done, before):
        time.sleep(1.0)
        before, done = done, tiles_done(url)
    return done
