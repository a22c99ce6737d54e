"""Iterations and Supersample at Auto (0): the plan's choice for the scene's plate
(:func:`holo_core.plate.quality.choose`), resolved while the scene is read, with what a
user's lower setting loses said in the render's report and log.

Pure arithmetic on the scene read (the plan runs in Blender's process). Camera mode, and a
plate that cannot be planned (its recording then refuses with its own message), take the
camera hologram's two fine pixels and the coded pair. Auto's looks fit the Memory and Disk
Budgets as the recording checks them; where a budget holds them down, the log says so.
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from holo_core.plate.path import plan_parts
from holo_core.plate.plan import LOOKS, SUPERSAMPLE, plan
from holo_core.plate.quality import QualityChoice, choose
from holo_core.validate import InputError

log = logging.getLogger(__name__)


def plate_choice(data, settings, parts=None) -> QualityChoice | None:
    """The plan's choice for the scene's plate (``data``: the scene read, its plate's zone
    resolved; ``parts``: a set's, whose parts each get the choice and the most any needs is
    kept) and the user's ``settings`` (Iterations and Supersample, 0: Auto), or None where no
    plate can be planned."""
    meshes = list(data.points) + list(data.triangles)
    if not meshes:
        return None
    world = np.concatenate([m.vertices for m in meshes])
    resolution = data.camera.resolution
    looks, supersample = settings.iterations, settings.supersample
    try:
        if parts:
            plans = plan_parts(parts, world).plans
        else:
            plate, zone = data.plate, data.plate.zone
            if zone is None:
                return None
            local = plate.to_plate(world)
            plans = [
                plan(
                    (plate.width, plate.height),
                    [local.min(0), local.max(0)],
                    zone=zone,
                    pixel_angle=zone.pixel or data.camera.pixel_angle(),
                    wavelength=settings.wavelength,
                )
            ]
        budget = (settings.memory_budget, settings.disk_budget)
        choices = [
            choose(
                p,
                resolution=resolution,
                looks=looks,
                supersample=supersample,
                budget=budget,
                plans=plans,
            )
            for p in plans
        ]
    except InputError:
        return None
    return min(choices, key=lambda c: c.planned.psnr)  # the part that needs the most


def resolve(settings, data, parts=None):
    """(``settings`` with Iterations and Supersample resolved, the warnings to report): Auto
    (0) takes the plan's choice for Plate mode, the coded pair and two fine pixels for Camera
    mode; a user's setting that loses against the plan's is said, with the dB it loses."""
    if settings.mode != "PLATE" or data.plate is None:
        return replace(
            settings,
            iterations=settings.iterations or LOOKS,
            supersample=settings.supersample or SUPERSAMPLE,
        ), ()
    choice = plate_choice(data, settings, parts)
    if choice is None:
        return replace(
            settings,
            iterations=settings.iterations or LOOKS,
            supersample=settings.supersample or SUPERSAMPLE,
        ), ()
    log.info("plate '%s': %s", data.plate_name, choice.describe())
    if choice.capped():
        log.info("plate '%s': %s", data.plate_name, choice.capped())
    warning = choice.warning()
    if warning:
        log.warning("plate '%s': %s", data.plate_name, warning)
    return (
        replace(settings, iterations=choice.looks, supersample=choice.supersample),
        (f"plate '{data.plate_name}': {warning}",) if warning else (),
    )
