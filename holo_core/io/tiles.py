"""Plates in tiles: a Zarr (v3) group on a local path or any fsspec URL, for plates beyond memory.

The group holds what an EXR hologram file holds, in chunks:

``attrs["holo"]``
    the same metadata, in the same schema, as the EXR's ``holo`` header
    (:func:`holo_core.io.hologram.metadata`), checked by the same reader;
``object_wave`` (C, H, W) complex64
    the complex plate's samples, one chunk per tile and channel, dimension names
    ``(channel, y, x)``: ``dask.array.from_zarr(url, component="object_wave")``,
    ``xarray.open_zarr(url)`` and napari open it as it is;
``tiles_done`` (rows of tiles, columns of tiles) bool
    a tile's flag, set after all its samples are written. A recording killed inside a tile
    leaves its flag unset, so resuming writes that tile again and a reader never takes a half
    written tile for a whole one.

Chunks are stored uncompressed: an object wave is noise-like and does not compress.
"""

from __future__ import annotations

import json
import math

import numpy as np

from ..scene.hologram import Hologram, HologramInfo
from .hologram import HologramFileError, info_of, metadata

WAVE, DONE = "object_wave", "tiles_done"
MIN_TILE, MAX_TILE = 64, 16384


def tile_grid(shape, tile) -> tuple[int, int]:
    """(rows, columns) of ``tile``-sized tiles that cover a plate of ``shape`` (rows, cols)."""
    return math.ceil(shape[0] / tile), math.ceil(shape[1] / tile)


def tile_window(shape, tile, i, j) -> tuple[int, int, int, int]:
    """(row0, row1, col0, col1) of tile (i, j); the last row and column of tiles may be
    smaller."""
    return i * tile, min((i + 1) * tile, shape[0]), j * tile, min((j + 1) * tile, shape[1])


def _zarr():
    try:
        import zarr
    except ImportError:  # an optional dependency: say how to get it
        raise HologramFileError("tiled plates need zarr: pip install 'holo[tiles]'") from None
    return zarr


def create_plate(url, info: HologramInfo, tile: int):
    """A new tiled store at ``url`` (a folder path or an fsspec URL) for the complex plate
    ``info`` describes, or the existing one there when it was made for the same plate (a
    recording resumes into it). Returns the zarr group. :class:`HologramFileError` when
    ``url`` holds another plate."""
    zarr = _zarr()
    shape = info.shape
    count = len(info.wavelengths)
    meta = metadata(info)
    group = zarr.open_group(store=str(url), mode="a")
    if "holo" in group.attrs:
        if json.loads(json.dumps(meta)) != dict(group.attrs["holo"]) or \
                group.attrs.get("tile") != tile:
            raise HologramFileError(f"{url}: holds another plate (its metadata or tile size "
                                    f"differ); record to a new path or remove it")
        return group
    group.create_array(WAVE, shape=(count, *shape), chunks=(1, tile, tile), dtype="complex64",
                       fill_value=0, compressors=None, dimension_names=("channel", "y", "x"),
                       overwrite=True)
    group.create_array(DONE, shape=tile_grid(shape, tile), chunks=(1, 1), dtype="bool",
                       fill_value=False, dimension_names=("tile_row", "tile_col"),
                       overwrite=True)
    group.attrs.update({"holo": meta, "tile": tile})  # last: a store without it is not a plate
    return group


def write_tile(url, i: int, j: int, samples: np.ndarray) -> None:
    """Tile (i, j)'s samples (C, rows, cols) complex, then its flag."""
    group = _zarr().open_group(store=str(url), mode="r+")
    tile = group.attrs["tile"]
    r0, r1, c0, c1 = tile_window(group[WAVE].shape[1:], tile, i, j)
    group[WAVE][:, r0:r1, c0:c1] = samples.astype(np.complex64, copy=False)
    group[DONE][i, j] = True


def tiles_done(url) -> np.ndarray:
    """The flags (rows of tiles, columns of tiles) of the tiles fully written."""
    return np.asarray(_zarr().open_group(store=str(url), mode="r")[DONE][...])


def open_plate(url, *, complete=True) -> Hologram:
    """The tiled plate at ``url`` as a :class:`Hologram` whose ``object_wave`` is the store's
    chunked array: nothing is read until a view reads the rows and columns it needs. With
    ``complete``, :class:`HologramFileError` names the tiles still missing (a recording that
    did not finish: resume it)."""
    zarr = _zarr()
    try:
        group = zarr.open_group(store=str(url), mode="r")
    except (FileNotFoundError, ValueError, KeyError) as e:
        raise HologramFileError(f"{url}: not a tiled plate ({e})") from None
    if "holo" not in group.attrs or WAVE not in group or DONE not in group:
        raise HologramFileError(f"{url}: not a tiled plate (no hologram metadata or samples)")
    info = info_of(url, json.dumps(group.attrs["holo"]))
    wave = group[WAVE]
    if info.encoding != "complex" or tuple(wave.shape) != (len(info.wavelengths), *info.shape):
        raise HologramFileError(f"{url}: a tiled plate holds a complex object wave of "
                                f"{list(info.shape)} samples per wavelength; it holds "
                                f"{wave.shape}, encoding {info.encoding!r}")
    missing = int((~np.asarray(group[DONE][...])).sum())
    if complete and missing:
        raise HologramFileError(f"{url}: {missing} of {group[DONE].size} tiles are not written "
                                f"yet; resume the recording (the same call again)")
    return Hologram(info=info, object_wave=wave)
