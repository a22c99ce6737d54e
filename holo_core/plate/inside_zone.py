"""Whether a camera's pupil lies inside the viewing zone a plate serves, and where it does not,
how far and which way it reaches beyond, in words a viewport's overlay and a message show.
"""

from __future__ import annotations

import numpy as np

from ..scene.camera import Camera
from ..scene.hologram import Hologram
from ..validate import InputError
from .view import unseen_light
from .window import camera_in_plate

INSIDE = 1e-9  # [m] a pupil reaching less than this beyond the zone lies inside it


def zone_sentence(h: Hologram, camera: Camera) -> str | None:
    """Why ``camera``'s pupil lies outside ``h``'s viewing zone (a sentence), or None inside
    it (or where ``h`` has no zone and its light reaches the camera)."""
    try:
        rotation, position = camera_in_plate(h, camera)
    except InputError as e:
        return str(e)
    if h.zone is None:
        return unseen_light(h, rotation, position)
    pupil = camera.aperture_diameter or 0.0
    if h.zone.distance_outside(position, pupil / 2) <= INSIDE:
        return None
    return (
        f"the camera's pupil lies outside the plate's viewing zone: "
        f"{beyond_words(h.zone, position, pupil)} ({h.zone.describe()}); move the camera "
        f"inside it or record the plate for a zone that holds it"
    )


def beyond_words(zone, position, pupil: float) -> str:
    """How far and which way a pupil of diameter ``pupil`` [m] at ``position`` (3,) [m] (the
    plate's frame) reaches beyond ``zone``, in words."""
    d = np.asarray(position, np.float64) - zone.centre
    over = np.abs(d) - zone.half_extents + np.array([pupil / 2, pupil / 2, 0.0])
    sides = (
        ("+x (right)", "-x (left)"),
        ("+y (up)", "-y (down)"),
        ("farther from the plate", "nearer the plate"),
    )
    ways = [
        f"{_length(over[i])} {'past its ' if i < 2 else ''}"
        f"{sides[i][0] if d[i] > 0 else sides[i][1]}{' side' if i < 2 else ''}"
        for i in range(3)
        if over[i] > INSIDE
    ]
    total = zone.distance_outside(position, pupil / 2)
    return f"it reaches {_length(total)} beyond the zone, {' and '.join(ways)}"


def _length(metres: float) -> str:
    return f"{metres * 1e3:.3g} mm" if metres < 0.1 else f"{metres:.3g} m"
