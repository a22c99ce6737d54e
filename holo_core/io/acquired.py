"""Acquired holograms in and out: camera scans and laboratory arrays.

In (:func:`read_acquired`): PNG (8- and 16-bit, grey or colour, animated PNG frames as pages),
TIFF (every page, or the one asked for), OpenEXR (a scan's Y or R/G/B channels, or a Holo
hologram file's intensity), NumPy ``.npy``, HDF5 (``.h5``, ``.hdf5``; HyperSpy's files with
their calibration) and MATLAB ``.mat`` v7.3 (HDF5 inside; read through h5py, the optional extra
``lab``), or an array in memory. Out (:func:`write_acquired`): the format the file name's suffix
asks for, or an error; whatever it writes, :func:`read_acquired` reads back.

Pitch, wavelength and the reference's angles are given, or read from the file's metadata under
these keys (SI units, as the hologram file's metadata names them):

``pitch_m``, ``wavelength_m``, ``reference_angle_rad``, ``reference_azimuth_rad``

- TIFF: the ImageDescription as a JSON object, or ImageJ's ``key=value`` lines; ImageJ's
  ``unit=micron`` (nm, mm, cm, m) with the X/Y resolution tags also gives the pitch;
- PNG: text chunks of those names;
- ``.npy``: a JSON object in ``<name>.json`` beside it;
- HDF5: attributes of the dataset, then of each group above it up to the file; a HyperSpy
  file's signal axes (scale and units) give the pitch and its microscope's beam energy the
  electrons' wavelength;
- ``.mat``: scalar variables of those names (and attributes, as HDF5).

A value given as an argument wins over the file's (a difference is logged). Every value is
checked as a typed one is (units guarded: a ``pitch_m`` of 8 is refused as micrometres).

Intensities: integers are scaled to [0, 1] by their bit depth (8, 16; 32-bit by the smallest
of 2⁸−1, 2¹⁶−1, 2³²−1 that holds them), colour is averaged to grey (16-bit colour keeps its 16
bits) and alpha dropped, floats are kept; a PNG this module wrote carries the scale that
restores its floats (``intensity_scale``). Layouts, by rule: a TIFF's samples stored as
separate planes (PlanarConfiguration 2, as tifffile writes a (P, H, W) array) are pages, one
per plane; interleaved samples are colour.

Nothing is read from outside the file named: an HDF5 dataset whose samples live in another
file (external storage, a virtual dataset) or that is reached through an external link is
refused, naming it. What cannot be bounded is refused before it is read: pages beyond
:data:`MAX_PAGES` for ``page='all'``, HDF5 files of more than :data:`MAX_OBJECTS` objects or
chunks larger than the memory, JSON nested deeper than :data:`~holo_core.io.jsonfile.MAX_DEPTH`.
"""

from __future__ import annotations

import json
import logging
import math
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import memory, units, validate
from ..scene.hologram import Hologram
from ..validate import InputError, shown
from . import jsonfile
from .hologram import HologramFileError, check_pixels, read_hologram, write_hologram
from .image import atomic_paths, check_writable, read_exr

log = logging.getLogger(__name__)

KEYS = ("pitch_m", "wavelength_m", "reference_angle_rad", "reference_azimuth_rad")
IMAGES = (".png", ".tif", ".tiff")
HDF5 = (".h5", ".hdf5", ".mat")
SUFFIXES = (*IMAGES, ".exr", ".npy", *HDF5)
MAX_PAGES = 4096  # page='all' returns at most this many holograms (each a full array)
MAX_OBJECTS = 100_000  # an HDF5 file's objects visited to find its datasets
_IMAGEJ_UNITS = {
    "nm": 1e-9,
    "nanometer": 1e-9,
    "micron": 1e-6,
    "um": 1e-6,
    "µm": 1e-6,
    "\\u00B5m": 1e-6,
    "mm": 1e-3,
    "cm": 1e-2,
    "m": 1.0,
    "meter": 1.0,
}
_AS_RGB = {
    "P": "RGBA",
    "PA": "RGBA",
    "CMYK": "RGB",
    "YCbCr": "RGB",
    "LAB": "RGB",
    "HSV": "RGB",
    "RGBX": "RGB",
    "RGBa": "RGBA",
    "La": "LA",
}
_MAT_HEADER = b"MATLAB 7.3 MAT-file, written by holo; HDF5 schema 1.00 ."
_NPY_MAGIC, _ZIP_MAGIC = b"\x93NUMPY", b"PK\x03\x04"
_COMPRESSION = {
    1: "uncompressed",
    5: "LZW",
    7: "JPEG",
    8: "deflate",
    32773: "PackBits",
    32946: "deflate",
}


@dataclass
class _Scan:
    """What a file holds: the pages read ({index: float64 (H, W)}), how many it has, its
    metadata, and per-page metadata that overrides it (a Holo file's wavelength per colour)."""

    pages: dict
    count: int
    meta: dict
    per_page: dict = field(default_factory=dict)


