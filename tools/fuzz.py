"""Seeded fuzzing of the readers, the hologram writer and the API.

Readers: valid files made here, mutated, each read once (``lab``: the laboratory arrays,
``.npy``, HDF5 and MATLAB v7.3, that :func:`~holo_core.io.acquired.write_acquired` writes).
``write``: holograms of hostile field values, each refused or written and read back unchanged
(the writer holds the reader's schema).
``api``: public calls with one or two hostile arguments. Every case must end in a result
(checked for sanity: finite, and a hologram that reconstructs and renders finite) or the
project's InputError, whose message names the file for a reader, within ``CASE_SECONDS`` and
under an address-space limit; anything else is a finding. Run as ``python tools/fuzz.py TARGET
CASES SEED`` (TARGET: hologram, ply, obj, scan, lab, write, api, store, layout); it prints one
JSON line: the outcome counts and up to 10 examples of each failure kind. ``store``: a valid tiled
plate's files damaged one or two at a time (bytes, JSON, links to /dev/zero or outside, FIFOs,
folders, missing files, another chunk's bytes), read back exactly as recorded or refused;
``layout``: a display's layout and tiles damaged (a tile listed up to 300 times too).
"""

from __future__ import annotations

import io
import json
import os
import resource
import signal
import struct
import sys
import tempfile
import time
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

CASE_SECONDS = 10
ADDRESS_SPACE = 6 * 2**30  # the process's limit: a runaway allocation fails, not the machine
MEMORY_BUDGET = "512M"  # HOLO_MEMORY_LIMIT: the readers' own checks refuse before that


class Hang(Exception):
    pass


# --- valid files ------------------------------------------------------------------------------


def hologram_file(rng) -> bytes:
    from holo_core.io.hologram import write_hologram
    from holo_core.scene.hologram import Hologram

    shape = (2, 12, 16)
    plate = np.eye(4)
    plate[:3, 3] = rng.normal(size=3)
    h = Hologram(
        intensity=rng.random(shape, np.float32),
        wavelengths=(633e-9, 632e-9),
        pitch=8e-6,
        reference_angle=0.02,
        reference_amplitudes=(1.0, 1.0),
        object_wave=(rng.normal(size=shape) + 1j).astype(np.complex64),
        plate=plate,
        bounds=np.array([[-1, -1, -2], [1, 1, -1.0]]),
        channels=("Y", "Z"),
    )
    with tempfile.TemporaryDirectory() as d:
        return write_hologram(Path(d) / "h.exr", h).read_bytes()


def ply_file(rng) -> bytes:
    verts = rng.normal(size=(6, 3))
    faces = [[0, 1, 2], [2, 3, 4, 5], [1, 3, 5]]
    colours = rng.integers(0, 256, (6, 3))
    fmt = rng.choice(["ascii", "binary_little_endian", "binary_big_endian"])
    head = (
        f"ply\nformat {fmt} 1.0\ncomment fuzz\nelement vertex 6\nproperty float x\n"
        f"property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
        f"property uchar blue\nelement face 3\nproperty list uchar int vertex_indices\n"
        f"end_header\n"
    ).encode()
    if fmt == "ascii":
        rows = [
            " ".join(f"{x:.6g}" for x in v) + " " + " ".join(map(str, c))
            for v, c in zip(verts, colours)
        ]
        rows += [" ".join(map(str, [len(f)] + f)) for f in faces]
        return head + ("\n".join(rows) + "\n").encode()
    e = "<" if fmt == "binary_little_endian" else ">"
    body = b"".join(struct.pack(e + "fffBBB", *v, *c) for v, c in zip(verts, colours))
    body += b"".join(struct.pack(e + "B" + "i" * len(f), len(f), *f) for f in faces)
    return head + body


def obj_file(rng) -> bytes:
    verts = rng.normal(size=(5, 3))
    lines = ["# fuzz", "o thing"] + [f"v {x:.6g} {y:.6g} {z:.6g}" for x, y, z in verts]
    lines += ["vt 0 0", "vn 0 0 1", "f 1/1/1 2/1/1 3/1/1", "f 2 3 4 5", "f -1 -2 -3", "s off"]
    return ("\n".join(lines) + "\n").encode()


