"""A plate set on disk: one folder, each part's looks as hologram files
(:mod:`holo_core.io.hologram`, each naming its plate's pose and zone), and ``plate_set.json``,
the manifest naming the recording, the parts (size, stretch, frames) and each file with its
size and BLAKE2b digest.

Every file is written through a temporary one and a rename, the manifest last, so a folder
holds either the set before or the set after. Reading checks every part against the
manifest before a sample of it is used: a part missing, damaged (its bytes not the digest's)
or foreign (a valid hologram of another recording, or of another plate than the manifest's)
is a :class:`~holo_core.io.hologram.HologramFileError` naming the part and its file; never
read as zeros. Opening a set checks what costs nothing (every file there, of the manifest's
size); a part's bytes are checked against their digest when the part is first read, so a
frame viewed from one part reads and hashes that part alone (hashing a 1 m dolly's 22 GiB
took about 40 s a frame on two cores, its view 1-2 s).
"""

from __future__ import annotations

import hashlib
import json
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from pathlib import Path

import numpy as np

from ..scene.plate import Plate, ViewingZone
from ..scene.plate_set import PathPart, PlateSet
from ..validate import InputError
from . import jsonfile
from .hologram import HologramFileError, metadata, read_hologram, write_hologram
from .image import check_writable, write_atomic

MANIFEST = "plate_set.json"
KIND = "holo plate set"
VERSION = 1  # the manifest's format
MANIFEST_CHARS = 1 << 20  # a manifest names files and numbers: 1 Mi characters is far beyond


def part_file(k: int, look: int) -> str:
    return f"part{k:03d}.look{look}.exr"


def write_plate_set(folder, plates: PlateSet) -> Path:
    """Write a plate set into a folder: each part's looks, then the manifest naming them.

    Parameters
    ----------
    folder : str or Path
        Made if absent.
    plates : PlateSet
        The set (:func:`~holo_core.plate.parts.record_set`'s).

    Returns
    -------
    Path
        The manifest's path; it names every part's files with their digests.

    Raises
    ------
    InputError
        Where ``plates`` is not a PlateSet, or ``folder`` is a file or cannot be written.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import Camera, Mesh, look_at, parts_along, record_set
    >>> cameras = [Camera(matrix_world=look_at((x, -0.5, 0.0), (0, 0, 0)), resolution=(32, 24),
    ...                   fstop=8.0, focus_distance=0.5) for x in (-0.01, 0.01)]
    >>> bounds = np.array([[-0.01, -0.01, -0.01], [0.01, 0.01, 0.01]])
    >>> parts = parts_along(cameras, bounds, distance=0.1)
    >>> import tempfile
    >>> from holo_core import read_plate_set, write_plate_set
    >>> triangle = Mesh(vertices=np.array([[-0.01, 0, -0.01], [0.01, 0, -0.01], [0, 0, 0.01]]),
    ...                 triangles=np.array([[0, 1, 2]]), colours=np.ones((3, 3)))
    >>> plates = record_set([triangle], parts, looks=1, depth=False)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     manifest = write_plate_set(folder, plates)
    ...     back = read_plate_set(folder)
    >>> manifest.name, len(back), back.recording == plates.recording
    ('plate_set.json', 1, True)
    """
    if not isinstance(plates, PlateSet):
        raise InputError(f"plates must be a PlateSet; got {type(plates).__name__}")
    folder = set_folder(folder)
    entries = [write_part(folder, k, plates.part_looks(k)) for k in range(len(plates))]
    return write_manifest(
        folder, plates.parts, entries, seed=plates.seed, recording=plates.recording
    )


def set_folder(folder) -> Path:
    """``folder`` made if absent, checked to take the set's files (before any work)."""
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"{folder}: a plate set is a folder; a file is in the way")
    folder.mkdir(parents=True, exist_ok=True)
    check_writable(folder / MANIFEST)
    return folder


def write_part(folder: Path, k: int, looks) -> list:
    """Write part ``k``'s ``looks`` (Hologram) into ``folder``; their manifest entries."""
    files = []
    for look, h in enumerate(looks):
        path = write_hologram(folder / part_file(k, look), h)
        files.append(
            {
                "name": path.name,
                "bytes": path.stat().st_size,
                "blake2b": file_digest(path),
                "metadata": metadata_digest(h),
            }
        )
    return files