@validate.public
def read_acquired(
    source,
    *,
    pitch=None,
    wavelength=None,
    reference_angle=None,
    reference_azimuth=None,
    page=None,
    dataset=None,
):
    """Read an acquired (real) intensity hologram from a file or an array.

    Parameters
    ----------
    source : path or array
        A PNG, TIFF, EXR, ``.npy``, HDF5 or ``.mat`` v7.3 file, or an (H, W) or (P, H, W)
        array of intensities (real; integers scaled by their bit depth). A hologram from
        memory: ``read_acquired(frame, pitch=3.45e-6, wavelength=633e-9)``.
    pitch : float, optional
        Sample spacing [m]; default the file's ``pitch_m``. One of 1 mm or more is warned
        (:class:`~holo_core.validate.UnitWarning`: it looks like millimetres).
    wavelength : float, optional
        Recording wavelength [m]; default the file's ``wavelength_m`` (for electrons, see
        :func:`holo_core.units.electron_wavelength`).
    reference_angle, reference_azimuth : float, optional
        The reference's ϑ in [0, π/2) and φ [rad]; default the file's, else 0 (unknown: the
        sideband filter then finds the carrier in the spectrum).
    page : int or 'all', optional
        Which page of a multi-page TIFF or PNG, which plane of a (P, H, W) array or dataset,
        or which colour of a Holo hologram file; 'all' gives a list of holograms, one per page
        (at most :data:`MAX_PAGES`). A source of several pages needs it.
    dataset : str, optional
        The dataset of an HDF5 or ``.mat`` file; default its only 2-D or 3-D numeric one.

    Returns
    -------
    Hologram, or a list of them for ``page='all'``.

    Raises
    ------
    InputError
        Where the file cannot be read or holds no usable intensities, or an optic is missing
        or out of range (a :class:`~holo_core.io.hologram.HologramFileError`, a subclass, for
        a damaged file), naming the file or the argument.

    Warns
    -----
    UnitWarning
        Where ``pitch`` is 1 mm or more (it looks like millimetres).

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import read_acquired
    >>> h = read_acquired(np.ones((64, 64)), pitch=3.45e-6, wavelength=633e-9)
    >>> h.intensity.shape, h.pitch, h.wavelengths
    ((1, 64, 64), 3.45e-06, (6.33e-07,))
    """
    settings = {
        "pitch_m": pitch,
        "wavelength_m": wavelength,
        "reference_angle_rad": reference_angle,
        "reference_azimuth_rad": reference_azimuth,
    }
    if page is not None and not (isinstance(page, str) and page == "all"):
        page = validate.integer("page", page, 0)
    _optics("", settings, {}, required=False)  # the given values, before any reading
    if pitch is not None:
        validate.pitch_typed("pitch", pitch)
    if isinstance(source, (str, Path)):
        name = str(source)
        scan = _read_file(Path(source), page, dataset)
    else:
        if dataset is not None:
            raise InputError(
                "dataset names a dataset of an HDF5 or .mat file; an array source has none"
            )
        name = "array"
        scan = _array_scan(name, _intensities(name, source), page)
    holograms = []
    for index in _wanted(name, scan.count, page):
        optics = _optics(name, settings, {**scan.meta, **scan.per_page.get(index, {})})
        h = Hologram(
            intensity=scan.pages[index][None].astype(np.float32),
            wavelengths=(optics["wavelength_m"],),
            pitch=optics["pitch_m"],
            reference_angle=optics["reference_angle_rad"],
            reference_azimuth=optics["reference_azimuth_rad"],
            reference_amplitudes=(scan.per_page.get(index, {}).get("reference_amplitude", 1.0),),
        )
        check_pixels(name, h)
        holograms.append(h)
    return holograms if page == "all" else holograms[0]


