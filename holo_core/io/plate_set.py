"""A plate set on disk: one folder, each part's looks as hologram files
(:mod:`holo_core.io.hologram`, each naming its plate's pose and zone), and ``plate_set.json``,
the manifest naming the recording, the parts (size, stretch, frames) and each file with its
size and BLAKE2b digest.

Every file is written through a temporary one and a rename, the manifest last, so a folder
holds either the set before or the set after. Reading checks every part against the
manifest before a sample is used: a part missing, damaged (its bytes not the digest's) or
foreign (a valid hologram of another recording, or of another plate than the manifest's)
is a :class:`~holo_core.io.hologram.HologramFileError` naming the part and its file; never
read as zeros.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np

from ..scene.plate import Plate
from ..scene.plate_set import PathPart, PlateSet
from ..validate import InputError
from . import jsonfile
from .hologram import HologramFileError, metadata, read_hologram, write_hologram
from .image import check_writable, write_atomic

MANIFEST = "plate_set.json"
KIND = "holo plate set"
VERSION = 1          # the manifest's format
MANIFEST_CHARS = 1 << 20  # a manifest names files and numbers: 1 Mi characters is far beyond


def part_file(k: int, look: int) -> str:
    return f"part{k:03d}.look{look}.exr"


def write_plate_set(folder, plates: PlateSet) -> Path:
    """Write ``plates`` into ``folder`` (made if absent): each part's looks, then the manifest
    naming them with their digests. Returns the manifest's path."""
    if not isinstance(plates, PlateSet):
        raise InputError(f"plates must be a PlateSet; got {type(plates).__name__}")
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"{folder}: a plate set is a folder; a file is in the way")
    folder.mkdir(parents=True, exist_ok=True)
    check_writable(folder / MANIFEST)
    parts = []
    for k, (part, looks) in enumerate(zip(plates.parts, plates.looks)):
        files = []
        for look, h in enumerate(looks):
            path = write_hologram(folder / part_file(k, look), h)
            files.append({"name": path.name, "bytes": path.stat().st_size,
                          "blake2b": file_digest(path), "metadata": metadata_digest(h)})
        p = part.plate
        parts.append({"plate_to_world": np.asarray(p.matrix_world).tolist(),
                      "width_m": p.width, "height_m": p.height,
                      "stretch_m": list(part.stretch), "frames": list(part.frames),
                      "files": files})
    manifest = {"kind": KIND, "version": VERSION, "recording": plates.recording,
                "seed": plates.seed, "looks": len(plates.looks[0]), "parts": parts}
    return write_atomic(folder / MANIFEST, json.dumps(manifest, indent=1).encode())


def file_digest(path) -> str:
    """The BLAKE2b digest (hex, 16 bytes) of the file's bytes, read in blocks."""
    h = hashlib.blake2b(digest_size=16)
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 22), b""):
            h.update(block)
    return h.hexdigest()


def metadata_digest(h) -> str:
    """The BLAKE2b digest (hex, 16 bytes) of a hologram's description (its file metadata):
    what tells a damaged part (its samples changed) from a foreign one (another hologram)."""
    text = json.dumps(metadata(h), sort_keys=True).encode()
    return hashlib.blake2b(text, digest_size=16).hexdigest()


