"""Acquired holograms in and out: camera scans and laboratory arrays.

In (:func:`import_acquired`): PNG (8- and 16-bit), TIFF (every page, or the one asked for),
OpenEXR, NumPy ``.npy``, HDF5 (``.h5``, ``.hdf5``) and MATLAB ``.mat`` v7.3 (HDF5 inside; read
through h5py, the optional extra ``lab``), or an array in memory. Out (:func:`write_acquired`):
the format the file name's suffix asks for, or an error.

Pitch, wavelength and the reference's angles are given, or read from the file's metadata under
these keys (SI units, as the hologram file's metadata names them):

``pitch_m``, ``wavelength_m``, ``reference_angle_rad``, ``reference_azimuth_rad``

- TIFF: the ImageDescription as a JSON object, or ImageJ's ``key=value`` lines; ImageJ's
  ``unit=micron`` (nm, mm, cm, m) with the X/Y resolution tags also gives the pitch;
- PNG: text chunks of those names;
- ``.npy``: a JSON object in ``<name>.json`` beside it;
- HDF5: attributes of the dataset, then of each group above it up to the file;
- ``.mat``: scalar variables of those names (and attributes, as HDF5).

A value given as an argument wins over the file's (a difference is logged). Every value is
checked as a typed one is (units guarded: a ``pitch_m`` of 8 is refused as micrometres).

Intensities: integers are scaled to [0, 1] by their bit depth (8, 16; 32-bit by the smallest
of 2⁸−1, 2¹⁶−1, 2³²−1 that holds them), colour is averaged to grey and alpha dropped, floats are
kept; a PNG this module wrote carries the scale that restores its floats (``intensity_scale``).
"""

from __future__ import annotations

import json
import logging
import math
import warnings
from pathlib import Path

import numpy as np

from .. import memory, validate
from ..scene.hologram import Hologram
from ..validate import InputError
from .hologram import HologramFileError, check_pixels, write_hologram
from .image import atomic_paths, check_writable, read_exr

log = logging.getLogger(__name__)

KEYS = ("pitch_m", "wavelength_m", "reference_angle_rad", "reference_azimuth_rad")
IMAGES = (".png", ".tif", ".tiff")
HDF5 = (".h5", ".hdf5", ".mat")
SUFFIXES = (*IMAGES, ".exr", ".npy", *HDF5)
_IMAGEJ_UNITS = {"nm": 1e-9, "nanometer": 1e-9, "micron": 1e-6, "um": 1e-6, "µm": 1e-6,
                 "\\u00B5m": 1e-6, "mm": 1e-3, "cm": 1e-2, "m": 1.0, "meter": 1.0}
_AS_RGB = {"P": "RGBA", "PA": "RGBA", "CMYK": "RGB", "YCbCr": "RGB", "LAB": "RGB",
           "HSV": "RGB", "RGBX": "RGB", "RGBa": "RGBA", "La": "LA"}
_MAT_HEADER = b"MATLAB 7.3 MAT-file, written by holo; HDF5 schema 1.00 ."


def import_acquired(source, *, pitch=None, wavelength=None, reference_angle=None,
                    reference_azimuth=None, page=None, dataset=None):
    """An acquired (real) intensity hologram from a file or an array.

    Parameters
    ----------
    source : path or array
        A PNG, TIFF, EXR, ``.npy``, HDF5 or ``.mat`` v7.3 file, or an (H, W) or (P, H, W)
        array of intensities (real; integers scaled by their bit depth). A hologram from
        memory: ``import_acquired(frame, pitch=3.45e-6, wavelength=633e-9)``.
    pitch : float, optional
        Sample spacing [m]; default the file's ``pitch_m``.
    wavelength : float, optional
        Recording wavelength [m]; default the file's ``wavelength_m``.
    reference_angle, reference_azimuth : float, optional
        The reference's ϑ in [0, π/2) and φ [rad]; default the file's, else 0.
    page : int or 'all', optional
        Which page of a multi-page TIFF or which plane of a (P, H, W) array or dataset; 'all'
        gives a list of holograms, one per page. A source of several pages needs it.
    dataset : str, optional
        The dataset of an HDF5 or ``.mat`` file; default its only 2-D or 3-D numeric one.

    Returns
    -------
    Hologram, or a list of them for ``page='all'``.
    """
    settings = {"pitch_m": pitch, "wavelength_m": wavelength,
                "reference_angle_rad": reference_angle, "reference_azimuth_rad": reference_azimuth}
    if page is not None and not (isinstance(page, str) and page == "all"):
        page = validate.integer("page", page, 0)
    _optics("", settings, {}, required=False)  # the given values, before any reading
    if isinstance(source, (str, Path)):
        path = Path(source)
        name = str(path)
        pages, count, meta = _read_file(path, page, dataset)
    else:
        if dataset is not None:
            raise InputError("dataset names a dataset of an HDF5 or .mat file; an array "
                             "source has none")
        name, meta = "array", {}
        pages, count = _pages(name, _intensities(name, source))
    optics = _optics(name, settings, meta)
    chosen = _choose(name, pages, count, page)
    holograms = []
    for p in chosen:
        h = Hologram(intensity=p[None].astype(np.float32), wavelengths=(optics["wavelength_m"],),
                     pitch=optics["pitch_m"], reference_angle=optics["reference_angle_rad"],
                     reference_azimuth=optics["reference_azimuth_rad"],
                     reference_amplitudes=(1.0,))
        check_pixels(name, h)
        holograms.append(h)
    return holograms if page == "all" else holograms[0]