def scan_file(rng) -> tuple[bytes, str]:
    from PIL import Image

    kind = rng.choice(["L", "LA", "P", "RGB", "RGBA", "I;16", "I", "F", "CMYK", "1", "exr"])
    if kind == "exr":
        from holo_core.io.image import write_exr

        with tempfile.TemporaryDirectory() as d:
            names = ("R", "G", "B") if rng.random() < 0.5 else ("Y",)
            path = write_exr(Path(d) / "s.exr", {n: rng.random((9, 11)) for n in names})
            return path.read_bytes(), ".exr"
    size = (11, 9)
    if kind in ("I", "F", "I;16"):
        a = rng.integers(0, 60000, size[::-1]).astype(
            {"I": np.int32, "F": np.float32, "I;16": np.uint16}[kind]
        )
        im = Image.fromarray(a)
    else:
        im = Image.fromarray(rng.integers(0, 256, size[::-1] + (3,), dtype=np.uint8))
        im = im.convert(kind)
    fmt = "TIFF" if kind in ("I", "F", "CMYK") or rng.random() < 0.3 else "PNG"
    out = io.BytesIO()
    im.save(out, fmt)
    return out.getvalue(), ".tif" if fmt == "TIFF" else ".png"


def lab_file(rng) -> tuple[bytes, str]:
    """A laboratory array as write_acquired writes it: .npy, HDF5 or MATLAB v7.3."""
    from holo_core.io.acquired import write_acquired
    from holo_core.scene.hologram import Hologram

    suffix = str(rng.choice([".npy", ".h5", ".mat"]))
    h = Hologram(
        intensity=rng.random((1, 9, 11)).astype(np.float32), wavelengths=(532e-9,), pitch=5e-6
    )
    with tempfile.TemporaryDirectory() as d:
        return write_acquired(Path(d) / f"a{suffix}", h).read_bytes(), suffix


# --- mutations --------------------------------------------------------------------------------


def bit_flips(data, rng):
    a = bytearray(data)
    for _ in range(int(rng.integers(1, 20))):
        i = int(rng.integers(len(a)))
        a[i] ^= 1 << int(rng.integers(8))
    return bytes(a)


def truncate(data, rng):
    return data[: int(rng.integers(len(data)))]


def splice(data, rng):
    """Random bytes over a random span (damaged blocks)."""
    i = int(rng.integers(len(data)))
    n = int(rng.integers(1, 64))
    return data[:i] + rng.integers(0, 256, n, dtype=np.uint8).tobytes() + data[i + n :]


TOKENS = [
    b"0",
    b"-1",
    b"nan",
    b"inf",
    b"-inf",
    b"1e308",
    b"4294967295",
    b"1000000000000",
    b"999999999999999999999",
    b"x",
    b"",
    b"3.5",
    b"list",
    b"float",
    b"ply",
    b"\xff\xfe",
]


PLY_FACE_LINES = [
    b"property int vertex_indices",
    b"property list uchar float vertex_indices",
    b"property list uchar int vertex_index",
    b"property uchar vertex_indices",
]


def ply_face_property(data, rng):
    """The face list declared otherwise: a scalar (the audit's TypeError), float indices, the
    other common name."""
    line = b"property list uchar int vertex_indices"
    return data.replace(line, PLY_FACE_LINES[int(rng.integers(len(PLY_FACE_LINES)))])


def token_edit(data, rng):
    """One whitespace-separated token of the text (or header) replaced by a hostile one."""
    parts = data.split(b" ")
    i = int(rng.integers(len(parts)))
    parts[i] = TOKENS[int(rng.integers(len(TOKENS)))] + (b"\n" if parts[i].endswith(b"\n") else b"")
    return b" ".join(parts)


def line_edit(data, rng):
    lines = data.split(b"\n")
    i = int(rng.integers(len(lines)))
    choice = rng.integers(4)
    if choice == 0:
        del lines[i]
    elif choice == 1:
        lines.insert(i, lines[int(rng.integers(len(lines)))])
    elif choice == 2:
        lines[i] = b"element junk 1000000000000"
    else:
        lines[i] = b"f 1" if rng.random() < 0.5 else b"v 1 2"
    return b"\n".join(lines)


def bom_or_encoding(data, rng):
    return (b"\xef\xbb\xbf" + data) if rng.random() < 0.5 else data.replace(b"fuzz", b"f\xe9\xff")


