"""The files a phase SLM's driver shows, one per laser, with a JSON layout beside each; and a
simulated focal stack as EXR with a PNG contact sheet.

Pattern images (the display as its second-monitor driver shows it, full screen, row 0 at the
top), ``b`` the display's bit depth and ``k`` a code in 0 .. 2^b − 1:

- ``grey8``  (b <= 8): an 8-bit greyscale PNG, value = k·2^(8 − b) (b = 8: the code itself);
- ``grey16`` (b <= 16): a 16-bit greyscale PNG, value = k·2^(16 − b) (the code in the high
  bits, as :mod:`holo_core.io.display`'s tiles);
- ``packed10`` (b = 10): an 8-bit RGB PNG, red = k >> 2 (the 8 high bits), green = 0,
  blue = k & 3 (the 2 low bits, as the values 0..3 of the blue byte), for SLMs whose driver
  reads 10-bit phase that way; k = 4·red + blue.

The layout (``<name>.json``, format ``holo-slm-pattern``) carries what the driver and a
reader need: the display (name, resolution, pitch, bit depth, phase range, inverted), the
laser (wavelength [m], power [W]), the scene's distance [m], the encoding, the packing, and
the response: the phase [rad] of every code (the table's, or the display's line), so that
anyone can turn the image back into the phase it shows. Image and layout are renamed into
place together (never a mixed pair); codes outside the bit depth are refused, so nothing
non-finite or out of range is ever written.

No physics is imported here: the codes and responses arrive as arrays.
"""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import numpy as np

from .. import validate
from ..validate import InputError
from .image import atomic_paths, check_writable, png_bytes, write_exr

FORMAT, VERSION = "holo-slm-pattern", 1
PACKINGS = ("grey8", "grey16", "packed10")
STACK_FORMAT = "holo-focal-stack"


def packing_for(bit_depth: int) -> str:
    """The usual packing of a ``bit_depth`` display: grey8 up to 8 bits, packed10 at 10,
    grey16 otherwise."""
    b = validate.integer("bit_depth", bit_depth, 1, 16)
    return "grey8" if b <= 8 else "packed10" if b == 10 else "grey16"


def _check_codes(codes, bit_depth: int) -> np.ndarray:
    c = np.asarray(codes)
    if c.ndim != 2 or not c.size:
        raise InputError(f"codes must be a 2-D array (rows, cols); got shape {c.shape}")
    if not np.issubdtype(c.dtype, np.integer):
        raise InputError(f"codes must be integers; got {c.dtype}")
    top = 2**bit_depth - 1
    if c.min() < 0 or c.max() > top:
        raise InputError(
            f"codes must be in 0..{top} for {bit_depth} bits; got {int(c.min())}..{int(c.max())}"
        )
    return c.astype(np.uint16)


def pack(codes, bit_depth: int, packing: str) -> np.ndarray:
    """The image's pixels for ``codes``: (H, W) uint8 (grey8), uint16 (grey16) or (H, W, 3)
    uint8 (packed10), per the module docstring."""
    b = validate.integer("bit_depth", bit_depth, 1, 16)
    packing = validate.choice("packing", packing, PACKINGS)
    c = _check_codes(codes, b)
    if packing == "grey8":
        if b > 8:
            raise InputError(
                f"packing grey8 holds at most 8 bits; the display has {b} "
                f"(grey16, or packed10 for 10 bits)"
            )
        return (c << (8 - b)).astype(np.uint8)
    if packing == "grey16":
        return (c.astype(np.uint32) << (16 - b)).astype(np.uint16)
    if b != 10:
        raise InputError(f"packing packed10 is for 10-bit displays; the display has {b} bits")
    out = np.zeros(c.shape + (3,), np.uint8)
    out[..., 0] = c >> 2
    out[..., 2] = c & 3
    return out