def write_manifest(
    folder: Path, parts, entries, *, seed: int, recording: str, looks: int | None = None
) -> Path:
    """The manifest of ``parts`` (PathPart) whose files ``entries`` (:func:`write_part`, one a
    part, None for a part not recorded yet) lie in ``folder``: rewritten after each part a
    recording finishes, so that a recording stopped resumes from the parts it wrote
    (:func:`recorded_parts`); a set with a part not recorded is refused by the reader."""
    listed = [{**part_entry(part), "files": files} for part, files in zip(parts, entries)]
    looks = looks or len(next(e for e in entries if e is not None))
    manifest = {
        "kind": KIND,
        "version": VERSION,
        "recording": recording,
        "seed": seed,
        "looks": looks,
        "parts": listed,
    }
    return write_atomic(folder / MANIFEST, json.dumps(manifest, indent=1).encode())


def part_entry(part: PathPart) -> dict:
    """A part as the manifest names it: its plate's pose, size and zone, its stretch [m] and
    frames (plain data, JSON's)."""
    p = part.plate
    return {
        "plate_to_world": np.asarray(p.matrix_world).tolist(),
        "width_m": p.width,
        "height_m": p.height,
        "zone": {
            "centre_m": list(p.zone.centre),
            "half_extents_m": list(p.zone.half_extents),
            "pupil_m": p.zone.pupil,
            "pixel_rad": p.zone.pixel,
        },
        "stretch_m": list(part.stretch),
        "frames": list(part.frames),
    }


def part_of(entry, name: str = "part") -> PathPart:
    """The :class:`PathPart` of a :func:`part_entry` (an :class:`InputError` naming ``name``
    where it is malformed)."""
    try:
        z = entry["zone"]
        zone = ViewingZone(
            centre=z["centre_m"],
            half_extents=z["half_extents_m"],
            pupil=z["pupil_m"],
            pixel=z["pixel_rad"],
        )
        plate = Plate(
            matrix_world=np.asarray(entry["plate_to_world"], np.float64),
            width=entry["width_m"],
            height=entry["height_m"],
            zone=zone,
        )
        return PathPart(
            plate=plate, stretch=tuple(entry["stretch_m"]), frames=tuple(entry["frames"])
        )
    except (KeyError, TypeError, ValueError) as e:
        raise InputError(
            f"{name}: not a plate set's part ({type(e).__name__}: {e})"[:300]
        ) from None
    except InputError as e:
        raise InputError(f"{name}: {e}") from None


def parts_to_json(parts) -> str:
    """``parts`` (PathPart) as JSON text (:func:`part_entry` each; :func:`parts_from_json`
    reads it): what a scene keeps of the parts it placed, before any is recorded."""
    return json.dumps([part_entry(p) for p in parts])


def parts_from_json(text: str) -> tuple:
    """The parts of :func:`parts_to_json`'s text; an :class:`InputError` naming the part
    that is malformed."""
    try:
        listed = json.loads(text)
    except (TypeError, ValueError) as e:
        raise InputError(f"plate set parts: not JSON ({e})"[:300]) from None
    if not isinstance(listed, list) or not listed:
        raise InputError("plate set parts: a non-empty list of parts")
    return tuple(part_of(entry, f"part {k}") for k, entry in enumerate(listed))


def set_current(folder, recording: str, count: int) -> bool:
    """Whether ``folder`` holds a whole set of ``count`` parts recorded as ``recording`` (its
    manifest names it, and files for every part): what tells a caller to record or to read.
    Only the manifest is read; the reader checks every file."""
    name = Path(folder) / MANIFEST
    if not name.is_file():
        return False
    try:
        m = jsonfile.load(name, error=HologramFileError, max_chars=MANIFEST_CHARS)
    except HologramFileError:
        return False  # damaged: the recording replaces it, or the reader names it
    listed = m.get("parts") if isinstance(m, dict) else None
    return (
        m.get("kind") == KIND
        and m.get("recording") == recording
        and isinstance(listed, list)
        and len(listed) == count
        and all(isinstance(e, dict) and e.get("files") for e in listed)
    )


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