def huge_dimensions(data, rng):
    """EXR dataWindow or PNG IHDR size set to a huge value (a decompression bomb)."""
    big = int(rng.choice([100000, 2**20, 2**31 - 1]))
    key = b"dataWindow\x00box2i\x00"
    i = data.find(key)
    if i >= 0:
        at = i + len(key) + 4
        return data[: at + 8] + struct.pack("<ii", big, big) + data[at + 16 :]
    i = data.find(b"IHDR")
    if i >= 0:
        return data[: i + 4] + struct.pack(">II", big, big) + data[i + 12 :]
    return data


def metadata_edit(data, rng):
    """The hologram's JSON metadata edited: keys dropped, wrong types, NaN, bad ranges."""
    import OpenEXR

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "h.exr"
        path.write_bytes(data)
        try:  # an earlier mutation may have broken the file: then it stays as it is
            with OpenEXR.File(str(path), separate_channels=True, header_only=True) as f:
                lo, hi = f.header()["dataWindow"]
                if np.prod(hi - lo + 1.0) > 1e6:
                    return data
            with OpenEXR.File(str(path), separate_channels=True) as f:
                header = dict(f.header())
                chans = {n: np.array(c.pixels) for n, c in f.channels().items()}
            meta = json.loads(header["holo"])
        except Exception:  # noqa: BLE001
            return data
        audit = isinstance(meta, dict) and rng.random() < 0.3
        if audit:
            meta = _audit_edit(meta, rng)
        for _ in range(int(rng.integers(0 if audit else 1, 4))):
            meta = _edit(meta, rng)
            if rng.random() < 0.2:  # NaN or huge pixels
                name = sorted(chans)[int(rng.integers(len(chans)))]
                chans[name].flat[int(rng.integers(chans[name].size))] = rng.choice(
                    [np.nan, np.inf, -1.0, 3e38]
                )
        header["holo"] = json.dumps(meta) if rng.random() < 0.95 else "{not json"
        with OpenEXR.File(header, chans) as f:
            f.write(str(path))
        return path.read_bytes()


VALUES = [
    None,
    True,
    "text",
    [],
    {},
    [1, 2],
    0,
    -1,
    1e300,
    float("nan"),
    float("inf"),
    -0.0,
    0.5,
    2.0,
    3,
    [[0, 0, 0], [1, 1, 1]],
    list(range(16)),
    [1e-9, -1e-9],
    1e-300,
    1.0,
    [0.0, 0.0],
    [633e-9, 1e-300],
]

# the audit's findings: optics a file may hold in JSON but nothing can render
AUDIT_EDITS = [
    ("pitch_m", 1e-300),
    ("pitch_m", 1e300),
    ("band_sin", 1.0),
    ("band_sin", 1.5),
    ("wavelengths_m", [1e-300, 633e-9]),
    ("wavelengths_m", [1e300, 633e-9]),
    ("amplitudes", [0.0, 1.0]),
    ("amplitudes", [0.0, 0.0]),
]


def _audit_edit(meta, rng):
    key, value = AUDIT_EDITS[int(rng.integers(len(AUDIT_EDITS)))]
    if key == "amplitudes":
        reference = meta.get("reference")
        return {
            **meta,
            "reference": {**(reference if isinstance(reference, dict) else {}), key: value},
        }
    return {**meta, key: value}


def _edit(obj, rng):
    if isinstance(obj, dict) and obj:
        key = sorted(obj)[int(rng.integers(len(obj)))]
        what = rng.integers(4)
        if what == 0:
            return {k: v for k, v in obj.items() if k != key}
        if what == 1 and isinstance(obj[key], (dict, list)):
            return {**obj, key: _edit(obj[key], rng)}
        return {**obj, key: VALUES[int(rng.integers(len(VALUES)))]}
    if isinstance(obj, list) and obj:
        i = int(rng.integers(len(obj)))
        out = list(obj)
        out[i] = (
            VALUES[int(rng.integers(len(VALUES)))] if rng.random() < 0.7 else _edit(out[i], rng)
        )
        return out if rng.random() < 0.8 else out[:-1]
    return VALUES[int(rng.integers(len(VALUES)))]


MUTATIONS = {
    "hologram": [bit_flips, truncate, splice, huge_dimensions, metadata_edit, metadata_edit],
    "ply": [bit_flips, truncate, splice, token_edit, token_edit, line_edit, ply_face_property],
    "obj": [bit_flips, truncate, splice, token_edit, line_edit, bom_or_encoding],
    "scan": [bit_flips, truncate, splice, huge_dimensions],
    "lab": [bit_flips, truncate, splice, splice],
}


