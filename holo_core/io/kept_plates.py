"""A plate's holograms held in memory from one job to the next, each named by its file's
identity so that a file written again since, by this process or another, is read again."""

from __future__ import annotations

import logging
from pathlib import Path

from ..scene.hologram import Hologram
from .hologram import HologramFileError
from .plate_paths import file_identity as _identity
from .plate_paths import plate_files, read_plate
from .plate_set import MANIFEST, read_plate_set
from .tiled_wave import TiledWave

log = logging.getLogger(__name__)


class KeptPlates:
    """A plate's holograms held in memory from one job to the next (a serving worker's: the
    frames of a shot render from the plate without reading its files again, 1.2 s for the
    shot of ``bench/shot.py`` from the page cache). Each is named by its file's identity
    (path, size, modification time, inode), so a file written again since, by this process
    or another, is read again. Only the latest job's set is held; a tiled store is never
    held (its tiles are read as a view needs them). ``hold=False``: nothing is held."""

    def __init__(self, hold: bool = True):
        self._held: dict = {}
        self._set: tuple = (None, None)  # (its manifest's identity, the PlateSet)
        self._hold = hold

    def read(self, paths, recording: str = "") -> list[Hologram]:
        """The holograms of ``paths``: held where their files are unchanged, else read.
        :class:`HologramFileError` naming the file unless each is the ``recording`` named
        (where one is): a plate replaced by another recording's valid plate (a folder synced
        from another shot, a file copied by hand, a restored backup) is refused, never
        viewed."""
        names = [_identity(p) for p in paths]
        self._held = {k: h for k, h in self._held.items() if k in names}  # freed before reads
        self._set = (None, None)
        holos = [self._held[k] if k in self._held else read_plate(p) for k, p in zip(names, paths)]
        if self._held:
            log.info(
                "the plate's holograms held in memory from the job before: %d of %d not read again",
                len(self._held),
                len(paths),
            )
        for path, h in zip(paths, holos):
            if recording and h.recording != recording:
                held = f"recording {h.recording}" if h.recording else "no named recording"
                raise HologramFileError(
                    f"{plate_files(path)}: holds {held}, not {recording} "
                    f"(this scene's): another recording's plate under "
                    f"this name is never rendered; record the plate again"
                )
        return holos

    def hold(self, paths, holos) -> None:
        """Hold ``holos``, the plates of ``paths`` as their files are now (their identities),
        in place of those held before."""
        if self._hold:
            self._held = {
                k: h
                for k, h in zip(map(_identity, paths), holos)
                if k is not None and not isinstance(h.object_wave, TiledWave)
            }

    def read_set(self, folder):
        """The plate set in ``folder`` (:func:`read_plate_set`: each part's digests checked
        when it is read): held where its manifest is unchanged since, else read (the part it
        held kept with it)."""
        name = _identity(Path(folder) / MANIFEST)
        if name is not None and self._set[0] == name:
            log.info("the plate set held in memory from the job before: not read again")
            return self._set[1]
        self._held = {}  # a plate's holograms are not held beside a set
        plates = read_plate_set(folder)
        if self._hold:
            self._set = (name, plates)
        return plates

    def hold_set(self, folder, plates) -> None:
        """Hold ``plates``, just recorded into ``folder`` (its manifest's identity now)."""
        if self._hold:
            self._set = (_identity(Path(folder) / MANIFEST), plates)

    def clear(self) -> None:
        self._held = {}
        self._set = (None, None)
