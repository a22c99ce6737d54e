"""A plate set: the parts of one plate along a camera path, each a plate facing its stretch of
the path with that stretch's viewing zone, recorded together from the same emitters
(:mod:`holo_core.plate.parts`), viewed from the part whose zone holds the pupil.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import validate
from ..validate import InputError, shown
from .hologram import Hologram
from .plate import Plate


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class PathPart:
    """One part of a set along a path.

    plate : Plate, its ``zone`` the part's viewing zone (the plate's frame)
    stretch : (s0, s1) [m] of path length, from the first frame, whose pupils its zone holds
    frames : the indices of the frames (cameras) whose pupils lie wholly inside its zone
    """

    plate: Plate
    stretch: tuple
    frames: tuple

    def __post_init__(self):
        if not isinstance(self.plate, Plate) or self.plate.zone is None:
            raise InputError("a path part needs a Plate with its viewing zone")
        s0, s1 = (validate.finite("part stretch", s, "m") for s in self.stretch)
        if not s1 >= s0:
            raise InputError(
                f"a part's stretch must run forwards (s1 >= s0) [m]; got ({shown(s0)}, {shown(s1)})"
            )
        object.__setattr__(self, "stretch", (s0, s1))
        object.__setattr__(self, "frames", tuple(int(f) for f in self.frames))

    def reach(self, position, pupil: float) -> float:
        """How far [m] a pupil of diameter ``pupil`` [m] at world ``position`` (3,) reaches
        beyond this part's zone (0: wholly inside)."""
        return reach_beyond(self.plate, position, pupil)


def reach_beyond(plate: Plate, position, pupil: float) -> float:
    """How far [m] a pupil of diameter ``pupil`` [m] at world ``position`` (3,) reaches beyond
    ``plate``'s zone (0: wholly inside)."""
    local = plate.to_plate(np.asarray(position, np.float64)[None])[0]
    return plate.zone.distance_outside(local, pupil / 2)


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class PlateSet:
    """The parts of a plate along a path, recorded.

    parts : tuple of PathPart
    looks : per part, its looks (a tuple of Hologram, the same count for every part), or None
        where ``load`` reads them when a view needs them (a set on disk: one part held at a
        time, so the memory stays that of a part however long the path)
    seed : the emitters' random phases' seed, shared by every part
    recording : the digest (hex) of what it was recorded from: the meshes, the parts, the seed
        and the looks (a set's files name it; a part of another recording is refused)
    load : callable(k) -> tuple of Hologram, part k's looks, where ``looks`` holds None
    """

    parts: tuple
    looks: tuple
    seed: int = 0
    recording: str = ""
    load: object = None
    _held: dict = field(default_factory=dict)

    def __post_init__(self):
        parts = tuple(self.parts)
        looks = tuple(None if part is None else tuple(part) for part in self.looks)
        if not parts or not all(isinstance(p, PathPart) for p in parts):
            raise InputError("a plate set's parts must be a non-empty sequence of PathPart")
        if len(looks) != len(parts):
            raise InputError(
                f"a plate set needs the looks of each of its {len(parts)} parts; got {len(looks)}"
            )
        counts = {len(held) for held in looks if held is not None}
        for k, held in enumerate(looks):
            if held is None:
                if not callable(self.load):
                    raise InputError(
                        f"part {k}'s looks are None: the set needs load, a "
                        f"callable reading a part's looks"
                    )
                continue
            if not held or not all(isinstance(h, Hologram) for h in held):
                raise InputError(f"part {k}'s looks must be a non-empty sequence of Hologram")
        if len(counts) > 1:
            raise InputError(
                f"the parts hold {sorted(counts)} looks: the parts of a set share their looks"
            )
        object.__setattr__(self, "parts", parts)
        object.__setattr__(self, "looks", looks)
        object.__setattr__(self, "seed", validate.seed(self.seed))

    def __len__(self) -> int:
        return len(self.parts)

    def part_looks(self, k: int) -> tuple:
        """Part ``k``'s looks (tuple of Hologram): held, or read by ``load``, the last part
        read kept until another is asked for."""
        k = validate.index("part", k, len(self.parts))
        if self.looks[k] is not None:
            return self.looks[k]
        if k not in self._held:
            self._held.clear()  # one part in memory at a time
            self._held[k] = tuple(self.load(k))
        return self._held[k]
