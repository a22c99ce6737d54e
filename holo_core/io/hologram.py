"""The hologram and its file: OpenEXR, float32 channels per wavelength, metadata as JSON.

Channels, for colour c = 0, 1, ...: ``c<c>.H`` the intensity hologram (an intensity
hologram's), and ``c<c>.O.re`` / ``c<c>.O.im`` the complex object wave (a complex hologram's,
optional beside an intensity). The header attribute ``holo`` holds the metadata (see
:func:`metadata`: the encoding, the optics, the plate's pose and its viewing zone); files are
written atomically and read back bit-exactly. Version 2 files (intensity holograms without a
viewing zone) are read as well.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .. import __version__, validate
from ..scene.hologram import CHANNEL_ROLES, ENCODINGS, MAX_CHANNELS, Hologram
from ..scene.plate import ViewingZone
from ..validate import InputError
from .image import write_exr

FORMAT = "holo-hologram"
FORMAT_VERSION = 3  # 3: the encoding (complex or intensity) and the plate's viewing zone
READS = (2, 3)      # 2: the depth partner 'Z' records every emitter at unit intensity


class HologramFileError(InputError):
    """A hologram file that cannot be read; the message names the file and the problem."""


def metadata(h: Hologram) -> dict:
    return {
        "format": FORMAT, "format_version": FORMAT_VERSION, "software": f"holo {__version__}",
        "wavelengths_m": list(map(float, h.wavelengths)), "pitch_m": float(h.pitch),
        "size_px": list(h.shape), "plate_to_world": np.asarray(h.plate).ravel().tolist(),
        "reference": {"angle_rad": float(h.reference_angle),
                      "azimuth_rad": float(h.reference_azimuth),
                      "amplitudes": list(map(float, h.reference_amplitudes))},
        "bounds_m": np.asarray(h.bounds).tolist(), "object_wave": h.object_wave is not None,
        "band_sin": float(h.band), "channels": list(h.channels),
        "point_density_per_m2": float(h.point_density), "encoding": h.encoding,
        "viewing_zone": None if h.zone is None else {
            "centre_m": list(h.zone.centre), "half_extents_m": list(h.zone.half_extents),
            "pupil_m": h.zone.pupil},
    }


def write_hologram(path, h: Hologram) -> Path:
    """Write ``h`` to ``path`` (.exr) through a temporary file and a rename. What the reader
    would refuse is refused here, never written: an empty or non-finite hologram, or
    metadata outside the reader's schema (:func:`_meta`)."""
    check_pixels(str(path), h)
    header = json.dumps(metadata(h))
    _meta(path, {"holo": header})  # the reader's schema, on the very text written
    channels = {}
    for c in range(len(h.wavelengths)):
        if h.intensity is not None:
            channels[f"c{c}.H"] = h.intensity[c]
        if h.object_wave is not None:
            channels[f"c{c}.O.re"] = h.object_wave[c].real
            channels[f"c{c}.O.im"] = h.object_wave[c].imag
    write_exr(path, channels, holo=header)
    return path


def check_pixels(name: str, h: Hologram) -> None:
    """:class:`HologramFileError` naming ``name`` unless the hologram holds samples, its
    intensity (if any) all finite and >= 0, and its object wave (if any) finite."""
    if 0 in h.shape:
        raise HologramFileError(f"{name}: the hologram holds no samples")
    if h.intensity is not None and (not np.isfinite(h.intensity).all() or
                                    (h.intensity < 0).any()):
        raise HologramFileError(f"{name}: the intensity holds NaN, infinite or negative values "
                                f"(it must be finite and >= 0)")
    if h.object_wave is not None and not np.isfinite(h.object_wave).all():
        raise HologramFileError(f"{name}: the object wave holds NaN or infinite values")


