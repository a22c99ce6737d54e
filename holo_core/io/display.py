"""A display's pattern as 16-bit greyscale tiles (PNG or TIFF) and a JSON layout.

The layout names each tile's file, its place on the display grid (row and column offset in
samples), and what a printer or an SLM's driver needs to show it: the pitch [m], the
wavelength [m], the distance [m] to the scene, the encoding and the quantisation. The tiles
and the layout are renamed into place together, so a reader never finds a mixed set.

Quantisation (16-bit codes, ``b`` = the display's bit depth, 1..16):

- phase [rad], taken modulo 2π: level = round(φ·2^b / 2π) mod 2^b, code = level·2^(16−b),
  φ = code·2π / 65536 (0 <= φ < 2π; 2π itself is 0);
- amplitude in [0, 1]: level = round(a·(2^b − 1)), code = round(level·65535 / (2^b − 1)),
  a = code / 65535.

No physics is imported here: the values arrive as arrays (see :mod:`holo_core.phase.display`).
"""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import numpy as np

from .. import memory, validate
from ..validate import InputError
from .image import atomic_paths, check_writable

FORMAT, VERSION = "holo-display-tiles", 1
QUANTITIES = ("phase", "amplitude")
TILE_FORMATS = ("png", "tiff")
CODE_BITS = 16
FULL = (1 << CODE_BITS) - 1  # 65535
DEFAULT_TILE = (2048, 2048)  # rows, cols: 8 MiB of 16-bit codes, a size every viewer opens
MAX_TILES = 4096  # a layout that lists more is refused before a file is read
MAX_LAYOUT_BYTES = 4 * 2**20  # ~1 KiB per tile entry and the header, far above what is written


def to_codes(values, quantity: str, bits: int = CODE_BITS) -> np.ndarray:
    """The uint16 codes of ``values`` (phase [rad] or amplitude in [0, 1]) quantised to
    ``bits`` levels (see the module docstring)."""
    quantity = validate.choice("quantity", quantity, QUANTITIES)
    bits = validate.integer("bit_depth", bits, 1, CODE_BITS)
    v = np.asarray(values, np.float64)
    if not np.isfinite(v).all():
        raise InputError(f"{quantity} values must be finite; they hold NaN or infinite values")
    if quantity == "phase":
        levels = np.round(np.mod(v, 2 * math.pi) * (2**bits / (2 * math.pi))) % 2**bits
        return (levels.astype(np.uint32) << (CODE_BITS - bits)).astype(np.uint16)
    _check_amplitudes(v)
    top = 2**bits - 1
    levels = np.round(np.clip(v, 0, 1) * top)
    return np.round(levels * (FULL / top)).astype(np.uint16)


def _check_amplitudes(v: np.ndarray) -> None:
    if v.size and (v.min() < -1e-9 or v.max() > 1 + 1e-9):  # float rounding is not clipping
        raise InputError(f"amplitude values must be in [0, 1]; got [{v.min():.6g}, {v.max():.6g}]")


def from_codes(codes, quantity: str) -> np.ndarray:
    """The float64 values of uint16 ``codes``: phase in [0, 2π) rad or amplitude in [0, 1]."""
    quantity = validate.choice("quantity", quantity, QUANTITIES)
    c = np.asarray(codes, np.float64)
    return c * (2 * math.pi / 2**CODE_BITS) if quantity == "phase" else c / FULL


def quantisation(quantity: str, bits: int) -> dict:
    """The layout's description of the codes (what a driver needs to undo them)."""
    if quantity == "phase":
        return {
            "quantity": "phase",
            "unit": "rad",
            "code_bits": CODE_BITS,
            "levels": 2**bits,
            "step": 2 * math.pi / 2**CODE_BITS,
            "range": [0.0, 2 * math.pi],
            "rule": f"phase = code * 2*pi / {2**CODE_BITS}, modulo 2*pi; the codes are "
            f"multiples of {2 ** (CODE_BITS - bits)}",
        }
    return {
        "quantity": "amplitude",
        "unit": "1",
        "code_bits": CODE_BITS,
        "levels": 2**bits,
        "step": 1 / FULL,
        "range": [0.0, 1.0],
        "rule": f"amplitude = code / {FULL}",
    }