def write_acquired(path, hologram: Hologram, *, colour: int = 0) -> Path:
    """Write one colour of ``hologram``'s intensity in the format ``path``'s suffix asks for,
    with its pitch, wavelength and reference angles as the metadata :func:`import_acquired`
    reads: ``.npy`` (and ``<name>.json``), ``.h5``/``.hdf5`` (dataset ``intensity``, attributes),
    ``.mat`` v7.3 (variable ``intensity`` and scalar ones), ``.tif``/``.tiff`` (float32),
    ``.png`` (16-bit of intensity/max, the max as ``intensity_scale``: 1/65535 of the peak),
    ``.exr`` (the hologram file, :func:`~holo_core.io.hologram.write_hologram`: every colour).
    Any other suffix is an :class:`InputError`; the file is written atomically."""
    if not isinstance(hologram, Hologram) or getattr(hologram, "intensity", None) is None:
        raise InputError(f"hologram must be an intensity Hologram; got "
                         f"{type(hologram).__name__}")
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        raise InputError(f"{path}: write_acquired writes {', '.join(SUFFIXES)}; the suffix "
                         f"{suffix or '(none)'!r} names none of them")
    if suffix == ".exr":
        return write_hologram(path, hologram)
    c = validate.index("colour", colour, len(hologram.wavelengths))
    check_writable(path, suffix)
    data = np.ascontiguousarray(hologram.intensity[c], np.float32)
    meta = {"pitch_m": float(hologram.pitch), "wavelength_m": float(hologram.wavelengths[c]),
            "reference_angle_rad": float(hologram.reference_angle),
            "reference_azimuth_rad": float(hologram.reference_azimuth)}
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

def _read_file(path: Path, page, dataset):
    """({page index: float64 page}, page count, metadata dict) of a file."""
    if not path.is_file():
        raise HologramFileError(f"{path}: no such file")
    suffix = path.suffix.lower()
    if dataset is not None and suffix not in HDF5:
        raise InputError(f"dataset names a dataset of an HDF5 or .mat file; {path} is not one")
    if suffix == ".exr":
        return {0: _exr_grey(path)}, 1, {}
    if suffix == ".npy":
        return _read_npy(path)
    if suffix in HDF5:
        return _read_hdf5(path, dataset)
    return _read_image(path, page)


def _exr_grey(path: Path) -> np.ndarray:
    try:
        _, chans = read_exr(path, what="scan")
    except HologramFileError:
        raise
    except ValueError as e:
        raise HologramFileError(str(e)) from None
    if "Y" in chans:
        return chans["Y"].astype(np.float64)
    rgb = [chans[n] for n in ("R", "G", "B") if n in chans]
    if rgb:
        return np.mean(rgb, axis=0, dtype=np.float64)
    if len(chans) == 1:
        return next(iter(chans.values())).astype(np.float64)
    raise HologramFileError(f"{path}: an EXR scan needs a Y channel, R/G/B channels or a "
                            f"single channel; it has {', '.join(sorted(chans))[:200]}")


def _read_image(path: Path, page):
    """The pages of a PNG or TIFF (all of them, or only ``page``), their count and the
    metadata."""
    from PIL import Image
    try:
        with warnings.catch_warnings():  # the memory check below is the limit, not PIL's guess
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            im = Image.open(path)
        with im:
            w, h = im.size
            count = getattr(im, "n_frames", 1)
            wanted = range(count) if page in (None, "all") else [page]
            _choose(str(path), dict.fromkeys(range(count)), count, page)  # before reading
            memory.check_host(f"{path} (scan, {w}x{h} pixels, {len(wanted)} page(s))",
                              8.0 * 4 * w * h * len(wanted))
            meta = _image_meta(im)
            pages = {}
            for i in wanted:
                im.seek(i)
                pages[i] = _grey(path, im)
    except InputError:
        raise
    except Exception as e:  # noqa: BLE001 -- PIL's errors for damaged files vary by format
        raise HologramFileError(f"{path}: not a readable PNG/TIFF image ({type(e).__name__}: "
                                f"{e})") from None
    scale = meta.pop("intensity_scale", None)
    if scale is not None:
        scale = validate.positive(f"{path}: metadata intensity_scale", scale)
        pages = {i: p * scale for i, p in pages.items()}
    return pages, count, meta