@validate.scale_free()  # a file holds what the renderer made, at the wavelength it chose
def read_hologram(path) -> Hologram:
    """Read a hologram written by :func:`write_hologram`; :class:`HologramFileError` naming the
    file and the problem if it is missing, not an EXR, damaged, too large for the memory, of
    an unknown format version, lacks a channel, or its metadata or pixels are out of range
    (every metadata field is checked, see :func:`_meta`)."""
    path = Path(path)
    header, names = _read(path)
    meta = _meta(path, header)
    colours = range(len(meta["wavelengths_m"]))
    intensity = meta["encoding"] == "intensity"
    wanted = [f"c{c}.H" for c in colours] if intensity else []
    if meta["object_wave"]:
        wanted += [f"c{c}.O.{p}" for c in colours for p in ("re", "im")]
    missing = [n for n in wanted if n not in names]
    if missing:
        raise HologramFileError(f"{path}: missing channel(s) {', '.join(missing)}")
    shape = tuple(meta["size_px"])
    for n in wanted:
        if names[n].shape != shape:
            raise HologramFileError(f"{path}: channel {n} is {names[n].shape}, metadata says "
                                    f"{shape}")
    wave = None
    if meta["object_wave"]:
        wave = np.stack([names[f"c{c}.O.re"] + 1j * names[f"c{c}.O.im"] for c in colours])
        wave = wave.astype(np.complex64)
    h = hologram_from(path, meta, np.stack([names[f"c{c}.H"] for c in colours]) if intensity
                      else None, wave)
    check_pixels(str(path), h)
    return h


def hologram_from(path, meta: dict, intensity, object_wave) -> Hologram:
    """The :class:`Hologram` of checked metadata ``meta`` (:func:`meta_of`) and its samples
    (arrays indexed [channel, row, col], in memory or in chunks)."""
    ref, zone = meta["reference"], meta["viewing_zone"]
    try:
        if zone is not None:
            zone = ViewingZone(centre=zone["centre_m"], half_extents=zone["half_extents_m"],
                               pupil=zone.get("pupil_m", 0.0))
        return Hologram(intensity=intensity, encoding=meta["encoding"], zone=zone,
                        wavelengths=tuple(meta["wavelengths_m"]), pitch=meta["pitch_m"],
                        reference_angle=ref["angle_rad"], reference_azimuth=ref["azimuth_rad"],
                        reference_amplitudes=tuple(ref["amplitudes"]), object_wave=object_wave,
                        plate=np.array(meta["plate_to_world"], np.float64).reshape(4, 4),
                        bounds=np.array(meta["bounds_m"], np.float64), band=meta["band_sin"],
                        channels=tuple(meta["channels"]),
                        point_density=meta["point_density_per_m2"])
    except ValueError as e:
        raise HologramFileError(f"{path}: {e}") from None


def meta_of(path, text: str) -> dict:
    """The metadata of the file at ``path`` from the JSON ``text`` of its ``holo`` header,
    every field checked (:class:`HologramFileError` naming the file and the field)."""
    return _meta(Path(str(path)), {"holo": text})


def _read(path: Path, what="hologram"):
    from .image import read_exr
    try:
        return read_exr(path, what=what)
    except HologramFileError:
        raise
    except ValueError as e:
        raise HologramFileError(str(e)) from None