# --- tiled stores and display layouts: folders of files, damaged file by file ----------------


def _pristine_store(folder):
    """A valid tiled store of 2 x 3 tiles of 64² (two channels, the last column of tiles cut
    short) written through the store's own functions, and the samples it holds."""
    if "store" not in _CACHE:
        from holo_core.io import store
        from holo_core.io.files import Files
        from holo_core.plate.points import record_points
        from holo_core.plate.tiles import _recording
        from holo_core.scene.hologram import HologramInfo

        shape, tile, lams = (96, 160), 64, (633e-9, 532e-9)
        pos = np.array([[1e-4, -2e-4, -0.02], [-3e-4, 1e-4, -0.025]])
        cols = np.array([[1.0, 0.5], [0.3, 1.0]])
        h = record_points(pos, cols, shape=shape, pitch=8e-6, wavelengths=lams, method="direct")
        url = folder / "pristine.zarr"
        info = HologramInfo(
            shape=shape, encoding="complex", wavelengths=lams, pitch=8e-6, bounds=h.bounds
        )
        recording = _recording(
            pos,
            cols,
            None,
            0,
            method="direct",
            shape=shape,
            pitch=8e-6,
            band=None,
            wavelengths=lams,
            tile=tile,
        )
        with store.recording_into(Files(url), info, tile, recording) as plate:
            for i, j in np.ndindex(*store.tile_grid(shape, tile)):
                r0, r1, c0, c1 = store.tile_window(shape, tile, i, j)
                plate.write_tile(i, j, h.object_wave[:, r0:r1, c0:c1])
        _CACHE["store"] = url, np.asarray(h.object_wave)
    return _CACHE["store"]


def _bytes_of(mutate):
    def damage(path, rng):
        data = path.read_bytes()
        if data:  # an earlier damage may have emptied it
            path.write_bytes(mutate(data, rng) or b"")

    return damage


def _json_of(path):
    try:
        return json.loads(path.read_text())
    except (UnicodeDecodeError, ValueError, RecursionError):  # damaged already
        return None


def _json_edit(path, rng):
    doc = _json_of(path)
    if doc is not None:
        path.write_text(json.dumps(_edit(doc, rng)))


def _deep_json(path, rng):
    depth = int(rng.choice([100, 10_000, 1_000_000]))
    path.write_bytes(b'{"a": ' + b"[" * depth + b"]" * depth + b"}")


def _replaced(kind):
    def damage(path, rng):
        path.unlink()
        if kind == "fifo":
            os.mkfifo(path)
        elif kind == "folder":
            path.mkdir()
        elif kind == "zero":
            os.symlink("/dev/zero", path)
        elif kind == "outside":
            os.symlink(path.parents[len(path.parents) - 2] / "etc" / "hostname", path)

    return damage


def _swap(path, rng):
    """The bytes of another file of the store of the same kind (a chunk for a chunk)."""
    others = [
        p
        for p in path.parent.parent.rglob("*")
        if p.is_file()
        and not p.is_symlink()
        and p != path
        and p.stat().st_size == path.stat().st_size
    ]
    if others:
        path.write_bytes(others[int(rng.integers(len(others)))].read_bytes())


STORE_MUTATIONS = [
    _bytes_of(bit_flips),
    _bytes_of(truncate),
    _bytes_of(splice),
    _json_edit,
    _json_edit,
    _deep_json,
    _replaced("fifo"),
    _replaced("folder"),
    _replaced("zero"),
    _replaced("outside"),
    _replaced("missing"),
    _swap,
]


def store_case(rng, case, folder, hostile=True):
    """A copy of a valid store with one or two of its files damaged: reading it back gives
    exactly the samples recorded, or InputError naming the store."""
    import shutil

    pristine, wave = _pristine_store(folder)
    url = folder / "case.zarr"
    shutil.rmtree(url, ignore_errors=True)
    shutil.copytree(pristine, url, symlinks=True)
    for _ in range(int(rng.integers(1, 3)) if hostile else 0):
        files = sorted(p for p in url.rglob("*") if p.is_file() and not p.is_symlink())
        if files:
            target = files[int(rng.integers(len(files)))]
            STORE_MUTATIONS[int(rng.integers(len(STORE_MUTATIONS)))](target, rng)

    def call():
        from holo_core.io.tiled_wave import open_plate

        back = named(url, lambda u: open_plate(u).object_wave[...])
        assert np.array_equal(back, wave), "a damaged store read back other samples"

    call.label = f"case {case}"
    return call