def _grey(path: Path, im) -> np.ndarray:
    """One loaded page as float64 intensities in its bit depth's scale."""
    im.load()
    if im.mode in _AS_RGB:
        im = im.convert(_AS_RGB[im.mode])
    a = np.asarray(im)
    if im.mode in ("LA", "RGBA"):
        a = a[..., :-1]
    a = _scaled(str(path), a)
    return a.mean(axis=2) if a.ndim == 3 else a


def _scaled(name: str, a: np.ndarray) -> np.ndarray:
    """Integers to [0, 1] by their bit depth; floats and booleans as they are, in float64."""
    if a.dtype.kind in "iu":
        if a.size and a.min() < 0:
            raise HologramFileError(f"{name}: a scan of signed integers holds negative values; "
                                    f"intensities must be >= 0")
        top = int(a.max()) if a.size else 0
        scale = 255 if a.dtype.itemsize == 1 else 65535 if a.dtype.itemsize == 2 else \
            next((s for s in (255, 65535, 2**32 - 1) if top <= s), None)
        if scale is None:
            raise HologramFileError(f"{name}: integer intensities up to {top} exceed 32 bits")
        return a.astype(np.float64) / scale
    if a.dtype.kind == "c":
        raise HologramFileError(f"{name}: holds complex values; an acquired hologram is an "
                                f"intensity (real, >= 0)")
    if a.dtype.kind not in "fb":
        raise HologramFileError(f"{name}: holds {a.dtype} values, not numbers")
    return a.astype(np.float64)


def _image_meta(im) -> dict:
    """The optics keys of a PNG's text chunks or a TIFF's description (JSON or ImageJ's
    lines), ImageJ's calibrated resolution as the pitch, and a PNG's intensity_scale."""
    meta = {}
    text = dict(getattr(im, "text", {}) or {})  # PNG text chunks
    tags = getattr(im, "tag_v2", None)
    if tags is not None and 270 in tags:
        text.update(_description(str(tags[270])))
        unit = _IMAGEJ_UNITS.get(str(text.get("unit", "")).strip().lower())
        if str(tags[270]).startswith("ImageJ=") and unit and 282 in tags:
            pitches = {1 / float(tags[t]) * unit for t in (282, 283) if t in tags and
                       float(tags[t]) > 0}
            if len(pitches) == 1:
                meta["pitch_m"] = pitches.pop()
            elif pitches:
                raise HologramFileError(f"{im.filename}: its pixels are {sorted(pitches)} m "
                                        f"apart in x and y; a hologram has one pitch")
    for key in (*KEYS, "intensity_scale"):
        if key in text:
            meta[key] = text[key]
    return meta


def _description(text: str) -> dict:
    text = text.strip()
    if text.startswith("{"):
        try:
            value = json.loads(text)
        except ValueError:
            return {}
        return value if isinstance(value, dict) else {}
    return dict(line.split("=", 1) for line in text.splitlines() if "=" in line)


def _read_npy(path: Path):
    try:
        a = np.load(path, mmap_mode="r", allow_pickle=False)
    except Exception as e:  # noqa: BLE001 -- a damaged header: ValueError, EOFError, OSError
        raise HologramFileError(f"{path}: not a readable .npy array ({type(e).__name__}: "
                                f"{e})") from None
    memory.check_host(f"{path} ({'x'.join(map(str, a.shape))} array)", 2.0 * 8 * a.size)
    meta = {}
    side = path.with_suffix(".json")
    if side.is_file():
        try:
            meta = json.loads(side.read_text())
        except (ValueError, UnicodeDecodeError) as e:
            raise HologramFileError(f"{side}: not a JSON object of {', '.join(KEYS)} "
                                    f"({e})") from None
        if not isinstance(meta, dict):
            raise HologramFileError(f"{side}: must hold a JSON object of {', '.join(KEYS)}")
    return (*_pages(str(path), _scaled(str(path), np.asarray(a))), meta)


def _h5py(path):
    try:
        import h5py
    except ImportError:
        raise InputError(f"{path}: HDF5 and .mat v7.3 files are read through h5py; install "
                         f"it (pip install 'holo[lab]')") from None
    return h5py