def _meta(path: Path, header) -> dict:
    """The ``holo`` metadata, every field checked against its type and range."""
    if "holo" not in header:
        raise HologramFileError(f"{path}: an EXR image without hologram metadata; "
                                f"import it with import_acquired(pitch=, wavelength=, ...)")
    try:
        meta = json.loads(header["holo"])
    except (TypeError, ValueError, RecursionError) as e:
        raise HologramFileError(f"{path}: damaged hologram metadata ({e})") from None
    if not isinstance(meta, dict):
        raise HologramFileError(f"{path}: hologram metadata must be a JSON object")
    if meta.get("format") != FORMAT:
        raise HologramFileError(f"{path}: metadata format {meta.get('format')!r}, "
                                f"expected {FORMAT!r}")
    version = meta.get("format_version")
    if isinstance(version, bool) or version not in READS:
        raise HologramFileError(f"{path}: format version {version!r} is not supported (this "
                                f"is holo {__version__}, which reads versions "
                                f"{', '.join(map(str, READS))})"[:400])
    meta = {"band_sin": 0.0, "channels": [], "point_density_per_m2": 0.0,
            "encoding": "intensity", "viewing_zone": None, **meta}
    schema = _Schema(path, meta)
    lengths = f"in [{validate.MIN_LENGTH:g}, {validate.MAX_LENGTH:g}] [m]"
    wavelengths = schema.numbers("wavelengths_m", lengths, _length, shape="any")
    if not 1 <= len(wavelengths) <= MAX_CHANNELS:
        schema.fail("wavelengths_m", f"1 to {MAX_CHANNELS} wavelengths [m]")
    schema.numbers("pitch_m", lengths, _length)
    rows, cols = schema.numbers("size_px", "two integers >= 1",
                                lambda v: v >= 1 and v == int(v), shape=2)
    meta["size_px"] = [int(rows), int(cols)]
    schema.numbers("plate_to_world", "16 finite numbers (a rigid pose)", shape=16)
    ref = meta.get("reference")
    if not isinstance(ref, dict):
        schema.fail("reference", "an object with angle_rad, azimuth_rad and amplitudes")
    sub = _Schema(path, ref, "reference.")
    sub.numbers("angle_rad", "in [0, π/2)", lambda v: 0 <= v < math.pi / 2)
    sub.numbers("azimuth_rad", "finite")
    amplitudes = sub.numbers("amplitudes", f"{len(wavelengths)} numbers > 0 (or none)",
                             lambda v: v > 0, shape="any")
    if len(amplitudes) not in (0, len(wavelengths)):
        sub.fail("amplitudes", f"{len(wavelengths)} numbers > 0 (or none)")
    bounds = np.reshape(schema.numbers("bounds_m", "two corners (x, y, z) [m]", shape=(2, 3)),
                        (2, 3))
    if (bounds[0] > bounds[1]).any():
        schema.fail("bounds_m", "a min corner <= the max corner")
    if not isinstance(meta.get("object_wave"), bool):
        schema.fail("object_wave", "true or false")
    schema.numbers("band_sin", "in [0, 1)", lambda v: 0 <= v < 1)
    schema.numbers("point_density_per_m2", ">= 0 [1/m²]", lambda v: v >= 0)
    names = meta["channels"]
    if not isinstance(names, list) or (names and (
            len(names) != len(wavelengths) or not all(n in CHANNEL_ROLES for n in names))):
        schema.fail("channels", f"one of {'/'.join(CHANNEL_ROLES)} per wavelength")
    if not isinstance(meta["encoding"], str) or meta["encoding"] not in ENCODINGS:
        schema.fail("encoding", " or ".join(map(repr, ENCODINGS)))
    if meta["encoding"] == "complex" and meta["object_wave"] is not True:
        schema.fail("object_wave", "true for a complex hologram (its samples are the object "
                    "wave)")
    zone = meta["viewing_zone"]
    if zone is not None:
        if not isinstance(zone, dict):
            schema.fail("viewing_zone", "null or an object with centre_m, half_extents_m and "
                        "pupil_m")
        sub = _Schema(path, zone, "viewing_zone.")
        sub.numbers("centre_m", "three coordinates [m], z > 0", shape=3)
        sub.numbers("half_extents_m", "three half widths >= 0 [m]", lambda v: v >= 0, shape=3)
        zone.setdefault("pupil_m", 0.0)
        sub.numbers("pupil_m", ">= 0 [m]", lambda v: v >= 0)
    return meta


def _length(v) -> bool:
    return validate.MIN_LENGTH <= v <= validate.MAX_LENGTH


class _Schema:
    """Checks the fields of one JSON object of a hologram file's metadata."""

    def __init__(self, path, obj, prefix=""):
        self.path, self.obj, self.prefix = path, obj, prefix

    def fail(self, key, allowed):
        value = repr(self.obj.get(key, "missing"))[:80]
        raise HologramFileError(f"{self.path}: metadata {self.prefix}{key} must be {allowed}; "
                                f"got {value}")

    def numbers(self, key, allowed, ok=lambda v: True, shape=None):
        """The field as a number, or with a ``shape`` (a length, a tuple of them, or "any"
        length) as a flat list of numbers; each finite, not a bool, and ``ok``."""
        value = self.obj.get(key)
        flat = [value] if shape is None else _flatten(value, shape)
        if flat is None or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                   and math.isfinite(v) and ok(v) for v in flat):
            self.fail(key, allowed)
        return flat[0] if shape is None else flat


def _flatten(value, shape):
    """``value`` (nested lists) flattened when it has ``shape`` (an int, a tuple, or "any"
    for a list of any length), else None."""
    dims = shape if isinstance(shape, tuple) else (shape,)
    if not isinstance(value, list) or (dims[0] != "any" and len(value) != dims[0]):
        return None
    if len(dims) == 1:
        return value
    parts = [_flatten(v, dims[1:]) for v in value]
    return None if any(p is None for p in parts) else [x for p in parts for x in p]



def __getattr__(name):  # acquired scans and lab arrays live in .acquired; the reader's old home
    if name == "import_acquired":
        from .acquired import import_acquired
        return import_acquired
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