def layout_case(rng, case, folder, hostile=True):
    """A display's layout and tiles with the layout's JSON or a tile damaged (a tile listed
    many times among the edits): read back as finite values of the layout's shape, or
    InputError naming the file."""
    from holo_core.io.display import write_tiles

    path = folder / f"layout{case}" / "p.json"
    write_tiles(
        path,
        rng.uniform(0, 2 * np.pi, (40, 50)),
        quantity="phase",
        pitch=4e-6,
        wavelength=633e-9,
        distance=-0.02,
        encoding="double-phase",
        tile=(16, 20),
    )
    for _ in range(int(rng.integers(1, 3)) if hostile else 0):
        choice = rng.integers(6)
        if choice == 0:  # a tile listed again, up to 300 times
            layout = _json_of(path)
            tiles = (
                layout["tiles"]
                if isinstance(layout, dict)
                and isinstance(layout.get("tiles"), list)
                and layout["tiles"]
                else None
            )
            if tiles:
                tiles += [tiles[int(rng.integers(len(tiles)))]] * int(rng.integers(1, 300))
                path.write_text(json.dumps(layout))
        elif choice == 1:
            _json_edit(path, rng)
        elif choice == 2:
            _deep_json(path, rng)
        else:
            target = sorted(path.parent.iterdir())[
                int(rng.integers(len(list(path.parent.iterdir()))))
            ]
            _bytes_of([bit_flips, truncate, splice][int(rng.integers(3))])(target, rng)

    def call():
        from holo_core.io.display import read_tiles

        values, layout = named(path, read_tiles)
        assert values.shape == tuple(layout["shape"]) and np.isfinite(values).all()

    call.label = f"case {case}"
    return call


# --- the readers and what a good result is -----------------------------------------------------


def read_case(reader, path):
    if reader == "hologram":
        from holo_core.io.hologram import read_hologram

        h = named(path, read_hologram)
        assert np.isfinite(h.intensity).all() and h.intensity.size
        usable(h)
    elif reader in ("ply", "obj"):
        from holo_core.io.mesh import read_mesh

        m = named(path, read_mesh)
        assert np.isfinite(m.vertices).all() and len(m.triangles)
        assert m.triangles.min() >= 0 and m.triangles.max() < len(m.vertices)
    else:
        from holo_core.io.acquired import read_acquired

        h = named(path, read_acquired, pitch=5e-6, wavelength=532e-9)
        assert h.intensity.ndim == 3 and len(h.intensity) == 1
        assert np.isfinite(h.intensity).all() and (h.intensity >= 0).all()


class Unnamed(Exception):
    """A reader's InputError that does not name the file."""


def named(path, reader, **kwargs):
    """``reader(path)``; its InputError must name the file."""
    from holo_core.validate import InputError

    try:
        return reader(path, **kwargs)
    except InputError as e:
        if str(path) not in str(e):
            raise Unnamed(str(e)) from None
        raise


def usable(h) -> None:
    """A hologram that reads must reconstruct and render finite: pitch 1e-300 passed the
    schema and rendered NaN, a zero reference amplitude reconstructed NaN."""
    from holo_core.optics.pupil import Pupil
    from holo_core.plate.reconstruction import reconstruct
    from holo_core.plate.view import render_view
    from holo_core.scene.camera import Camera, look_at

    for c in range(len(h.wavelengths)):
        assert np.isfinite(reconstruct(h, c)).all(), f"channel {c} reconstructs to NaN"
    plate = np.asarray(h.plate)  # the command line's default camera: 3 plate sizes in front
    centre = (plate @ np.append(np.asarray(h.bounds).mean(0), 1.0))[:3]
    eye = plate[:3, 3] + plate[:3, 2] * 3 * max(h.size)
    # pixels of λ/(plate size): the depth pair's pupil, and ours, span half the plate
    pixel = max(h.wavelengths) / min(h.size)
    cam = Camera(
        matrix_world=look_at(eye, centre, up=plate[:3, 1]),
        resolution=(4, 4),
        lens=50,
        sensor_width=50 * 4 * pixel,
    )
    view = render_view(h, cam, aperture=Pupil(diameter=min(h.size) / 2))
    assert all(np.isfinite(a).all() for a in (view.rgb, view.alpha, view.depth)), "NaN view"