def tile_bytes(codes: np.ndarray, fmt: str) -> bytes:
    """One 16-bit greyscale PNG or TIFF (uncompressed) file of (rows, cols) uint16 ``codes``."""
    from PIL import Image

    fmt = validate.choice("fmt", fmt, TILE_FORMATS)
    a = np.ascontiguousarray(codes, dtype="<u2")  # 'I;16' is little-endian in memory
    if a.ndim != 2:
        raise InputError(f"codes must be a 2-D array (rows, cols); got {a.ndim}-D")
    image = Image.frombuffer("I;16", (a.shape[1], a.shape[0]), a.tobytes(), "raw", "I;16", 0, 1)
    out = io.BytesIO()
    image.save(out, "PNG" if fmt == "png" else "TIFF")
    return out.getvalue()


def read_tile(path) -> np.ndarray:
    """The uint16 codes of a 16-bit greyscale PNG or TIFF tile; :class:`InputError` naming
    the file if it is missing, damaged or not 16-bit greyscale."""
    from PIL import Image

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such tile")
    try:
        with Image.open(path) as im:
            mode, size = im.mode, im.size
            if mode not in ("I;16", "I;16B", "I;16L", "I"):
                raise InputError(f"{path}: a tile must be 16-bit greyscale; its mode is {mode}")
            memory.check_host(f"{path} (tile, {size[0]}x{size[1]} pixels)", 8.0 * size[0] * size[1])
            a = np.asarray(im)
    except InputError:
        raise
    except Exception as e:  # noqa: BLE001 -- PIL's errors for damaged files vary by format
        raise InputError(
            f"{path}: not a readable PNG/TIFF tile ({type(e).__name__}: {e})"
        ) from None
    if a.size and (a.min() < 0 or a.max() > FULL):  # mode 'I' holds 32-bit integers
        raise InputError(f"{path}: values outside 0..{FULL}: not a 16-bit tile")
    return a.astype(np.uint16)


def write_tiles(
    path,
    values,
    *,
    quantity,
    pitch,
    wavelength,
    distance,
    encoding,
    bit_depth=CODE_BITS,
    tile=DEFAULT_TILE,
    fmt="png",
    display="",
) -> Path:
    """Write ``values`` (rows, cols) as 16-bit tiles beside the layout ``path`` (*.json).

    Parameters
    ----------
    path : path-like
        The layout file; tiles are named ``<stem>_r<row>_c<col>.<fmt>`` in its folder, row and
        col the tile's offset in samples.
    values : (rows, cols) float array
        Phase [rad] (any range; written modulo 2π) or amplitude in [0, 1].
    quantity : 'phase' or 'amplitude'
    pitch : float
        The display's sample spacing [m].
    wavelength : float
        The wavelength [m] the pattern is meant for.
    distance : float
        The scene's signed distance from the display [m], along the display's normal
        (negative: behind it, a virtual image, as the plate's frame puts a scene at z < 0).
    encoding : str
        How the pattern encodes the complex wave ('double-phase', 'error-diffusion', 'bias',
        ...), written for the reader.
    bit_depth : int
        Levels the display resolves, 2^bit_depth (1..16); the codes are quantised to them.
    tile : (int, int)
        Most rows and cols of one tile; edge tiles are smaller.
    fmt : 'png' or 'tiff'
    display : str
        The display's name, written for the reader.

    Returns
    -------
    The layout's path.
    """
    layout_path = check_writable(path, ".json")
    v = validate.host_field("values", np.asarray(values))
    if np.iscomplexobj(v):
        raise InputError("values must be real (phases [rad] or amplitudes); got complex")
    tile = validate.shape2d("tile", tile)
    fmt = validate.choice("fmt", fmt, TILE_FORMATS)
    layout = _layout(
        v.shape,
        quantity=quantity,
        pitch=pitch,
        wavelength=wavelength,
        distance=distance,
        encoding=encoding,
        bit_depth=bit_depth,
        display=display,
    )
    if layout["kind"] == "amplitude":
        _check_amplitudes(v)  # before a file is opened, not at the tile that holds it
    places = _places(v.shape, tile)
    names = [f"{layout_path.stem}_r{r}_c{c}.{fmt}" for r, c, _, _ in places]
    layout["tiles"] = [
        {"file": n, "row": r, "col": c, "rows": h, "cols": w}
        for n, (r, c, h, w) in zip(names, places)
    ]
    with atomic_paths(*[layout_path.parent / n for n in names], layout_path) as temps:
        for tmp, (r, c, h, w) in zip(temps, places):  # one tile's codes in memory at a time
            codes = to_codes(v[r : r + h, c : c + w], layout["kind"], layout["bit_depth"])
            Path(tmp).write_bytes(tile_bytes(codes, fmt))
        Path(temps[-1]).write_text(json.dumps(layout, indent=1) + "\n")
    return Path(path)