def read_plate_set(folder) -> PlateSet:
    """The plate set in ``folder`` (:func:`write_plate_set`), every part checked against the
    manifest (module docstring)."""
    folder = Path(folder)
    name = folder / MANIFEST
    if not folder.is_dir():
        raise HologramFileError(f"{folder}: not a plate set's folder (no such folder)")
    if not name.exists():
        raise HologramFileError(f"{folder}: not a plate set (no {MANIFEST})")
    m = jsonfile.load(name, error=HologramFileError, max_chars=MANIFEST_CHARS)
    field = _Fields(name)
    field.value(m, dict, "an object", "(the manifest)")
    if m.get("kind") != KIND:
        field.fail("kind", f"{KIND!r}")
    if m.get("version") != VERSION:
        field.fail("version", f"{VERSION} (this reader's; a newer Holo writes newer ones)")
    recording = field.check(m, "recording", str, "the recording's digest (text)")
    seed = field.check(m, "seed", int, "an integer >= 0")
    looks = field.check(m, "looks", int, "an integer >= 1")
    listed = field.check(m, "parts", list, "a non-empty list of parts")
    if not listed or looks < 1:
        field.fail("parts" if not listed else "looks", "at least one")
    parts, held = [], []
    for k, entry in enumerate(listed):
        at = f"parts[{k}]."
        field.value(entry, dict, "an object", f"parts[{k}]")
        files = field.check(entry, "files", list, f"{looks} files", at)
        if len(files) != looks:
            field.fail(f"{at}files", f"{looks} files (one a look); it lists {len(files)}")
        try:
            pose = np.asarray(entry.get("plate_to_world"), np.float64)
            stretch = tuple(entry.get("stretch_m"))
            frames = tuple(entry.get("frames"))
        except (TypeError, ValueError):
            field.fail(f"{at}plate_to_world", "a 4x4 pose, its stretch_m and frames")
        part_looks = tuple(_part_look(folder, k, look, f, field, at)
                           for look, f in enumerate(files))
        first = part_looks[0]
        if not np.allclose(np.asarray(first.plate), pose, atol=1e-12) or first.zone is None:
            raise HologramFileError(f"{folder}: part {k} ({files[0]['name']}) is foreign: it "
                                    f"holds a plate at another pose or without a zone than "
                                    f"the manifest's part {k}")
        try:
            plate = Plate(matrix_world=pose, width=entry.get("width_m"),
                          height=entry.get("height_m"), zone=first.zone)
            parts.append(PathPart(plate=plate, stretch=stretch, frames=frames))
        except InputError as e:
            raise HologramFileError(f"{name}: {at[:-1]}: {e}") from None
        for look, h in enumerate(part_looks[1:], 1):
            if not np.array_equal(np.asarray(h.plate), np.asarray(first.plate)) or \
                    h.zone.centre != first.zone.centre or h.shape != first.shape:
                raise HologramFileError(f"{folder}: part {k} ({files[look]['name']}) is "
                                        f"foreign: its plate is not its part's")
        held.append(part_looks)
    try:
        return PlateSet(parts=tuple(parts), looks=tuple(held), seed=seed, recording=recording)
    except InputError as e:
        raise HologramFileError(f"{name}: {e}") from None


def _part_look(folder: Path, k: int, look: int, entry, field, at):
    """Part ``k``'s look ``look`` as its manifest ``entry`` names it, refused by name when
    missing, damaged or foreign."""
    where = f"{at}files[{look}]."
    field.value(entry, dict, "an object", where[:-1])
    name = field.check(entry, "name", str, "a file name", where)
    size = field.check(entry, "bytes", int, "the file's size", where)
    digest = field.check(entry, "blake2b", str, "the file's digest", where)
    described = field.check(entry, "metadata", str, "its metadata's digest", where)
    if Path(name).name != name or name in ("", ".", ".."):
        field.fail(f"{where}name", "a file name inside the set's folder")
    path = folder / name
    if path.is_symlink() or (path.exists() and not path.is_file()):
        raise HologramFileError(f"{folder}: part {k} ({name}) is not a regular file")
    if not path.exists():
        raise HologramFileError(f"{folder}: part {k} ({name}) is missing: the set is "
                                f"incomplete; record it again")
    if path.stat().st_size != size or file_digest(path) != digest:
        try:
            h = read_hologram(path)
        except HologramFileError:
            h = None
        if h is not None and metadata_digest(h) != described:
            raise HologramFileError(f"{folder}: part {k} ({name}) is foreign: a hologram, but "
                                    f"not the one this set recorded (its description differs "
                                    f"from the manifest's); record the set again")
        raise HologramFileError(f"{folder}: part {k} ({name}) is damaged: its bytes do not "
                                f"match the manifest's digest; record the set again")
    return read_hologram(path)


class _Fields:
    """The manifest's fields checked by name."""

    def __init__(self, path: Path):
        self.path = path

    def fail(self, key, allowed):
        raise HologramFileError(f"{self.path}: manifest field {key} must be {allowed}")

    def value(self, value, kind, allowed, name):
        if not isinstance(value, kind) or (kind is int and isinstance(value, bool)):
            self.fail(name, allowed)
        return value

    def check(self, obj, key, kind, allowed, prefix=""):
        return self.value(obj.get(key), kind, allowed, f"{prefix}{key}")