# --- the writer: holograms of hostile fields are refused, or written and read back ------------

HOLOGRAM_VALUES = {
    "wavelengths": [
        (1e-300, 532e-9),
        (1e300, 532e-9),
        (633e-9,),
        (),
        (633e-9,) * 17,
        633e-9,
        (3e-3, 3e-3),
        (633e-9, float("nan")),
    ],
    "pitch": [1e-300, 1e300, 1e-12, 1e3, 1.1e-12, 8e-6],
    "reference_angle": [np.pi / 2, 1.5707, -0.1, 0.2],
    "reference_azimuth": [1e300, -7.0],
    "reference_amplitudes": [(0.0, 1.0), (1.0,), (1e-30, 1e30), (-1.0, 1.0)],
    "band": [0.999999, 1.0, 1.5, 0.3, -0.0],
    "bounds": [[[0, 0, 0], [-1, 0, 0]], [[0, 0, 0], [1, 1, 1]], np.full((2, 3), np.nan)],
    "channels": [("Z", "Y"), ("Y", "Z"), ("Q", "Y"), "YZ", ("R", "G", "B")],
    "point_density": [-1.0, 1e30, 0.0],
    "plate": [2 * np.eye(4), np.diag([1.0, 1.0, -1.0, 1.0]), np.eye(3)],
    "object_wave": [None, np.ones((2, 3, 3), np.complex64), np.full((2, 6, 8), np.nan + 0j)],
    "intensity": [
        np.zeros((2, 0, 4), np.float32),
        np.full((2, 6, 8), -1.0, np.float32),
        np.ones((6, 8), np.float32),
    ],
}


def hostile_hologram(rng, hostile=True) -> dict:
    """A valid hologram's fields with one to three replaced by hostile values."""
    shape = (2, 6, 8)
    fields = {
        "intensity": rng.random(shape, np.float32),
        "wavelengths": (633e-9, 632e-9),
        "pitch": 8e-6,
        "reference_angle": 0.02,
        "reference_amplitudes": (1.0, 1.0),
        "object_wave": (rng.normal(size=shape) + 1j).astype(np.complex64),
        "bounds": np.array([[-1, -1, -2], [1, 1, -1.0]]),
        "channels": ("Y", "Z"),
    }
    for _ in range(int(rng.integers(1, 4)) if hostile else 0):
        key = sorted(HOLOGRAM_VALUES)[int(rng.integers(len(HOLOGRAM_VALUES)))]
        pool = HOLOGRAM_VALUES[key] + VALUES
        fields[key] = pool[int(rng.integers(len(pool)))]
    return fields


def write_case(fields, path) -> None:
    from holo_core.io.hologram import metadata, read_hologram, write_hologram
    from holo_core.scene.hologram import Hologram

    h = Hologram(**fields)
    write_hologram(path, h)
    try:
        back = read_hologram(path)
    except Exception as e:  # noqa: BLE001 -- any failure here is the finding
        raise AssertionError(f"written but unreadable: {e}") from None
    assert metadata(back) == metadata(h), "read back other than written"
    path.unlink()


# --- the API: public calls with hostile arguments ---------------------------------------------

API_VALUES = [
    1e-300,
    1e300,
    -1e-9,
    1.5,
    0,
    (0, 0),
    (0.0, 0.0, 0.0),
    np.zeros((0, 0)),
    np.full((4, 4), np.nan),
    np.eye(3),
    np.eye(4),
    "x",
    [1.0, 2.0],
]