def unpack(pixels, bit_depth: int, packing: str) -> np.ndarray:
    """The codes of an image's ``pixels`` (the inverse of :func:`pack`), uint16; InputError
    where a pixel is not one :func:`pack` writes."""
    b = validate.integer("bit_depth", bit_depth, 1, 16)
    packing = validate.choice("packing", packing, PACKINGS)
    p = np.asarray(pixels).astype(np.int64)
    if packing == "packed10":
        if p.ndim != 3 or p.shape[2] < 3:
            raise InputError(f"a packed10 image is RGB; got shape {p.shape}")
        if (p[..., 1] != 0).any() or (p[..., 2] > 3).any() or b != 10:
            raise InputError("not a packed10 image: green must be 0 and blue 0..3")
        return (4 * p[..., 0] + p[..., 2]).astype(np.uint16)
    if p.ndim != 2:
        raise InputError(f"a {packing} image is greyscale; got shape {p.shape}")
    shift = (8 if packing == "grey8" else 16) - b
    if shift < 0 or (p & ((1 << shift) - 1)).any():
        raise InputError(f"not a {packing} image of {b}-bit codes (the low {shift} bits must be 0)")
    return (p >> shift).astype(np.uint16)


def image_bytes(pixels: np.ndarray) -> bytes:
    """The PNG file of packed ``pixels`` (uint8 grey or RGB, or uint16 grey)."""
    if pixels.dtype == np.uint8:
        return png_bytes(pixels / 255.0)  # exact: round(v / 255 · 255) = v
    from PIL import Image

    a = np.ascontiguousarray(pixels, dtype="<u2")
    image = Image.frombuffer("I;16", (a.shape[1], a.shape[0]), a.tobytes(), "raw", "I;16", 0, 1)
    out = io.BytesIO()
    image.save(out, "PNG")
    return out.getvalue()


def write_pattern(path, codes, **fields) -> tuple[Path, Path]:
    """Write ``codes`` as the driver's image ``path`` (*.png) and its layout beside it (same
    stem, *.json), atomically as a pair; returns (image, layout). ``fields`` as for
    :func:`pattern_files`."""
    return write_patterns([(path, codes, fields)])[0]


def write_patterns(items) -> list[tuple[Path, Path]]:
    """Write several patterns (a frame's, one per laser) as one atomic set: every image and
    layout renamed into place together, or none. ``items``: (path, codes, fields) each, as
    :func:`write_pattern` takes them; returns (image, layout) per item."""
    files, pairs = [], []
    for path, codes, fields in items:
        image_path = check_writable(path, ".png")
        data, layout = pattern_files(image_path.name, codes, **fields)
        layout_path = image_path.with_suffix(".json")
        files += [(image_path, data), (layout_path, (json.dumps(layout, indent=1) + "\n").encode())]
        pairs.append((image_path, layout_path))
    if len({p for p, _ in files}) != len(files):
        raise InputError("patterns must be written to distinct files")
    with atomic_paths(*[p for p, _ in files]) as temps:
        for tmp, (_, data) in zip(temps, files):
            Path(tmp).write_bytes(data)
    return pairs


