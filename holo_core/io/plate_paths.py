"""Where a plate file's samples are: the file, or the tiled store beside it."""

from __future__ import annotations

import stat
from pathlib import Path

from ..scene.hologram import Hologram
from .hologram import HologramFileError, read_hologram, recording_of
from .store import read_store
from .tiled_wave import open_plate


def file_identity(path) -> tuple | None:
    """A plate file's identity: (resolved path, size [bytes], modification time [ns], inode),
    which changes when the file is written again, by this process or another; None where
    ``path`` is no regular file (none there, or a tiled store's folder)."""
    try:
        st = Path(path).stat()
    except OSError:
        return None
    if not stat.S_ISREG(st.st_mode):
        return None
    return (str(Path(path).resolve()), st.st_size, st.st_mtime_ns, st.st_ino)


def store_of(path) -> Path:
    """The tiled store that holds a plate file's samples when its plate is recorded tile by
    tile (:meth:`holo_core.plate.plan.PlatePlan.needs_tiles`): NAME.zarr beside NAME.exr."""
    return Path(path).with_suffix(".zarr")


def read_plate(path) -> Hologram:
    """The hologram file at ``path``, or the complete tiled store beside it
    (:func:`store_of`)."""
    found = plate_files(path)
    return open_plate(str(found)) if found.suffix == ".zarr" else read_hologram(found)


def plate_files(path) -> Path:
    """Where the plate of file ``path`` is: the file, or the tiled store beside it when only
    that was written (:func:`store_of`)."""
    path = Path(path)
    return store_of(path) if not path.is_file() and store_of(path).is_dir() else path


def plate_current(path, recording: str = "") -> bool:
    """Whether the plate file at ``path``, or the tiled store beside it, is there whole (a
    store's every tile written by its recording; a cancelled one resumes) and, given the
    ``recording`` it must be, names that one: another recording's plate under its name (a
    folder synced from another shot, a file copied by hand) is not current, it is recorded
    again. A file whose description cannot be read is left to the reader, which refuses it
    naming the file (a damaged or half-copied plate is said, never silently replaced)."""
    path = Path(path)
    if path.is_file():
        held = recording_of(path)
        return not recording or held is None or held == recording
    if not store_of(path).is_dir():
        return False
    try:
        store = read_store(str(store_of(path)))
    except HologramFileError:  # a StoreError too
        return False
    return (
        not store.bad
        and bool(store.written().all())
        and not store.foreign().any()
        and (not recording or store.info.recording == recording)
    )