def write_acquired(path, hologram: Hologram, *, colour: int = 0) -> Path:
    """Write one colour of an intensity hologram in the format the path's suffix asks for.

    The hologram's pitch, wavelength and reference angles are written as the metadata
    :func:`read_acquired` reads.

    Parameters
    ----------
    path : str or Path
        ``.npy`` (and ``<name>.json``), ``.h5``/``.hdf5`` (dataset ``intensity``,
        attributes), ``.mat`` v7.3 (variable ``intensity`` and scalar ones), ``.tif``/``.tiff``
        (float32), ``.png`` (16-bit of intensity/max, the max as ``intensity_scale``: 1/65535
        of the peak), ``.exr`` (the hologram file,
        :func:`~holo_core.io.hologram.write_hologram`: every colour).
    hologram : Hologram
        An intensity hologram.
    colour : int
        Index into its wavelengths.

    Returns
    -------
    Path
        The path written; the file is written atomically.

    Raises
    ------
    InputError
        For any other suffix, or where ``hologram`` is not an intensity Hologram.

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np
    >>> from holo_core import Hologram, read_acquired, write_acquired
    >>> h = Hologram(intensity=np.ones((1, 64, 64), np.float32), wavelengths=(633e-9,),
    ...              pitch=2e-6)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     back = read_acquired(write_acquired(os.path.join(folder, "scan.npy"), h))
    >>> back.pitch, back.wavelengths
    (2e-06, (6.33e-07,))
    """
    if not isinstance(hologram, Hologram) or getattr(hologram, "intensity", None) is None:
        raise InputError(f"hologram must be an intensity Hologram; got {type(hologram).__name__}")
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        raise InputError(
            f"{path}: write_acquired writes {', '.join(SUFFIXES)}; the suffix "
            f"{suffix or '(none)'!r} names none of them"
        )
    if suffix == ".exr":
        return write_hologram(path, hologram)
    c = validate.index("colour", colour, len(hologram.wavelengths))
    check_writable(path, suffix)
    data = np.ascontiguousarray(hologram.intensity[c], np.float32)
    meta = {
        "pitch_m": float(hologram.pitch),
        "wavelength_m": float(hologram.wavelengths[c]),
        "reference_angle_rad": float(hologram.reference_angle),
        "reference_azimuth_rad": float(hologram.reference_azimuth),
    }
    targets = [path] + ([Path(path).with_suffix(".json")] if suffix == ".npy" else [])
    with atomic_paths(*targets) as temps:
        if suffix == ".npy":
            with open(temps[0], "wb") as f:
                np.save(f, data)
            Path(temps[1]).write_text(json.dumps(meta, indent=1))
        elif suffix in HDF5:
            _write_hdf5(temps[0], data, meta, matlab=suffix == ".mat")
        else:
            _write_image(temps[0], suffix, data, meta)
    return Path(path)


# --- reading ---------------------------------------------------------------------------------


def _read_file(path: Path, page, dataset) -> _Scan:
    """The pages ``page`` asks for of a file, its page count and metadata."""
    if not path.is_file():
        raise HologramFileError(f"{path}: no such file")
    suffix = path.suffix.lower()
    if dataset is not None and suffix not in HDF5:
        raise InputError(f"dataset names a dataset of an HDF5 or .mat file; {path} is not one")
    if suffix == ".exr":
        return _read_exr(path, page)
    if suffix == ".npy":
        return _read_npy(path, page)
    if suffix in HDF5:
        return _read_hdf5(path, dataset, page)
    return _read_image(path, page)


def _wanted(name: str, count: int, page) -> list[int]:
    """The page indices ``page`` asks for (None: the only one; an index; 'all'), checked
    against ``count`` before anything is read."""
    if page is None and count > 1:
        raise InputError(
            f"{name}: holds {count} pages; pass page=i (0 to {count - 1}) for one "
            f"of them or page='all' for every one"
        )
    if isinstance(page, int) and page >= count:
        raise InputError(
            f"page must be in [0, {count - 1}] for {name} ({count} page"
            f"{'s' if count > 1 else ''}); got {page}"
        )
    if page == "all" and count > MAX_PAGES:
        raise InputError(
            f"{name}: holds {count} pages; page='all' returns at most {MAX_PAGES} "
            f"holograms: pass page=i (0 to {count - 1})"
        )
    return list(range(count)) if page in (None, "all") else [page]


def _array_scan(name: str, a: np.ndarray, page) -> _Scan:
    """The pages of a 2-D or 3-D (pages, H, W) array, scaled to intensities (only those
    asked for)."""
    if a.ndim not in (2, 3):
        raise HologramFileError(
            f"{name}: holds a {a.ndim}-D array; an intensity hologram is "
            f"2-D (H, W), or 3-D (pages, H, W)"
        )
    stack = a[None] if a.ndim == 2 else a
    pages = {i: _scaled(name, np.asarray(stack[i])) for i in _wanted(name, len(stack), page)}
    return _Scan(pages, len(stack), {})


def _read_exr(path: Path, page) -> _Scan:
    """A Holo hologram file's intensity (a page per colour, each with its wavelength), or a
    scan's grey (Y, R/G/B, or its single channel)."""
    try:
        header, chans = read_exr(path, what="scan")
    except HologramFileError:
        raise
    except ValueError as e:
        raise HologramFileError(str(e)) from None
    if "holo" in header:  # written by write_hologram (or write_acquired's .exr)
        h = read_hologram(path)
        if h.intensity is None:
            raise HologramFileError(
                f"{path}: a complex hologram (its samples are the object "
                f"wave already); read it with read_hologram"
            )
        count = len(h.wavelengths)
        per_page = {
            c: {
                "wavelength_m": h.wavelengths[c],
                "reference_amplitude": (h.reference_amplitudes or (1.0,) * count)[c],
            }
            for c in range(count)
        }
        meta = {
            "pitch_m": h.pitch,
            "reference_angle_rad": h.reference_angle,
            "reference_azimuth_rad": h.reference_azimuth,
        }
        pages = {c: h.intensity[c].astype(np.float64) for c in _wanted(str(path), count, page)}
        return _Scan(pages, count, meta, per_page)
    if "Y" in chans:
        grey = chans["Y"].astype(np.float64)
    elif any(n in chans for n in ("R", "G", "B")):
        grey = np.mean([chans[n] for n in ("R", "G", "B") if n in chans], axis=0, dtype=np.float64)
    elif len(chans) == 1:
        grey = next(iter(chans.values())).astype(np.float64)
    else:
        raise HologramFileError(
            f"{path}: an EXR scan needs a Y channel, R/G/B channels or a "
            f"single channel; it has {', '.join(sorted(chans))[:200]}"
        )
    return _Scan(dict.fromkeys(_wanted(str(path), 1, page), grey), 1, {})