def recorded_parts(folder, recording: str, count: int, *, overwrite=False) -> dict:
    """The parts already recorded in ``folder`` for the recording ``recording`` of ``count``
    parts, {index: their manifest entries}, each checked (a damaged one is left out, to be
    recorded again): empty where the folder holds no set. A set of another recording (an
    edited scene, other parts or looks) is refused naming both, unless ``overwrite``."""
    folder = Path(folder)
    if not (folder / MANIFEST).exists():
        return {}
    m = jsonfile.load(folder / MANIFEST, error=HologramFileError, max_chars=MANIFEST_CHARS)
    held = m.get("recording") if isinstance(m, dict) else None
    if held != recording or m.get("kind") != KIND:
        if overwrite:
            return {}
        raise InputError(
            f"{folder}: holds another plate set (recording {str(held)[:12]}; this "
            f"one is {recording[:12]}: the scene, the path or the looks "
            f"differ); record to a new folder, or replace it (overwrite=True)"
        )
    field, done = _Fields(folder / MANIFEST), {}
    listed = m.get("parts") if isinstance(m.get("parts"), list) else []
    for k, entry in enumerate(listed[:count]):
        files = entry.get("files") if isinstance(entry, dict) else None
        if not files:
            continue
        try:
            for look, f in enumerate(files):
                _check_file(folder, k, look, f, field, f"parts[{k}].")
        except HologramFileError:
            continue  # recorded again
        done[k] = files
    return done


def read_plate_set(folder) -> PlateSet:
    """Open the plate set in a folder: every part's files there as the manifest lists them,
    each part's bytes checked against their digests when it is first read.

    Parameters
    ----------
    folder : str or Path
        A folder written by :func:`write_plate_set`.

    Returns
    -------
    PlateSet
        The parts and their looks (read when a view needs them), as the manifest names them
        (module docstring).

    Raises
    ------
    HologramFileError
        (an :class:`InputError`) Where ``folder`` is no plate set's folder, the manifest is
        damaged, or a part's file is missing or not of its listed size; when a part is read
        (:meth:`~holo_core.scene.plate_set.PlateSet.part_looks`), where its bytes or its
        plate are not the manifest's.

    Examples
    --------
    >>> import tempfile
    >>> from holo_core import InputError, read_plate_set
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     try:
    ...         read_plate_set(folder)
    ...     except InputError as e:
    ...         print(str(e).endswith("(no plate_set.json)"))
    True
    """
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
        if entry.get("files") is None:
            raise HologramFileError(
                f"{folder}: part {k} was not recorded (the recording "
                f"stopped before it); recording the set again resumes it"
            )
        files = field.check(entry, "files", list, f"{looks} files", at)
        if len(files) != looks:
            field.fail(f"{at}files", f"{looks} files (one a look); it lists {len(files)}")
        try:
            pose = np.asarray(entry.get("plate_to_world"), np.float64)
            stretch = tuple(entry.get("stretch_m"))
            frames = tuple(entry.get("frames"))
        except (TypeError, ValueError):
            field.fail(f"{at}plate_to_world", "a 4x4 pose, its stretch_m and frames")
        for look, f in enumerate(files):  # their bytes when the part is read (_load_part)
            _listed_file(folder, k, look, f, field, at)
        z = field.check(entry, "zone", dict, "the part's viewing zone", at)
        try:
            zone = ViewingZone(
                centre=z.get("centre_m"),
                half_extents=z.get("half_extents_m"),
                pupil=z.get("pupil_m"),
                pixel=z.get("pixel_rad"),
            )
            plate = Plate(
                matrix_world=pose,
                width=entry.get("width_m"),
                height=entry.get("height_m"),
                zone=zone,
            )
            parts.append(PathPart(plate=plate, stretch=stretch, frames=frames))
        except InputError as e:
            raise HologramFileError(f"{name}: {at[:-1]}: {e}") from None
        held.append(files)
    load = partial(_load_part, folder, tuple(parts), tuple(held))
    try:
        return PlateSet(
            parts=tuple(parts),
            looks=(None,) * len(parts),
            seed=seed,
            recording=recording,
            load=load,
        )
    except InputError as e:
        raise HologramFileError(f"{name}: {e}") from None


