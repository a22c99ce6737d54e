"""The emitters' phases of each look of a plate: coded looks of one seed (:func:`look_code`),
whose mean cancels the cross terms between neighbouring emitters, or seeds of their own; and
the classes of emitters that coded looks shift alike, so that one zone sum serves every look.
"""

from __future__ import annotations

import math

import numpy as np

from .. import validate
from .emitters import random_phases


def code_classes(em, codes) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(each emitter's class, the looks' factors (looks, classes)) where the looks are coded
    looks of one seed (:func:`emitter_phases`): look l's phases are look 0's plus 2π·s_l/m, s_l
    taking m values over the lattice cells, so the emitters fall in the classes of equal
    shifts and each look is the classes' sums times exp(2πi·(s_l − s_0)/m)
    (:class:`ZoneEmitters`). (None, None) for a single look or independent ones."""
    if len(codes) < 2 or any(c is None for c in codes) or len({c[1] for c in codes}) > 1:
        return None, None
    m = codes[0][1]
    # an emitter's shifts follow from its cell (i, j) mod m: the distinct rows are found among
    # the m² residues' (np.unique(axis=0) over every emitter's row took 0.4 s of a set's
    # part of 450k emitters)
    residue = (em.cell[:, 1] % m) * m + em.cell[:, 0] % m
    _, first, where = np.unique(residue, return_index=True, return_inverse=True)
    shifts = np.stack([code_steps(em, code)[first] % m for code in codes], 1)
    kinds, inverse = np.unique(shifts, axis=0, return_inverse=True)
    classes = inverse.reshape(-1)[where.reshape(-1)]
    mixing = np.exp(2j * np.pi * (kinds - kinds[:, :1]).T / m)
    return classes.reshape(-1).astype(np.int32), mixing


def look_seed(seed: int, codes, look: int) -> int:
    """The seed of look ``look``'s phases: the plate's, shifted by the look's code where it
    has one, else seed + look (independent looks)."""
    return seed + (0 if codes[look] else look)


def emitter_phases(em, seed: int, code, smooth: bool = False) -> np.ndarray:
    """The emitters' random phases [rad] of ``seed`` (0 where ``smooth``), shifted by ``code``
    (k, m): 2π·(k1·i + k2·j)/m on the lattice cells (i, j) they lie in (k = k1·m + k2;
    :func:`~holo_core.plate.looks.record_plate`).
    Each emitter's is drawn from its own key (:func:`~holo_core.plate.emitters.random_phases`),
    so emitters gained or lost near a silhouette leave the others' phases, and a set several
    plates share sends each pupil the same wave from every plate."""
    if smooth:
        phases = np.zeros(em.count or len(em))
        if em.ids is not None:
            phases = phases[em.ids]
    elif em.key is not None:
        phases = random_phases(em.key, seed)
    else:  # emitters made without keys: drawn in their order
        phases = np.random.default_rng(seed).uniform(0, 2 * np.pi, em.count or len(em))
        if em.ids is not None:  # drawn from a set several plates share: the set's phases
            phases = phases[em.ids]
    if code is not None:
        phases = phases + 2 * np.pi * code_steps(em, code) / code[1]
    return phases


def in_phase_at_zone(reach, wavelength: float, smooth: bool):
    """−k·|p − Z| [rad] (reduced to ±π in float64) of emitters ``reach`` = |p − Z| [m] away
    from the zone's centre: their light reaches it in one phase; 0 unless ``smooth``."""
    if not smooth:
        return np.zeros(np.shape(reach))
    return (
        np.remainder(-2 * np.pi / wavelength * np.asarray(reach, np.float64) + np.pi, 2 * np.pi)
        - np.pi
    )


def code_steps(em, code) -> np.ndarray:
    """k1·i + k2·j (int) for the emitters' lattice cells (i, j) and code (k1·m + k2, m): their
    phases are shifted by 2π/m times it."""
    k1, k2 = divmod(code[0], code[1])
    return k1 * em.cell[:, 1] + k2 * em.cell[:, 0]


def look_code(k: int, n: int):
    """``code`` of look ``k`` of ``n`` looks of one plate
    (:func:`~holo_core.plate.looks.record_plate`, one seed for all): n = m² gives the m² looks whose mean has no cross terms between emitters of
    neighbouring lattice cells, n = 2 the checkerboard pair (looks 0 and 3 of m = 2), whose
    mean has none between the four nearest cells (on the plate scene: 28.0–28.5 dB against
    29.3–30.0 for four and 25.6–26.1 for one). Other n: None (independent random phases, one
    seed per look)."""
    n = validate.integer("looks", n, 1)
    k = validate.integer("look", k, 0, n - 1)
    m = math.isqrt(n)
    if n == 2:
        return (3 * k, 2)
    return (k, m) if m > 1 and m * m == n else None