def pattern_files(
    image_name,
    codes,
    *,
    response,
    display,
    pitch,
    bit_depth,
    phase_range,
    inverted,
    wavelength,
    power,
    distance,
    encoding,
    packing=None,
    table="",
    extra=None,
) -> tuple[bytes, dict]:
    """The image file's bytes and the layout of one pattern.

    Parameters
    ----------
    image_name : str
        The image's file name, written into the layout.
    codes : (rows, cols) integer array, 0 .. 2^bit_depth − 1
    response : (2^bit_depth,) float array
        The phase [rad] each code shows (written into the layout).
    display : str
        The display's name.
    pitch : float
        [m].
    bit_depth : int
    phase_range : float
        [rad], the display's line without a table.
    inverted : bool
    wavelength : float
        The laser's wavelength [m].
    power : float
        The laser's power [W].
    distance : float
        The scene's signed distance from the display [m] (negative: behind it).
    encoding : str
        'double-phase', 'gradient-descent', 'gerchberg-saxton', ...
    packing : str, optional
        One of :data:`PACKINGS` (default :func:`packing_for` the bit depth).
    table : str
        The table's source ('' for the display's line).
    extra : dict, optional
        More fields for the layout (the frame, the eye box, the encoding's settings): plain
        JSON values, finite.
    """
    bits = validate.integer("bit_depth", bit_depth, 1, 16)
    packing = (
        packing_for(bits) if packing is None else validate.choice("packing", packing, PACKINGS)
    )
    pixels = pack(codes, bits, packing)
    curve = np.asarray(response, np.float64)
    if curve.shape != (2**bits,) or not np.isfinite(curve).all():
        raise InputError(f"response must be {2**bits} finite phases [rad]; got shape {curve.shape}")
    rows, cols = pixels.shape[:2]
    layout = {
        "format": FORMAT,
        "version": VERSION,
        "image": str(image_name),
        "display": {
            "name": str(display),
            "resolution": [cols, rows],
            "pitch": validate.pitch("pitch", pitch),
            "bit_depth": bits,
            "phase_range": validate.positive("phase_range", phase_range, "rad"),
            "inverted": bool(inverted),
        },
        "laser": {
            "wavelength": validate.wavelength("wavelength", wavelength),
            "power": validate.positive("power", power, "W"),
        },
        "distance": validate.within("distance", distance, validate.MAX_LENGTH),
        "encoding": str(encoding),
        "packing": packing,
        "packing_rule": {
            "grey8": f"code = value >> {max(0, 8 - bits)}",
            "grey16": f"code = value >> {16 - bits}",
            "packed10": "code = 4 * red + blue (green 0)",
        }[packing],
        "table": str(table),
        "response": [float(v) for v in curve],
        "response_rule": "the phase [rad] code k shows is response[k]",
    }
    if extra:
        layout["extra"] = _finite_json("extra", extra)
    return image_bytes(pixels), layout


def _finite_json(name, value):
    text = json.dumps(value, allow_nan=True)
    if "NaN" in text or "Infinity" in text:
        raise InputError(f"{name} must hold finite numbers only")
    return json.loads(text)


def read_pattern(path) -> tuple[np.ndarray, dict]:
    """(codes, layout) of the layout ``path`` (*.json) :func:`write_pattern` wrote: the codes
    unpacked from its image and the layout's fields; InputError naming the file when the
    layout or image is damaged or does not match."""
    from PIL import Image

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such layout file")
    try:
        layout = json.loads(path.read_text())
        if layout.get("format") != FORMAT or layout.get("version") != VERSION:
            raise InputError(f"{path}: not a pattern layout ({FORMAT} version {VERSION})")
        d = layout["display"]
        bits, packing = int(d["bit_depth"]), layout["packing"]
        image = path.parent / layout["image"]
        if Path(layout["image"]).name != layout["image"]:
            raise InputError(f"{path}: the image must be a file beside the layout")
        with Image.open(image) as im:
            pixels = np.asarray(im)
        codes = unpack(pixels, bits, packing)
        if list(codes.shape[::-1]) != list(d["resolution"]):
            raise InputError(
                f"{path}: the image is {codes.shape[1]}x{codes.shape[0]}; the "
                f"layout says {d['resolution']}"
            )
        if len(layout["response"]) != 2**bits:
            raise InputError(f"{path}: {len(layout['response'])} response phases for {bits} bits")
    except InputError as e:
        raise InputError(f"{path}: {e}" if str(path) not in str(e) else str(e)) from None
    except (KeyError, TypeError, ValueError, OSError) as e:
        raise InputError(
            f"{path}: not a readable pattern and layout ({type(e).__name__}: {e})"[:400]
        ) from None
    return codes, layout


