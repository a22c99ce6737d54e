"""The plans of a held plate's views, made once and reused while a camera moves
(:class:`ViewPlans`)."""

from __future__ import annotations

from .view import render_view


class ViewPlans:
    """What a moving camera's views of one plate share: planned at the first view, reused
    by the next."""

    def __init__(self):
        self._held = {}

    def render(self, looks, camera, **options):
        """:func:`holo_core.render_view` of ``looks`` through ``camera`` with ``options``."""
        return render_view(looks, camera, **options)

    def clear(self) -> None:
        self._held.clear()