def api_calls():
    """(name, function, valid keyword arguments) of cheap public calls."""
    from holo_core import propagation as prop
    from holo_core.camera import render_camera
    from holo_core.plate.plan import plan
    from holo_core.plate.points import record_points
    from holo_core.plate.reconstruction import reconstruct
    from holo_core.plate.sampling import choose
    from holo_core.plate.view import render_view
    from holo_core.scene import Camera, Hologram, Mesh, look_at, sample_points
    from holo_core.scene.plate import ViewingZone

    field = np.ones((16, 16), np.complex64)
    wave = {"wavelength": 633e-9, "pitch": 1e-6}
    h = _fixture_hologram()
    cam = Camera(
        matrix_world=look_at((0, 0, 4e-3), (0, 0, -3e-3)), sensor_width=3.2, resolution=(4, 4)
    )
    tri = {
        "vertices": np.array([[0, 0, -1], [0.1, 0, -1], [0, 0.1, -1.0]]),
        "triangles": np.array([[0, 1, 2]]),
        "colours": np.ones((3, 3)),
    }
    return [
        (
            "angular_spectrum",
            prop.angular_spectrum,
            {"field": field, **wave, "distance": 1e-4, "offset": (0.0, 0.0), "padding": 2},
        ),
        (
            "rayleigh_sommerfeld",
            prop.rayleigh_sommerfeld,
            {"field": field[:8, :8], **wave, "distance": 1e-4},
        ),
        ("fresnel", prop.fresnel, {"field": field, **wave, "distance": 1e-4}),
        (
            "resample",
            prop.resample,
            {"field": field, "pitch": 1e-6, "out_shape": (8, 8), "out_pitch": 2e-6},
        ),
        ("tilt", prop.tilt, {"field": field, **wave, "rotation": np.eye(3), "padding": 2}),
        (
            "propagate_to_plane",
            prop.propagate_to_plane,
            {"field": field, **wave, "rotation": np.eye(3), "position": (0, 0, 1e-4)},
        ),
        (
            "record_points",
            record_points,
            {
                "positions": [[0, 0, -3e-3]],
                "colours": [[1.0]],
                "shape": (16, 16),
                "pitch": 1e-6,
                "wavelengths": (633e-9,),
                "seed": 0,
                "band": None,
            },
        ),
        ("reconstruct", reconstruct, {"hologram": h, "colour": 0}),
        (
            "render_view",
            render_view,
            {
                "holograms": h,
                "camera": cam,
                "supersample": 1,
                "exposure": None,
                "opacity_threshold": 0.5,
            },
        ),
        (
            "choose",
            choose,
            {
                "plate_size": (0.01, 0.01),
                "points": [[0, 0, -0.05]],
                "resolution": 64,
                "max_resolution": 64,
                "wavelength": None,
            },
        ),
        (
            "plan",
            plan,
            {
                "plate_size": (0.05, 0.05),
                "bounds": [[-0.01, -0.01, -0.31], [0.01, 0.01, -0.29]],
                "zone": ViewingZone.around((0, 0, 0.3), 0.01, 0.01),
                "pixel_angle": 5e-4,
                "supersample": 2,
                "looks": 2,
                "wavelength": None,
            },
        ),
        (
            "render_camera",
            render_camera,
            {
                "meshes": Mesh(**tri),
                "camera": Camera(matrix_world=look_at((0, 0, 0.5), (0, 0, -1)), resolution=(8, 8)),
                "samples": 1,
                "supersample": 1,
                "seed": 0,
                "exposure": 1.0,
                "via": "object_wave",
            },
        ),
        ("Mesh", Mesh, tri),
        (
            "sample_points",
            sample_points,
            {"mesh": Mesh(**tri), "spacing": 0.01, "seed": 0, "max_points": 100},
        ),
        ("look_at", look_at, {"eye": (0, 0, 1), "target": (0, 0, 0), "up": (0, 1, 0)}),
        (
            "Camera",
            Camera,
            {
                "matrix_world": np.eye(4),
                "lens": 50,
                "resolution": (8, 8),
                "shift_x": 0.0,
                "pixel_aspect": (1, 1),
            },
        ),
        (
            "Hologram",
            Hologram,
            {
                "intensity": np.ones((1, 4, 4), np.float32),
                "wavelengths": (633e-9,),
                "pitch": 8e-6,
                "band": 0.0,
            },
        ),
    ]


_CACHE = {}


def _fixture_hologram():
    if "h" not in _CACHE:
        from holo_core.plate import record_points

        _CACHE["h"] = record_points(
            [[0, 0, -3e-3]], [[1.0]], shape=(32, 32), pitch=1e-6, wavelengths=(633e-9,)
        )
    return _CACHE["h"]