def _read_image(path: Path, page) -> _Scan:
    """The pages of a PNG or TIFF (the ones asked for), their count and the metadata."""
    from PIL import Image

    try:
        with warnings.catch_warnings():  # the memory check below is the limit, not PIL's guess
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            im = Image.open(path)
        with im:
            w, h = im.size
            planes = _planes(path, im)
            frames = _frame_count(im)
            count = frames * planes
            wanted = _wanted(str(path), count, page)
            memory.check_host(
                f"{path} (scan, {w}x{h} pixels, {len(wanted)} page(s))",
                8.0 * 4 * w * h * len(wanted),
            )
            pages = {}
            for i in wanted:
                im.seek(i // planes)
                pages[i] = (
                    _grey(path, im)
                    if planes == 1
                    else _scaled(str(path), _plane(path, im, i % planes))
                )
            meta = _image_meta(im)  # after the pixels: a PNG's text chunks load the image
    except InputError:
        raise
    except Exception as e:  # noqa: BLE001 -- PIL's errors for damaged files vary by format
        raise HologramFileError(
            f"{path}: not a readable PNG/TIFF image ({type(e).__name__}: {e})"[:400]
        ) from None
    scale = meta.pop("intensity_scale", None)
    if scale is not None:
        scale = validate.positive(f"{path}: metadata intensity_scale", scale)
        pages = {i: p * scale for i, p in pages.items()}
    return _Scan(pages, count, meta)


def _frame_count(im) -> int:
    """A PNG's or TIFF's frames, counted one by one up to :data:`MAX_PAGES` + 1 only (a chain
    of a million pages is not walked; Pillow's n_frames after a failed seek is not trusted)."""
    if not getattr(im, "is_animated", False):
        return 1
    count = MAX_PAGES + 1  # at least: more than page='all' takes, and page=i still works
    for i in range(1, MAX_PAGES + 1):
        try:
            im.seek(i)
        except EOFError:
            count = i
            break
    im.seek(0)
    return count


def _grey(path: Path, im) -> np.ndarray:
    """One loaded page as float64 intensities in its bit depth's scale (16-bit colour keeps
    its 16 bits: :func:`_wide`)."""
    raw = _rawmode(im)  # before loading, which clears the tiles
    im.load()
    if im.mode in _AS_RGB:
        im = im.convert(_AS_RGB[im.mode])
    a = (
        _wide(im, raw)
        if raw.endswith((";16B", ";16L", ";16N")) and im.mode in ("RGB", "RGBA", "LA")
        else np.asarray(im)
    )
    if im.mode in ("LA", "RGBA"):
        a = a[..., :-1]
    a = _scaled(str(path), a)
    return a.mean(axis=2) if a.ndim == 3 else a


def _rawmode(im) -> str:
    """The raw mode of the current frame's first tile ('RGB;16B' for a 16-bit RGB PNG), or ''."""
    tiles = getattr(im, "tile", None) or []
    if not tiles:
        return ""
    args = tiles[0].args
    return args if isinstance(args, str) else str(args[0]) if args else ""


_OTHER_END = {"B": "L", "L": "B", "N": "B" if sys.byteorder == "little" else "L"}


def _wide(im, raw: str) -> np.ndarray:
    """A 16-bit multi-channel frame as uint16. Pillow keeps 8 bits of each sample (the high
    byte, by the tile's raw mode 'RGB;16B'); decoding the same tiles a second time with the
    other byte order's raw mode gives the low bytes, and the two make the 16 bits."""
    from PIL import Image

    other = raw[:-1] + _OTHER_END[raw[-1]]
    low = Image.open(im.filename)
    with low:
        low.seek(im.tell())
        low.tile = [
            t._replace(args=other if isinstance(t.args, str) else (other, *t.args[1:]))
            for t in low.tile
        ]
        try:
            low.load()
        except ValueError:  # no decoder for that byte order (16-bit grey with alpha)
            raise HologramFileError(
                f"{im.filename}: 16-bit samples laid out as {raw}, of which "
                f"Pillow reads only 8 bits a sample: not read (save it as "
                f"16-bit grey, RGB or RGBA)"
            ) from None
        return np.asarray(im).astype(np.uint16) * 256 + np.asarray(low)


def _planes(path: Path, im) -> int:
    """How many pages each frame gives: a TIFF's samples per pixel where they are stored as
    separate planes (PlanarConfiguration 2), else 1."""
    tags = getattr(im, "tag_v2", None)
    if tags is None or tags.get(284) != 2:
        return 1
    return int(tags.get(277, 1))


def _plane(path: Path, im, k: int) -> np.ndarray:
    """Plane ``k`` of the current frame of a planar TIFF, read from its strips as the bytes
    are (uncompressed), or through Pillow's colour bands (8-bit compressed); other layouts
    are refused, naming them."""
    tags = im.tag_v2
    bits = tuple(tags.get(258, (8,)))
    compression = int(tags.get(259, 1))
    samples = int(tags.get(277, 1))
    w, h = im.size
    layout = (
        f"{samples} {bits[0]}-bit samples per pixel stored as separate planes, "
        f"{_COMPRESSION.get(compression, f'compression {compression}')}"
    )
    if (
        compression == 1
        and 273 in tags
        and 324 not in tags
        and len(set(bits)) == 1
        and bits[0] in (8, 16, 32, 64)
    ):
        return _strip_plane(path, tags, k, (h, w), bits[0], layout)
    if bits[0] == 8 and im.mode in ("RGB", "RGBA") and samples == len(im.mode):
        im.load()
        return np.asarray(im)[..., k]
    raise HologramFileError(
        f"{path}: a TIFF of {layout}: not read (save it uncompressed, or one page per frame)"
    )


def _strip_plane(path: Path, tags, k: int, shape, bits: int, layout: str) -> np.ndarray:
    """Plane ``k`` of an uncompressed planar TIFF from its strips, every offset and count
    checked against the file's size before it is read."""
    rows, cols = shape
    fmt = {1: "u", 2: "i", 3: "f"}.get(int(tags.get(339, (1,))[0]), "u")
    with open(path, "rb") as f:
        order = "<" if f.read(2) == b"II" else ">"
        size = f.seek(0, 2)
        dtype = np.dtype(f"{order}{fmt}{bits // 8}")
        per_strip = int(tags.get(278, rows))
        offsets, counts = tuple(tags[273]), tuple(tags.get(279, ()))
        strips = -(-rows // max(per_strip, 1))
        mine = range(k * strips, (k + 1) * strips)
        if len(offsets) < (k + 1) * strips or len(counts) != len(offsets):
            raise HologramFileError(
                f"{path}: a TIFF of {layout} whose strips do not cover "
                f"its planes ({len(offsets)} strips for {strips} a plane)"
            )
        chunks = []
        for s in mine:
            if offsets[s] + counts[s] > size:
                raise HologramFileError(f"{path}: strip {s} reaches beyond the file's {size} bytes")
            f.seek(offsets[s])
            chunks.append(f.read(counts[s]))
    data = np.frombuffer(b"".join(chunks), dtype)
    if data.size < rows * cols:
        raise HologramFileError(
            f"{path}: plane {k} holds {data.size} samples, {rows}x{cols} needed"
        )
    return data[: rows * cols].reshape(rows, cols).astype(dtype.newbyteorder("="))


def _scaled(name: str, a: np.ndarray) -> np.ndarray:
    """Integers to [0, 1] by their bit depth; floats and booleans as they are, in float64."""
    if a.dtype.kind in "iu":
        if a.size and a.min() < 0:
            raise HologramFileError(
                f"{name}: a scan of signed integers holds negative values; intensities must be >= 0"
            )
        top = int(a.max()) if a.size else 0
        scale = (
            255
            if a.dtype.itemsize == 1
            else 65535
            if a.dtype.itemsize == 2
            else next((s for s in (255, 65535, 2**32 - 1) if top <= s), None)
        )
        if scale is None:
            raise HologramFileError(f"{name}: integer intensities up to {top} exceed 32 bits")
        return a.astype(np.float64) / scale
    if a.dtype.kind == "c":
        raise HologramFileError(
            f"{name}: holds complex values; an acquired hologram is an intensity (real, >= 0)"
        )
    if a.dtype.kind not in "fb":
        raise HologramFileError(f"{name}: holds {a.dtype} values, not numbers")
    a = a.astype(np.float64)
    if a.size and not (np.isfinite(a).all() and np.abs(a).max() <= np.finfo(np.float32).max):
        raise HologramFileError(
            f"{name}: the intensity holds NaN, infinite or values beyond "
            f"float32's range (it must be finite)"
        )
    return a


def _image_meta(im) -> dict:
    """The optics keys of a PNG's text chunks or a TIFF's description (JSON or ImageJ's
    lines), ImageJ's calibrated resolution as the pitch, and a PNG's intensity_scale."""
    meta = {}
    text = dict(getattr(im, "text", {}) or {})  # PNG text chunks
    tags = getattr(im, "tag_v2", None)
    if tags is not None and 270 in tags:
        text.update(_description(f"{im.filename}: ImageDescription", str(tags[270])))
        unit = _IMAGEJ_UNITS.get(str(text.get("unit", "")).strip().lower())
        if str(tags[270]).startswith("ImageJ=") and unit and 282 in tags:
            pitches = {
                1 / float(tags[t]) * unit for t in (282, 283) if t in tags and float(tags[t]) > 0
            }
            if len(pitches) == 1:
                meta["pitch_m"] = pitches.pop()
            elif pitches:
                raise HologramFileError(
                    f"{im.filename}: its pixels are {sorted(pitches)} m "
                    f"apart in x and y; a hologram has one pitch"
                )
    for key in (*KEYS, "intensity_scale"):
        if key in text:
            meta[key] = text[key]
    return meta


def _description(name: str, text: str) -> dict:
    """The key/value pairs of a TIFF description: a JSON object (bounded: :mod:`jsonfile`),
    or ImageJ's ``key=value`` lines; other text holds none."""
    text = text.strip()
    if text.startswith("{"):
        value = jsonfile.loads(text, name, error=HologramFileError)
        return value if isinstance(value, dict) else {}
    return dict(line.split("=", 1) for line in text.splitlines() if "=" in line)


def _read_npy(path: Path, page) -> _Scan:
    """The pages of a ``.npy`` array (memory-mapped: only the pages asked for are read) and
    ``<name>.json`` beside it."""
    with open(path, "rb") as f:
        magic = f.read(6)
    if magic.startswith(_ZIP_MAGIC):
        raise HologramFileError(
            f"{path}: a zip archive (.npz, several arrays) named .npy; "
            f"save the hologram with numpy.save, or pass the array itself"
        )
    if magic != _NPY_MAGIC:
        raise HologramFileError(f"{path}: not a .npy array (it starts with {magic!r})")
    try:
        a = np.load(path, mmap_mode="r", allow_pickle=False)
    except Exception as e:  # noqa: BLE001 -- a damaged header: ValueError, EOFError, OSError
        raise HologramFileError(
            f"{path}: not a readable .npy array ({type(e).__name__}: {e})"[:400]
        ) from None
    meta = {}
    side = path.with_suffix(".json")
    if side.exists():
        meta = jsonfile.load(side, error=HologramFileError)
        if not isinstance(meta, dict):
            raise HologramFileError(f"{side}: must hold a JSON object of {', '.join(KEYS)}")
    if a.ndim in (2, 3):
        plane = a.shape[-2] * a.shape[-1]
        wanted = _wanted(str(path), 1 if a.ndim == 2 else a.shape[0], page)
        memory.check_host(
            f"{path} ({'x'.join(map(str, a.shape))} array, {len(wanted)} page(s))",
            2.0 * 8 * plane * len(wanted),
        )
    scan = _array_scan(str(path), a, page)
    scan.meta = meta
    return scan


def _h5py(path):
    try:
        import h5py
    except ImportError:
        raise InputError(
            f"{path}: HDF5 and .mat v7.3 files are read through h5py; install "
            f"it (pip install 'holo[lab]')"
        ) from None
    return h5py


def _read_hdf5(path: Path, dataset, page) -> _Scan:
    """A dataset of an HDF5 or MATLAB v7.3 file: the pages asked for and the metadata; a
    damaged file's errors name it."""
    h5py = _h5py(path)
    with open(path, "rb") as f:
        head = f.read(128)
    if head.startswith(b"MATLAB 5.0") or (path.suffix.lower() == ".mat" and not h5py.is_hdf5(path)):
        raise HologramFileError(
            f"{path}: a MATLAB v5 (or older) MAT-file; save it in MATLAB "
            f"with save(name, ..., '-v7.3') (HDF5), which this reads"
        )
    try:
        with h5py.File(path, "r") as f:
            return _hdf5_scan(h5py, path, f, dataset, page)
    except InputError:
        raise
    except Exception as e:  # noqa: BLE001 -- HDF5's errors for damaged files: OSError,
        # RuntimeError, KeyError, ValueError, TypeError, by where the damage lies
        raise HologramFileError(
            f"{path}: not a readable HDF5 file ({type(e).__name__}: {e})"[:400]
        ) from None


def _hdf5_scan(h5py, path: Path, f, dataset, page) -> _Scan:
    name = _dataset_name(h5py, path, f, dataset)
    d = _local(path, f[name])
    where = f"{path}:{name}"
    if d.chunks is not None:  # HDF5 allocates a whole chunk to read any of it
        memory.check_host(
            f"{where} (chunks of {'x'.join(map(str, d.chunks))})",
            2.0 * d.dtype.itemsize * math.prod(d.chunks),
        )
    matlab = "MATLAB_class" in d.attrs
    if d.ndim not in (2, 3):
        raise HologramFileError(
            f"{where}: holds a {d.ndim}-D array; an intensity hologram is "
            f"2-D (H, W), or 3-D (pages, H, W)"
        )
    count = 1 if d.ndim == 2 else d.shape[0]
    wanted = _wanted(where, count, page)
    plane = math.prod(d.shape) // count
    memory.check_host(
        f"{where} ({'x'.join(map(str, d.shape))}, {len(wanted)} page(s))",
        2.0 * 8 * plane * len(wanted),
    )
    pages = {}
    for i in wanted:
        a = d[()] if d.ndim == 2 else d[i]
        if matlab:  # MATLAB stores column-major: an H x W (x P) array is (P x) W x H in HDF5
            a = np.transpose(a)
        pages[i] = _scaled(where, np.asarray(a))
    return _Scan(pages, count, _hdf5_meta(h5py, path, f, d))


def _dataset_name(h5py, path: Path, f, dataset) -> str:
    """The dataset to read: ``dataset`` when it names one, else the file's only 2-D or 3-D
    numeric dataset (found among at most :data:`MAX_OBJECTS` objects, through hard links)."""
    candidates, seen = [], [0]

    def visit(name, obj):
        seen[0] += 1
        if seen[0] > MAX_OBJECTS:
            return True  # stops the walk
        if (
            isinstance(obj, h5py.Dataset)
            and obj.ndim in (2, 3)
            and min(obj.shape) > 1
            and obj.dtype.kind in "iufb"
            and "original_metadata" not in name.split("/")
        ):
            candidates.append(name)
        return None

    f.visititems(visit)
    if seen[0] > MAX_OBJECTS and dataset is None:
        raise InputError(
            f"{path}: holds more than {MAX_OBJECTS} objects; pass dataset= the one to read"
        )
    if dataset is None:
        if len(candidates) != 1:
            raise InputError(
                f"{path}: holds {len(candidates)} 2-D or 3-D numeric datasets; "
                f"pass dataset= one of {', '.join(candidates[:10]) or '(none)'}"
            )
        return candidates[0]
    if not isinstance(dataset, str) or not _inside(h5py, path, f, dataset):
        raise InputError(
            f"dataset must name a dataset of {path}: one of "
            f"{', '.join(candidates[:10]) or '(none)'}; got {dataset!r}"[:400]
        )
    return dataset.strip("/")


def _inside(h5py, path: Path, f, name: str) -> bool:
    """Whether ``name`` is a dataset reached through links inside the file; an external
    link on the way is refused (naming it) before anything of another file is opened."""
    parts = [p for p in name.strip("/").split("/") if p]
    for i in range(1, len(parts) + 1):
        step = "/".join(parts[:i])
        try:
            link = f.get(step, getlink=True)
        except (KeyError, ValueError, TypeError):
            return False
        if link is None:
            return False
        if isinstance(link, h5py.ExternalLink):
            raise HologramFileError(
                f"{path}:{step} is an external link to "
                f"{link.filename}:{link.path}; refused: nothing is read "
                f"from outside the file named"[:400]
            )
    return bool(parts) and isinstance(f.get("/".join(parts)), h5py.Dataset)


def _local(path: Path, d):
    """The dataset ``d``, refused when its samples live in another file (external storage, a
    virtual dataset): nothing is read from outside the file the user named."""
    if d.external:
        files = ", ".join(sorted({str(e[0]) for e in d.external}))
        raise HologramFileError(
            f"{path}:{d.name.lstrip('/')} stores its samples in another "
            f"file ({files}); refused: nothing is read from outside the "
            f"file named"[:400]
        )
    if d.is_virtual:
        files = ", ".join(sorted({m.file_name for m in d.virtual_sources()}))
        raise HologramFileError(
            f"{path}:{d.name.lstrip('/')} is a virtual dataset mapping "
            f"{files}; refused: nothing is read from outside the file "
            f"named"[:400]
        )
    return d


def _hdf5_meta(h5py, path: Path, f, d) -> dict:
    """The optics of the dataset ``d``: its attributes, then each group's above it, MATLAB's
    scalar variables, and a HyperSpy file's calibration."""
    meta = {}
    for node in _parents(f, d.name):  # the dataset's own attributes win
        for key in KEYS:
            if key in node.attrs and key not in meta:
                meta[key] = _scalar(node.attrs[key])
    for key in KEYS:  # MATLAB's scalar variables, in this file only
        if (
            key not in meta
            and isinstance(f.get(key, getlink=True), h5py.HardLink)
            and isinstance(f[key], h5py.Dataset)
            and f[key].size == 1
        ):
            meta[key] = _scalar(f[key][()])
    if str(_scalar(f.attrs.get("file_format", ""))) == "HyperSpy":
        meta = {**_hyperspy_meta(h5py, path, d), **meta}
    return meta


def _hyperspy_meta(h5py, path: Path, d) -> dict:
    """A HyperSpy signal's pitch (its two signal axes' scale and units) and, for a TEM, the
    electrons' wavelength from its beam energy [kV]."""
    group, meta = d.parent, {}
    scales = []
    for k in range(d.ndim):
        axis = group.get(f"axis-{k}")
        if isinstance(axis, h5py.Group) and not _scalar(axis.attrs.get("navigate", False)):
            unit = str(_scalar(axis.attrs.get("units", ""))).strip()
            factor = _IMAGEJ_UNITS.get(unit.lower()) or units.METRES.get(unit)
            if factor and "scale" in axis.attrs:
                scales.append(float(_scalar(axis.attrs["scale"])) * factor)
    if len(scales) == 2 and math.isclose(*scales, rel_tol=1e-9):
        meta["pitch_m"] = scales[0]
    tem = group.get("metadata/Acquisition_instrument/TEM")
    if isinstance(tem, h5py.Group) and "beam_energy" in tem.attrs:
        energy = float(_scalar(tem.attrs["beam_energy"]))
        if math.isfinite(energy) and energy > 0:
            meta["wavelength_m"] = units.electron_wavelength(energy * 1e3)
    return meta


def _parents(f, name: str):
    parts = name.strip("/").split("/")
    yield f[name]
    for i in range(len(parts) - 1, -1, -1):
        yield f["/" + "/".join(parts[:i])]


def _scalar(value):
    a = np.asarray(value)
    if a.dtype.kind in "SO":
        return a.reshape(-1)[0].decode() if isinstance(a.reshape(-1)[0], bytes) else a.item()
    return a.reshape(-1)[0].item() if a.size == 1 else value


def _intensities(name: str, a) -> np.ndarray:
    try:
        arr = np.asarray(a)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.ndim not in (2, 3) or arr.dtype.kind not in "iufbc" or not arr.size:
        shape = None if arr is None else arr.shape
        raise InputError(
            f"source must be a path or an (H, W) or (P, H, W) array of "
            f"intensities; got {type(a).__name__} of shape {shape}"
        )
    return arr


def _optics(name: str, given: dict, meta: dict, required=True) -> dict:
    """The optics: each given value, else the file's, checked (units guarded); pitch and
    wavelength must be found when ``required``."""
    out = {}
    for key in KEYS:
        arg = key.rsplit("_", 1)[0]  # the argument's name: pitch, wavelength, ...
        value, stored = given[key], meta.get(key)
        if value is not None and stored is not None and not _same(value, stored):
            log.warning(
                "%s: %s given as %r, the file says %r; using the given value",
                name,
                arg,
                value,
                stored,
            )
        if value is None and stored is not None:
            value, arg = stored, f"{name}: metadata {key}"
        if value is None and key in ("pitch_m", "wavelength_m"):
            if not required:
                continue
            raise InputError(
                f"{arg} must be given [m]: {name} holds no {key} (pass "
                f"{arg}=..., or store {key} in its metadata)"
            )
        if key == "pitch_m":
            out[key] = validate.pitch(arg, value)
        elif key == "wavelength_m":
            out[key] = validate.wavelength(arg, value)
        else:
            out[key] = 0.0 if value is None else validate.finite(arg, value, "rad")
        if key == "reference_angle_rad" and not 0 <= out[key] < math.pi / 2:
            raise InputError(f"{arg} must be in [0, π/2) rad; got {shown(out[key])}")
    return out


def _same(a, b) -> bool:
    try:
        return math.isclose(float(a), float(b), rel_tol=1e-9)
    except (TypeError, ValueError):
        return False


# --- writing ---------------------------------------------------------------------------------


def _write_hdf5(filename, data: np.ndarray, meta: dict, matlab: bool) -> None:
    h5py = _h5py(filename)
    with h5py.File(filename, "w", userblock_size=512 if matlab else 0) as f:
        if matlab:  # column-major, as MATLAB reads it; metadata as scalar variables
            d = f.create_dataset("intensity", data=data.T.astype(np.float64))
            d.attrs["MATLAB_class"] = np.bytes_("double")
            for key, value in meta.items():
                s = f.create_dataset(key, data=np.array([[value]], np.float64))
                s.attrs["MATLAB_class"] = np.bytes_("double")
        else:
            d = f.create_dataset("intensity", data=data)
            for key, value in meta.items():
                d.attrs[key] = value
    if matlab:
        with open(filename, "r+b") as f:
            f.write(_MAT_HEADER.ljust(116, b" ") + b"\0" * 8 + b"\x00\x02IM")


def _write_image(filename, suffix: str, data: np.ndarray, meta: dict) -> None:
    from PIL import Image
    from PIL.PngImagePlugin import PngInfo

    if suffix == ".png":
        peak = float(data.max())
        scale = peak if peak > 0 else 1.0
        info = PngInfo()
        for key, value in {**meta, "intensity_scale": scale}.items():
            info.add_text(key, repr(float(value)))
        grey = np.round(np.clip(data / scale, 0, 1) * 65535).astype(np.uint16)
        Image.fromarray(grey).save(filename, "PNG", pnginfo=info)
    else:
        Image.fromarray(data, "F").save(filename, "TIFF", description=json.dumps(meta))
