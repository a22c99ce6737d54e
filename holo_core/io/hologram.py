"""The hologram and its file: OpenEXR, float32 channels per wavelength, metadata as JSON.

Channels, for colour c = 0, 1, ...: ``c<c>.H`` the intensity hologram (an intensity
hologram's), and the complex object wave (a complex hologram's, optional beside an intensity):
``c<c>.O`` of a complex hologram, its samples' (real, imaginary) pairs side by side in a row
twice the hologram's width (the complex64 array as it lies in memory: a plate's 1.8 GB are
written without a copy), or beside an intensity ``c<c>.O.re`` / ``c<c>.O.im`` (an EXR's
channels share one width). The header attribute ``holo`` holds the metadata (see
:func:`metadata`: the encoding, the optics, the plate's pose and its viewing zone); files are
written atomically and read back bit-exactly. A plate stored against its zone's carrier names
it: ``carrier`` holds the point it converges on, the origin of the samples and their row
pitch. Older versions are read as well: 2 (intensity holograms without a viewing zone), 3 (no
carrier, a zone without its pixel angle) and 4 (a complex hologram's ``O.re`` and ``O.im``).
"""

from __future__ import annotations

import json
import math
import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from .. import __version__, memory, validate
from ..scene.hologram import Hologram, HologramInfo
from ..scene.plate import Carrier, ViewingZone
from ..validate import InputError
from .image import exr_attribute, read_exr, write_exr

FORMAT = "holo-hologram"
FORMAT_VERSION = 5  # 5: a complex hologram's samples as (real, imaginary) pairs, ``c<c>.O``
# 2: the depth partner 'Z' records every emitter at unit intensity; 3: the encoding (complex or
# intensity) and the plate's viewing zone; 4: the samples' carrier and the zone's pixel angle
READS = (2, 3, 4, 5)


class HologramFileError(InputError):
    """A hologram file that cannot be read; the message names the file and the problem."""


# the file's name of each field of a hologram's description (HologramInfo)
FILE_KEYS = {
    "wavelengths": "wavelengths_m",
    "pitch": "pitch_m",
    "shape": "size_px",
    "plate": "plate_to_world",
    "reference_angle": "reference.angle_rad",
    "reference_azimuth": "reference.azimuth_rad",
    "reference_amplitudes": "reference.amplitudes",
    "bounds": "bounds_m",
    "band": "band_sin",
    "point_density": "point_density_per_m2",
    "zone": "viewing_zone",
    "keeps_object_wave": "object_wave",
    "carrier": "carrier",
    "recording": "recording",
}


def metadata(h: Hologram | HologramInfo) -> dict:
    """The file's metadata of a hologram or of its description (:class:`HologramInfo`)."""
    info = h.info if isinstance(h, Hologram) else h
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "software": f"holo {__version__}",
        "wavelengths_m": list(map(float, info.wavelengths)),
        "pitch_m": float(info.pitch),
        "size_px": list(info.shape),
        "plate_to_world": np.asarray(info.plate).ravel().tolist(),
        "reference": {
            "angle_rad": float(info.reference_angle),
            "azimuth_rad": float(info.reference_azimuth),
            "amplitudes": list(map(float, info.reference_amplitudes)),
        },
        "bounds_m": np.asarray(info.bounds).tolist(),
        "object_wave": info.keeps_object_wave,
        "band_sin": float(info.band),
        "channels": list(info.channels),
        "point_density_per_m2": float(info.point_density),
        "encoding": info.encoding,
        "viewing_zone": None
        if info.zone is None
        else {
            "centre_m": list(info.zone.centre),
            "half_extents_m": list(info.zone.half_extents),
            "pupil_m": info.zone.pupil,
            "pixel_rad": info.zone.pixel,
        },
        "carrier": None
        if info.carrier is None
        else {
            "centre_m": list(info.carrier.centre),
            "origin_m": list(info.carrier.origin),
            "row_pitch_m": info.carrier.row_pitch,
        },
        "recording": info.recording,
    }


