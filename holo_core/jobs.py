"""Progress reports and cancellation for long stages.

A stage takes ``progress``: a callable given the fraction done in [0, 1] between units of work.
To cancel, the callable raises :class:`Cancelled`; the stage stops there and writes nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Optional

Progress = Optional[Callable[[float], None]]


class Cancelled(Exception):
    """Raised by a progress callback (or a stage) when the user cancels the run."""


def report(progress: Progress, done: float, total: float) -> None:
    if progress is not None:
        progress(min(1.0, done / total) if total > 0 else 1.0)


def scaled(progress: Progress, start: float, end: float) -> Progress:
    """A callback mapping a sub-stage's [0, 1] onto [start, end] of ``progress``."""
    if progress is None:
        return None
    return lambda f: progress(start + (end - start) * f)