def api_case(rng, hostile=True):
    """A call of :func:`api_calls` with one or two arguments hostile, and its result checked."""
    if "calls" not in _CACHE:
        _CACHE["calls"] = api_calls()
    name, function, good = _CACHE["calls"][int(rng.integers(len(_CACHE["calls"])))]
    kwargs, changed = dict(good), {}
    for _ in range(int(rng.integers(1, 3)) if hostile else 0):
        key = sorted(kwargs)[int(rng.integers(len(kwargs)))]
        pool = API_VALUES + VALUES
        kwargs[key] = changed[key] = pool[int(rng.integers(len(pool)))]

    def call():
        sane(function(**kwargs))

    call.label = f"{name}({', '.join(f'{k}={_short(v)}' for k, v in changed.items())})"
    return call


def _short(value) -> str:
    if isinstance(value, np.ndarray):
        return f"array{value.shape}"
    return repr(value)[:40]


def sane(result) -> None:
    """Every number a result holds is finite (a NaN result is a silent failure)."""
    from holo_core.scene.hologram import Hologram
    from holo_core.view import RenderResult

    if isinstance(result, RenderResult):
        result = (result.rgb, result.alpha, result.depth)
    if isinstance(result, Hologram):
        result = result.intensity
    if hasattr(result, "memory_bytes"):  # a plate's plan: every figure it states finite
        result = np.array(
            [
                result.pitch,
                result.row_pitch,
                result.wavelength,
                result.depth_wavelength,
                *result.band,
                result.memory_bytes(),
                result.disk_bytes(),
                result.record_seconds(),
            ]
        )
    if isinstance(result, (tuple, list)):
        for r in result:
            sane(r)
    elif isinstance(result, np.ndarray) and result.dtype.kind in "fc":
        assert np.isfinite(result).all(), "a result holds NaN or infinity"


# --- running --------------------------------------------------------------------------------


def make(reader, rng):
    if reader in ("scan", "lab"):
        return (scan_file if reader == "scan" else lab_file)(rng)
    return {"hologram": hologram_file, "ply": ply_file, "obj": obj_file}[reader](rng), {
        "hologram": ".exr",
        "ply": ".ply",
        "obj": ".obj",
    }[reader]


def next_case(target, case, rng, folder):
    """The case to run; one in ten is the valid file or call itself."""
    if target == "store":
        return store_case(rng, case, folder, case % 10)
    if target == "layout":
        return layout_case(rng, case, folder, case % 10)
    if target == "write":
        fields = hostile_hologram(rng, case % 10)
        return lambda: write_case(fields, folder / "h.exr")
    if target == "api":
        return api_case(rng, case % 10)
    data, suffix = make(target, rng)
    if case % 10:
        for _ in range(int(rng.integers(1, 3))):
            data = MUTATIONS[target][int(rng.integers(len(MUTATIONS[target])))](data, rng) or data
    path = folder / f"case{suffix}"
    path.write_bytes(data)
    return lambda: read_case(target, path)


def run(reader: str, cases: int, seed: int) -> dict:
    from holo_core.validate import InputError

    rng = np.random.default_rng([seed, sum(map(ord, reader))])
    counts, examples, slowest = Counter(), {}, 0.0
    with tempfile.TemporaryDirectory() as d:
        for case in range(cases):
            call = next_case(reader, case, rng, Path(d))
            start = time.perf_counter()
            signal.alarm(CASE_SECONDS)
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    call()
                outcome = "ok"
            except InputError:
                outcome = "InputError"
            except Hang:
                outcome = "hang"
            except BaseException as e:  # noqa: BLE001 -- every other ending is a finding
                outcome = f"other: {type(e).__name__}"
                label = getattr(call, "label", "")
                examples.setdefault(outcome, []).append(f"case {case}: {label} {str(e)[:200]}")
            finally:
                signal.alarm(0)
            slowest = max(slowest, time.perf_counter() - start)
            counts[outcome] += 1
    return {
        "reader": reader,
        "cases": cases,
        "seed": seed,
        "outcomes": dict(counts),
        "slowest_s": round(slowest, 3),
        "examples": {k: v[:10] for k, v in examples.items()},
    }


def main(argv):
    reader, cases, seed = argv[0], int(argv[1]), int(argv[2]) if len(argv) > 2 else 1
    os.environ["HOLO_MEMORY_LIMIT"] = MEMORY_BUDGET
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))

    def hang(*_):
        raise Hang()

    signal.signal(signal.SIGALRM, hang)
    print(json.dumps(run(reader, cases, seed)))


if __name__ == "__main__":
    main(sys.argv[1:])