def contact_sheet(stack, labels=(), columns=6) -> np.ndarray:
    """A grid of the (N, H, W) or (N, H, W, 3) ``stack``'s slices in [0, 1] (each scaled by
    one peak, the whole stack's 99.9th percentile, so slices compare), labelled in their
    top-left corner, float64 (rows·H', cols·W'[, 3])."""
    from PIL import Image, ImageDraw

    s = np.asarray(stack, np.float64)
    if s.ndim == 3:
        s = s[..., None].repeat(3, axis=3)
    n, h, w = s.shape[:3]
    peak = float(np.percentile(s, 99.9)) or 1.0
    s = np.clip(s / peak, 0, 1) ** (1 / 2.2)  # intensity to display: a plain gamma
    cols = min(columns, n)
    rows = math.ceil(n / cols)
    gap = 2
    sheet = np.ones((rows * (h + gap), cols * (w + gap), 3))
    for i in range(n):
        r, c = divmod(i, cols)
        sheet[r * (h + gap) : r * (h + gap) + h, c * (w + gap) : c * (w + gap) + w] = s[i]
    im = Image.fromarray(np.round(sheet * 255).astype(np.uint8))
    draw = ImageDraw.Draw(im)
    for i, label in enumerate(labels):
        r, c = divmod(i, cols)
        draw.text((c * (w + gap) + 3, r * (h + gap) + 2), str(label), fill=(255, 255, 0))
    return np.asarray(im) / 255.0


def write_stack(
    path,
    stack,
    *,
    distances,
    reference=None,
    metrics=None,
    labels=(),
    sheet_width=1800,
    compression="zip",
) -> tuple[Path, ...]:
    """Write a focal stack as one EXR (``path``, *.exr; channels ``z00.R`` ... per slice,
    ``ref.z00.R`` ... for the ``reference`` stack when given) with a PNG contact sheet beside
    it (same stem, *.png; the reference's slices below the stack's when given), renamed into
    place together. ``stack`` (N, H, W) or (N, H, W, 3) finite intensities; ``distances``
    (N,) [m]; ``metrics`` a JSON-able dict written into the EXR header as text;
    ``compression`` 'zip' or 'none' (a stack's float noise barely compresses: 'none' writes
    a 1024×1536 colour stack of 30 slices and its reference, 1.1 GB, several times faster)."""
    exr_path = check_writable(path, ".exr")
    s = np.asarray(stack, np.float32)
    z = np.asarray(distances, np.float64)
    if (
        s.ndim not in (3, 4)
        or s.shape[0] != z.size
        or not np.isfinite(s).all()
        or not np.isfinite(z).all()
    ):
        raise InputError(
            f"stack must be finite (N, H, W[, 3]) with N distances; got {s.shape} and {z.size}"
        )
    stacks = {"": s}
    if reference is not None:
        ref = np.asarray(reference, np.float32)
        if ref.shape != s.shape or not np.isfinite(ref).all():
            raise InputError(f"reference must be finite and of the stack's shape {s.shape}")
        stacks["ref."] = ref
    channels = {}
    for prefix, a in stacks.items():
        for i in range(a.shape[0]):
            if a.ndim == 4:
                for c, name in enumerate("RGB"):
                    channels[f"{prefix}z{i:02d}.{name}"] = a[i, ..., c]
            else:
                channels[f"{prefix}z{i:02d}.Y"] = a[i]
    # one slice per ~300 px across the sheet: a 30-slice stack is 6 across
    step = max(1, math.ceil(s.shape[2] * min(6, s.shape[0]) / sheet_width))
    small = {k: a[:, ::step, ::step] for k, a in stacks.items()}
    sheets = [
        contact_sheet(small[k], labels if k == "" else [f"ref {x}" for x in labels]) for k in stacks
    ]
    sheet = np.concatenate(sheets, axis=0)
    header = {
        "holo_format": STACK_FORMAT,
        "holo_distances": json.dumps([float(v) for v in z]),
        "holo_metrics": json.dumps(_finite_json("metrics", metrics or {})),
    }
    write_exr(
        exr_path, channels, preview=png_bytes(sheet), compression=compression, **header
    )  # one unit, atomic
    return exr_path, exr_path.with_suffix(".png")