def write_hologram(path, h: Hologram) -> Path:
    """Write a hologram to an EXR file, through a temporary file and a rename.

    Parameters
    ----------
    path : str or Path
        The ``.exr`` file to write.
    h : Hologram
        The hologram (intensity, object wave, or both) and its description.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    HologramFileError
        (an :class:`InputError`) What the reader would refuse is refused here, never
        written: an empty or non-finite hologram, or metadata outside the reader's schema
        (:func:`_described`).

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np
    >>> from holo_core import Hologram, read_hologram, write_hologram
    >>> h = Hologram(intensity=np.ones((1, 64, 64), np.float32), wavelengths=(633e-9,),
    ...              pitch=2e-6)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     back = read_hologram(write_hologram(os.path.join(folder, "h.exr"), h))
    >>> back.intensity.shape, back.pitch
    ((1, 64, 64), 2e-06)
    """
    check_pixels(str(path), h)
    header = json.dumps(metadata(h))
    _described(path, {"holo": header})  # the reader's schema, on the very text written
    channels = {}
    for c in range(len(h.wavelengths)):
        if h.intensity is not None:
            channels[f"c{c}.H"] = h.intensity[c]
        if h.object_wave is not None and h.intensity is not None:
            channels[f"c{c}.O.re"] = h.object_wave[c].real
            channels[f"c{c}.O.im"] = h.object_wave[c].imag
        elif h.object_wave is not None:  # pairs: the samples as they lie, not split in copies
            channels[f"c{c}.O"] = np.ascontiguousarray(h.object_wave[c]).view(np.float32)
    # a plate's object wave is speckle, which ZIP barely shrinks (by about a fifth) at seconds
    # to write and to read it, where a frame reads it each time (docs, Performance)
    write_exr(path, channels, holo=header, compression="none" if h.carrier is not None else "zip")
    return path


def check_pixels(name: str, h: Hologram) -> None:
    """:class:`HologramFileError` naming ``name`` unless the hologram holds samples, its
    intensity (if any) all finite and >= 0, and its object wave (if any) finite."""
    if 0 in h.shape:
        raise HologramFileError(f"{name}: the hologram holds no samples")
    if h.intensity is not None and (not np.isfinite(h.intensity).all() or (h.intensity < 0).any()):
        raise HologramFileError(
            f"{name}: the intensity holds NaN, infinite or negative values "
            f"(it must be finite and >= 0)"
        )
    if h.object_wave is not None and not np.isfinite(h.object_wave).all():
        raise HologramFileError(f"{name}: the object wave holds NaN or infinite values")


@validate.scale_free()  # a file holds what the renderer made, at the wavelength it chose
def read_hologram(path) -> Hologram:
    """Read a hologram written by :func:`write_hologram`.

    Parameters
    ----------
    path : str or Path
        The ``.exr`` file.

    Returns
    -------
    Hologram
        Its samples and description (wavelengths and pitch [m], ...).

    Raises
    ------
    HologramFileError
        (an :class:`InputError`) Naming the file and the problem if it is missing, not an EXR,
        damaged, too large for the memory, of an unknown format version, lacks a channel, or
        its metadata or pixels are out of range (every metadata field is checked, see
        :func:`_meta`).

    Examples
    --------
    >>> from holo_core import InputError, read_hologram
    >>> try:
    ...     read_hologram("no-such-file.exr")
    ... except InputError:
    ...     print("refused")
    refused
    """
    path = Path(path)
    header, names = _read(path)
    info = _described(path, header)
    colours = range(len(info.wavelengths))
    intensity = info.encoding == "intensity"
    wanted = [f"c{c}.H" for c in colours] if intensity else []
    pairs = info.keeps_object_wave and any(f"c{c}.O" in names for c in colours)  # format 5
    if pairs:
        wanted += [f"c{c}.O" for c in colours]
    elif info.keeps_object_wave:
        wanted += [f"c{c}.O.{p}" for c in colours for p in ("re", "im")]
    missing = [n for n in wanted if n not in names]
    if missing:
        raise HologramFileError(f"{path}: missing channel(s) {', '.join(missing)}")
    for n in wanted:
        shape = (info.shape[0], 2 * info.shape[1]) if n.endswith(".O") else info.shape
        if names[n].shape != shape:
            raise HologramFileError(
                f"{path}: channel {n} is {names[n].shape}, metadata says {shape}"
            )
    wave = None
    if pairs:
        wave = _complex([(names[f"c{c}.O"],) for c in colours])
    elif info.keeps_object_wave:
        wave = _complex([(names[f"c{c}.O.re"], names[f"c{c}.O.im"]) for c in colours])
    h = Hologram(
        info=info,
        intensity=np.stack([names[f"c{c}.H"] for c in colours]) if intensity else None,
        object_wave=wave,
    )
    check_pixels(str(path), h)
    return h