def read_tiles(path) -> tuple[np.ndarray, dict]:
    """(values, layout) of the layout ``path`` written by :func:`write_tiles`: the float64
    (rows, cols) pattern reassembled from its tiles (phase in [0, 2π) rad or amplitude in
    [0, 1]) and the layout's fields. :class:`InputError` naming the file when the layout is
    damaged, a tile is missing or misshapen, or the tiles do not cover the grid once."""
    path = Path(path)
    layout = _read_layout(path)
    rows, cols = layout["shape"]
    memory.check_host(f"{path} (display pattern, {cols}x{rows} samples)", 10.0 * rows * cols)
    codes = np.zeros((rows, cols), np.uint16)
    covered = np.zeros((rows, cols), bool)  # a flag, not a count: a count of 256 wraps to 0
    for t in layout["tiles"]:
        window = (slice(t["row"], t["row"] + t["rows"]), slice(t["col"], t["col"] + t["cols"]))
        if covered[window].any():  # before its file is read
            raise InputError(
                f"{path}: the tiles do not cover the {cols}x{rows} grid exactly "
                f"once: tile {t['file']} (row {t['row']}, col {t['col']}) covers "
                f"samples an earlier tile covers"
            )
        try:
            a = read_tile(path.parent / t["file"])
        except InputError as e:  # the layout that lists it, and the tile's own complaint
            raise InputError(f"{path}: {e}") from None
        if a.shape != (t["rows"], t["cols"]):
            raise InputError(
                f"{path}: tile {t['file']} is {a.shape[1]}x{a.shape[0]} samples; "
                f"the layout says {t['cols']}x{t['rows']}"
            )
        codes[window] = a
        covered[window] = True
    if not covered.all():
        raise InputError(
            f"{path}: the tiles do not cover the {cols}x{rows} grid exactly "
            f"once: {int((~covered).sum())} samples missing"
        )
    return from_codes(codes, layout["kind"]), layout


def _layout(shape, *, quantity, pitch, wavelength, distance, encoding, bit_depth, display) -> dict:
    quantity = validate.choice("quantity", quantity, QUANTITIES)
    bits = validate.integer("bit_depth", bit_depth, 1, CODE_BITS)
    if not isinstance(encoding, str) or not encoding.strip() or len(encoding) > 100:
        raise InputError(
            f"encoding must name the encoding (1 to 100 characters); got {encoding!r}"[:200]
        )
    if not isinstance(display, str) or len(display) > 100:
        raise InputError(f"display must be a name of at most 100 characters; got {display!r}"[:200])
    return {
        "format": FORMAT,
        "version": VERSION,
        "display": display,
        "kind": quantity,
        "encoding": encoding,
        "shape": [int(shape[0]), int(shape[1])],
        "pitch": validate.pitch("pitch", pitch),
        "wavelength": validate.wavelength("wavelength", wavelength),
        "distance": validate.within("distance", distance, validate.MAX_LENGTH),
        "bit_depth": bits,
        "quantisation": quantisation(quantity, bits),
    }