def _read_hdf5(path: Path, dataset):
    h5py = _h5py(path)
    with open(path, "rb") as f:
        head = f.read(128)
    if head.startswith(b"MATLAB 5.0") or (path.suffix.lower() == ".mat" and
                                          not h5py.is_hdf5(path)):
        raise HologramFileError(f"{path}: a MATLAB v5 (or older) MAT-file; save it in MATLAB "
                                f"with save(name, ..., '-v7.3') (HDF5), which this reads")
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise HologramFileError(f"{path}: not a readable HDF5 file ({e})") from None
    with f:
        candidates = []
        f.visititems(lambda n, o: candidates.append(n) if isinstance(o, h5py.Dataset) and
                     o.ndim in (2, 3) and min(o.shape) > 1 and o.dtype.kind in "iufb" else None)
        if dataset is None:
            if len(candidates) != 1:
                raise InputError(f"{path}: holds {len(candidates)} 2-D or 3-D numeric "
                                 f"datasets; pass dataset= one of "
                                 f"{', '.join(candidates[:10]) or '(none)'}")
            dataset = candidates[0]
        elif not isinstance(dataset, str) or dataset not in f or \
                not isinstance(f[dataset], h5py.Dataset):
            raise InputError(f"dataset must name a dataset of {path}: one of "
                             f"{', '.join(candidates[:10]) or '(none)'}; got {dataset!r}"[:400])
        d = f[dataset]
        memory.check_host(f"{path}:{dataset} ({'x'.join(map(str, d.shape))})", 2.0 * 8 * d.size)
        matlab = "MATLAB_class" in d.attrs
        a = d[()]
        meta = {}
        for node in _parents(f, d.name):  # the dataset's own attributes win
            for key in KEYS:
                if key in node.attrs and key not in meta:
                    meta[key] = _scalar(node.attrs[key])
        for key in KEYS:  # MATLAB's scalar variables
            if key not in meta and key in f and isinstance(f[key], h5py.Dataset) and \
                    f[key].size == 1:
                meta[key] = _scalar(f[key][()])
    if matlab:  # MATLAB stores column-major: an H x W (x P) array is (P x) W x H in HDF5
        a = np.swapaxes(a, -1, -2)
    return (*_pages(f"{path}:{dataset}", _scaled(f"{path}:{dataset}", a)), meta)


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
        raise InputError(f"source must be a path or an (H, W) or (P, H, W) array of "
                         f"intensities; got {type(a).__name__} of shape {shape}")
    return _scaled(name, arr)


def _pages(name: str, a: np.ndarray) -> tuple[dict, int]:
    """({index: page}, count) of a 2-D or 3-D (pages, H, W) array."""
    if a.ndim in (2, 3):
        pages = [a] if a.ndim == 2 else list(a)
        return dict(enumerate(pages)), len(pages)
    raise HologramFileError(f"{name}: holds a {a.ndim}-D array; an intensity hologram is 2-D "
                            f"(H, W), or 3-D (pages, H, W)")


def _choose(name: str, pages: dict, count: int, page) -> list:
    """The pages ``page`` asks for (None: the only one; an index; 'all')."""
    if page is None and count > 1:
        raise InputError(f"{name}: holds {count} pages; pass page=i (0 to {count - 1}) for one "
                         f"of them or page='all' for every one")
    if isinstance(page, int) and page >= count:
        raise InputError(f"page must be in [0, {count - 1}] for {name} ({count} page"
                         f"{'s' if count > 1 else ''}); got {page}")
    return [pages[i] for i in (range(count) if page in (None, "all") else [page])]


def _optics(name: str, given: dict, meta: dict, required=True) -> dict:
    """The optics: each given value, else the file's, checked (units guarded); pitch and
    wavelength must be found when ``required``."""
    out = {}
    for key in KEYS:
        arg = key.rsplit("_", 1)[0]  # the argument's name: pitch, wavelength, ...
        value, stored = given[key], meta.get(key)
        if value is not None and stored is not None and not _same(value, stored):
            log.warning("%s: %s given as %r, the file says %r; using the given value", name,
                        arg, value, stored)
        if value is None and stored is not None:
            value, arg = stored, f"{name}: metadata {key}"
        if value is None and key in ("pitch_m", "wavelength_m"):
            if not required:
                continue
            raise InputError(f"{arg} must be given [m]: {name} holds no {key} (pass "
                             f"{arg}=..., or store {key} in its metadata)")
        if key == "pitch_m":
            out[key] = validate.pitch(arg, value)
        elif key == "wavelength_m":
            out[key] = validate.wavelength(arg, value)
        else:
            out[key] = 0.0 if value is None else validate.finite(arg, value, "rad")
    if not 0 <= out.get("reference_angle_rad", 0.0) < math.pi / 2:
        raise InputError(f"reference_angle must be in [0, π/2) rad; got "
                         f"{out['reference_angle_rad']!r}")
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