def _complex(parts) -> np.ndarray:
    """(C, H, W) complex64 of each channel's float32 planes ``parts``: (real, imaginary), or
    the pairs (H, 2W) alone; page-aligned (a CPU device's views read it in place), copied in
    blocks of rows over the cores: a frame of an animation reads its plate this way."""
    h, w = parts[0][0].shape
    wave = memory.aligned_zeros((len(parts), h, w if len(parts[0]) == 2 else w // 2))

    def fill(block):
        c, r0 = block
        out = wave[c, r0 : r0 + ROWS_A_BLOCK]
        if len(parts[c]) == 1:
            out.view(np.float32)[...] = parts[c][0][r0 : r0 + ROWS_A_BLOCK]
        else:
            out.real, out.imag = (p[r0 : r0 + ROWS_A_BLOCK] for p in parts[c])

    with ThreadPoolExecutor(os.cpu_count() or 1) as pool:  # NumPy's copies release the GIL
        list(
            pool.map(fill, [(c, r0) for c in range(len(parts)) for r0 in range(0, h, ROWS_A_BLOCK)])
        )
    return wave


ROWS_A_BLOCK = 512


def recording_of(path) -> str | None:
    """The recording the hologram file at ``path`` names in its header ('' where it names
    none: an earlier or imported file), read without the EXR library and without its
    samples; None when the file or its metadata cannot be read."""
    header = exr_attribute(path, "holo")
    try:
        meta = json.loads(header.decode("utf-8")) if header is not None else None
    except (UnicodeDecodeError, ValueError, RecursionError):
        return None
    if not isinstance(meta, dict) or not isinstance(meta.get("recording", ""), str):
        return None
    return meta.get("recording", "")


def info_of(path, text: str) -> HologramInfo:
    """The description of the hologram at ``path`` from the JSON ``text`` of its ``holo``
    metadata, checked (:class:`HologramFileError` naming the file and the field)."""
    return _described(Path(str(path)), {"holo": text})


def _read(path: Path, what="hologram"):
    try:
        return read_exr(path, what=what)
    except HologramFileError:
        raise
    except ValueError as e:
        raise HologramFileError(str(e)) from None


@validate.scale_free()  # a file holds what the renderer made, at the wavelength it chose
def _described(path: Path, header) -> HologramInfo:
    """The ``holo`` metadata as a :class:`HologramInfo`: the JSON's structure checked here (a
    format and version this reads, each field of its type), every value by the description
    itself, its complaint naming the file and the field as the file names it."""
    if "holo" not in header:
        raise HologramFileError(
            f"{path}: an EXR image without hologram metadata; import it "
            f"with holo_core.import_acquired(pitch=, wavelength=, ...)"
        )
    try:
        meta = json.loads(header["holo"])
    except (TypeError, ValueError, RecursionError) as e:
        raise HologramFileError(f"{path}: damaged hologram metadata ({e})") from None
    if not isinstance(meta, dict):
        raise HologramFileError(f"{path}: hologram metadata must be a JSON object")
    if meta.get("format") != FORMAT:
        raise HologramFileError(
            f"{path}: metadata format {meta.get('format')!r}, expected {FORMAT!r}"
        )
    version = meta.get("format_version")
    if isinstance(version, bool) or version not in READS:
        raise HologramFileError(
            f"{path}: format version {version!r} is not supported (this "
            f"is holo {__version__}, which reads versions "
            f"{', '.join(map(str, READS))})"[:400]
        )
    meta = {
        "band_sin": 0.0,
        "channels": [],
        "point_density_per_m2": 0.0,
        "encoding": "intensity",
        "viewing_zone": None,
        "carrier": None,
        "recording": "",
        **meta,
    }
    schema = _Schema(path, meta)
    ref = meta.get("reference")
    if not isinstance(ref, dict):
        schema.fail("reference", "an object with angle_rad, azimuth_rad and amplitudes")
    sub = _Schema(path, ref, "reference.")
    fields = {
        "wavelengths": schema.numbers("wavelengths_m", "a list of wavelengths [m]", shape="any"),
        "pitch": schema.numbers("pitch_m", "a number [m]"),
        "shape": schema.numbers(
            "size_px", "two integers >= 1", lambda v: v >= 1 and v == int(v), shape=2
        ),
        "plate": np.reshape(
            schema.numbers("plate_to_world", "16 finite numbers (a rigid pose)", shape=16), (4, 4)
        ),
        "reference_angle": sub.numbers("angle_rad", "a number [rad]"),
        "reference_azimuth": sub.numbers("azimuth_rad", "a number [rad]"),
        "reference_amplitudes": sub.numbers("amplitudes", "a list of numbers", shape="any"),
        "bounds": np.reshape(
            schema.numbers("bounds_m", "two corners (x, y, z) [m]", shape=(2, 3)), (2, 3)
        ),
        "band": schema.numbers("band_sin", "a number"),
        "point_density": schema.numbers("point_density_per_m2", "a number [1/m²]"),
        "channels": schema.kind("channels", list, "a list of channel roles"),
        "encoding": schema.kind("encoding", str, "a string"),
        "keeps_object_wave": schema.kind("object_wave", bool, "true or false"),
        "zone": _zone(path, meta["viewing_zone"]),
        "carrier": _carrier(path, meta["carrier"]),
        "recording": schema.kind("recording", str, "the recording's digest (a string)"),
    }
    fields["shape"] = tuple(int(n) for n in fields["shape"])
    try:
        return HologramInfo(**fields)
    except InputError as e:  # named as the file names the field
        field, _, rest = str(e).partition(" ")
        raise HologramFileError(f"{path}: metadata {FILE_KEYS.get(field, field)} {rest}") from None


def _zone(path, zone) -> ViewingZone | None:
    if zone is None:
        return None
    if not isinstance(zone, dict):
        _Schema(path, {"viewing_zone": zone}).fail(
            "viewing_zone", "null or an object with centre_m, half_extents_m and pupil_m"
        )
    sub = _Schema(path, {"pupil_m": 0.0, "pixel_rad": 0.0, **zone}, "viewing_zone.")
    try:
        return ViewingZone(
            centre=sub.numbers("centre_m", "three coordinates [m]", shape=3),
            half_extents=sub.numbers("half_extents_m", "three half widths [m]", shape=3),
            pupil=sub.numbers("pupil_m", "a number [m]"),
            pixel=sub.numbers("pixel_rad", "a number [rad]"),
        )
    except InputError as e:
        raise HologramFileError(f"{path}: metadata viewing_zone: {e}") from None


def _carrier(path, carrier) -> Carrier | None:
    if carrier is None:
        return None
    if not isinstance(carrier, dict):
        _Schema(path, {"carrier": carrier}).fail(
            "carrier", "null or an object with centre_m, origin_m and row_pitch_m"
        )
    sub = _Schema(path, carrier, "carrier.")
    try:
        return Carrier(
            centre=sub.numbers("centre_m", "three coordinates [m]", shape=3),
            origin=sub.numbers("origin_m", "two coordinates [m]", shape=2),
            row_pitch=sub.numbers("row_pitch_m", "a number [m]"),
        )
    except InputError as e:
        raise HologramFileError(f"{path}: metadata carrier: {e}") from None


class _Schema:
    """Checks the fields of one JSON object of a hologram file's metadata."""

    def __init__(self, path, obj, prefix=""):
        self.path, self.obj, self.prefix = path, obj, prefix

    def fail(self, key, allowed):
        value = repr(self.obj.get(key, "missing"))[:80]
        raise HologramFileError(
            f"{self.path}: metadata {self.prefix}{key} must be {allowed}; got {value}"
        )

    def kind(self, key, kind, allowed):
        """The field, when it is of the JSON type ``kind``."""
        value = self.obj.get(key)
        if not isinstance(value, kind):
            self.fail(key, allowed)
        return value

    def numbers(self, key, allowed, ok=lambda v: True, shape=None):
        """The field as a number, or with a ``shape`` (a length, a tuple of them, or "any"
        length) as a flat list of numbers; each finite, not a bool, and ``ok``."""
        value = self.obj.get(key)
        flat = [value] if shape is None else _flatten(value, shape)
        if flat is None or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and ok(v)
            for v in flat
        ):
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