def _places(shape, tile) -> list[tuple[int, int, int, int]]:
    """(row, col, rows, cols) of each tile, row-major."""
    (h, w), (th, tw) = shape, tile
    count = math.ceil(h / th) * math.ceil(w / tw)
    if count > MAX_TILES:
        raise InputError(
            f"tile {th}x{tw} cuts {w}x{h} samples into {count} tiles; at most "
            f"{MAX_TILES} are written: choose larger tiles"
        )
    return [
        (r, c, min(th, h - r), min(tw, w - c)) for r in range(0, h, th) for c in range(0, w, tw)
    ]


def _read_layout(path: Path) -> dict:
    """The layout's fields, each checked as :func:`write_tiles` writes it."""
    if not path.is_file():
        raise InputError(f"{path}: no such layout file")
    if path.stat().st_size > MAX_LAYOUT_BYTES:
        raise InputError(
            f"{path}: {path.stat().st_size} bytes; a layout of {MAX_TILES} tiles "
            f"takes less than {MAX_LAYOUT_BYTES}"
        )
    try:
        layout = json.loads(path.read_text())
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as e:
        raise InputError(f"{path}: not a JSON layout ({type(e).__name__}: {e})"[:400]) from None
    if not isinstance(layout, dict) or layout.get("format") != FORMAT:
        raise InputError(f"{path}: not a display layout (format {FORMAT!r})")
    if layout.get("version") != VERSION:
        raise InputError(
            f"{path}: layout version {layout.get('version')!r}; this reader reads version {VERSION}"
        )
    try:
        shape = validate.shape2d("shape", layout["shape"])  # first: _layout takes it as valid
        checked = _layout(
            shape,
            quantity=layout["kind"],
            pitch=layout["pitch"],
            wavelength=layout["wavelength"],
            distance=layout["distance"],
            encoding=layout["encoding"],
            bit_depth=layout["bit_depth"],
            display=layout.get("display", ""),
        )
        tiles = [_tile_entry(t, shape) for t in _tile_list(layout["tiles"])]
    except KeyError as e:
        raise InputError(f"{path}: the layout lacks the field {e.args[0]!r}") from None
    except InputError as e:
        raise InputError(f"{path}: {e}") from None
    return {**checked, "shape": list(shape), "tiles": tiles}


def _tile_list(tiles) -> list:
    if not isinstance(tiles, list) or not 1 <= len(tiles) <= MAX_TILES:
        raise InputError(f"tiles must be a list of 1 to {MAX_TILES} tiles")
    return tiles


def _tile_entry(t, shape) -> dict:
    """One tile's entry: a plain file name in the layout's folder (a layout must not point a
    reader elsewhere), its window inside the grid."""
    if not isinstance(t, dict):
        raise InputError(f"each tile must be an object; got {t!r}"[:200])
    name = t.get("file")
    if not isinstance(name, str) or not name or Path(name).name != name or name in (".", ".."):
        raise InputError(
            f"a tile's file must be a plain file name in the layout's folder; got {name!r}"[:200]
        )
    r = validate.integer(f"tile {name} row", t.get("row"), 0, shape[0] - 1)
    c = validate.integer(f"tile {name} col", t.get("col"), 0, shape[1] - 1)
    h = validate.integer(f"tile {name} rows", t.get("rows"), 1, shape[0] - r)
    w = validate.integer(f"tile {name} cols", t.get("cols"), 1, shape[1] - c)
    return {"file": name, "row": r, "col": c, "rows": h, "cols": w}