def _check_file(folder: Path, k: int, look: int, entry, field, at) -> None:
    """Part ``k``'s look ``look`` as its manifest ``entry`` names it, its bytes included:
    refused by name when missing, damaged or foreign (:func:`_listed_file`,
    :func:`_check_bytes`)."""
    _check_bytes(folder, k, entry, _listed_file(folder, k, look, entry, field, at))


def _listed_file(folder: Path, k: int, look: int, entry, field, at) -> Path:
    """The path of part ``k``'s look ``look`` as its manifest ``entry`` names it, its fields
    checked and the file there with the manifest's size (no byte read); refused by name
    otherwise."""
    where = f"{at}files[{look}]."
    field.value(entry, dict, "an object", where[:-1])
    name = field.check(entry, "name", str, "a file name", where)
    field.check(entry, "bytes", int, "the file's size", where)
    field.check(entry, "blake2b", str, "the file's digest", where)
    field.check(entry, "metadata", str, "its metadata's digest", where)
    if Path(name).name != name or name in ("", ".", ".."):
        field.fail(f"{where}name", "a file name inside the set's folder")
    path = folder / name
    if path.is_symlink() or (path.exists() and not path.is_file()):
        raise HologramFileError(f"{folder}: part {k} ({name}) is not a regular file")
    if not path.exists():
        raise HologramFileError(
            f"{folder}: part {k} ({name}) is missing: the set is incomplete; record it again"
        )
    if path.stat().st_size != entry["bytes"]:
        _refuse(folder, k, entry, path)
    return path


def _check_bytes(folder: Path, k: int, entry, path: Path) -> None:
    """Part ``k``'s file ``path`` (a checked manifest ``entry``'s) refused by name unless its
    bytes are the manifest's digest (read once)."""
    if file_digest(path) != entry["blake2b"]:
        _refuse(folder, k, entry, path)


def _refuse(folder: Path, k: int, entry, path: Path):
    """The refusal of part ``k``'s file ``path``, which does not match its manifest ``entry``:
    foreign where it is a hologram of another description, else damaged."""
    try:
        h = read_hologram(path)
    except HologramFileError:
        h = None
    name = entry["name"]
    if h is not None and metadata_digest(h) != entry["metadata"]:
        raise HologramFileError(
            f"{folder}: part {k} ({name}) is foreign: a hologram, but "
            f"not the one this set recorded (its description differs "
            f"from the manifest's); record the set again"
        )
    raise HologramFileError(
        f"{folder}: part {k} ({name}) is damaged: its bytes do not "
        f"match the manifest's digest; record the set again"
    )


def _load_part(folder: Path, parts, files, k: int) -> tuple:
    """Part ``k``'s looks read from ``folder``, each checked to be the hologram the manifest
    names (its size, its bytes' digest and its description) and to lie on its part's
    plate. The digest is found while the file is read (a core each: the part's load takes
    about the longer of the two, not their sum), and a sample is used only once it matches."""
    looks = []
    for entry in files[k]:
        path = folder / entry["name"]
        if not path.is_file() or path.stat().st_size != entry["bytes"]:
            raise HologramFileError(
                f"{folder}: part {k} ({entry['name']}) changed or went "
                f"missing since the set was opened"
            )
        with ThreadPoolExecutor(1, thread_name_prefix="holo-part-digest") as pool:
            digest = pool.submit(file_digest, path)
            try:
                h = read_hologram(path)
            except HologramFileError:
                h = None  # unreadable: named below, damaged or foreign, where the digest fails
            if digest.result() != entry["blake2b"]:
                _refuse(folder, k, entry, path)
        if h is None:
            h = read_hologram(path)  # its bytes are the manifest's: the reader's own refusal
        if metadata_digest(h) != entry["metadata"] or not np.allclose(
            np.asarray(h.plate), parts[k].plate.matrix_world, atol=1e-12
        ):
            raise HologramFileError(
                f"{folder}: part {k} ({entry['name']}) is foreign: its "
                f"plate is not the manifest's part {k}"
            )
        looks.append(h)
    return tuple(looks)


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
