"""Seeded fuzzing of the readers: valid files made here, mutated, each read once.

Every case must end in a result (checked for sanity) or the project's InputError, within
``CASE_SECONDS`` and under an address-space limit; anything else is a finding. Run as
``python tools/fuzz.py READER CASES SEED`` (READER: hologram, ply, obj, scan); it prints one
JSON line: the outcome counts and up to 10 examples of each failure kind.
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
ADDRESS_SPACE = 6 * 2**30   # the process's limit: a runaway allocation fails, not the machine
MEMORY_BUDGET = "512M"      # HOLO_MEMORY_LIMIT: the readers' own checks refuse before that


class Hang(Exception):
    pass


# --- valid files ------------------------------------------------------------------------------

def hologram_file(rng) -> bytes:
    from holo_core.io.hologram import write_hologram
    from holo_core.scene.hologram import Hologram
    shape = (2, 12, 16)
    plate = np.eye(4)
    plate[:3, 3] = rng.normal(size=3)
    h = Hologram(intensity=rng.random(shape, np.float32), wavelengths=(633e-9, 632e-9),
                 pitch=8e-6, reference_angle=0.02, reference_amplitudes=(1.0, 1.0),
                 object_wave=(rng.normal(size=shape) + 1j).astype(np.complex64), plate=plate,
                 bounds=np.array([[-1, -1, -2], [1, 1, -1.0]]), channels=("Y", "Z"))
    with tempfile.TemporaryDirectory() as d:
        return write_hologram(Path(d) / "h.exr", h).read_bytes()


def ply_file(rng) -> bytes:
    verts = rng.normal(size=(6, 3))
    faces = [[0, 1, 2], [2, 3, 4, 5], [1, 3, 5]]
    colours = rng.integers(0, 256, (6, 3))
    fmt = rng.choice(["ascii", "binary_little_endian", "binary_big_endian"])
    head = (f"ply\nformat {fmt} 1.0\ncomment fuzz\nelement vertex 6\nproperty float x\n"
            f"property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
            f"property uchar blue\nelement face 3\nproperty list uchar int vertex_indices\n"
            f"end_header\n").encode()
    if fmt == "ascii":
        rows = [" ".join(f"{x:.6g}" for x in v) + " " + " ".join(map(str, c))
                for v, c in zip(verts, colours)]
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
        a = rng.integers(0, 60000, size[::-1]).astype({"I": np.int32, "F": np.float32,
                                                      "I;16": np.uint16}[kind])
        im = Image.fromarray(a)
    else:
        im = Image.fromarray(rng.integers(0, 256, size[::-1] + (3,), dtype=np.uint8))
        im = im.convert(kind)
    fmt = "TIFF" if kind in ("I", "F", "CMYK") or rng.random() < 0.3 else "PNG"
    out = io.BytesIO()
    im.save(out, fmt)
    return out.getvalue(), ".tif" if fmt == "TIFF" else ".png"


# --- mutations --------------------------------------------------------------------------------

def bit_flips(data, rng):
    a = bytearray(data)
    for _ in range(int(rng.integers(1, 20))):
        i = int(rng.integers(len(a)))
        a[i] ^= 1 << int(rng.integers(8))
    return bytes(a)


def truncate(data, rng):
    return data[:int(rng.integers(len(data)))]


def splice(data, rng):
    """Random bytes over a random span (damaged blocks)."""
    i = int(rng.integers(len(data)))
    n = int(rng.integers(1, 64))
    return data[:i] + rng.integers(0, 256, n, dtype=np.uint8).tobytes() + data[i + n:]


TOKENS = [b"0", b"-1", b"nan", b"inf", b"-inf", b"1e308", b"4294967295", b"1000000000000",
          b"999999999999999999999", b"x", b"", b"3.5", b"list", b"float", b"ply", b"\xff\xfe"]


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
        return data[:at + 8] + struct.pack("<ii", big, big) + data[at + 16:]
    i = data.find(b"IHDR")
    if i >= 0:
        return data[:i + 4] + struct.pack(">II", big, big) + data[i + 12:]
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
        for _ in range(int(rng.integers(1, 4))):
            meta = _edit(meta, rng)
            if rng.random() < 0.2:  # NaN or huge pixels
                name = sorted(chans)[int(rng.integers(len(chans)))]
                chans[name].flat[int(rng.integers(chans[name].size))] = rng.choice(
                    [np.nan, np.inf, -1.0, 3e38])
        header["holo"] = json.dumps(meta) if rng.random() < 0.95 else "{not json"
        with OpenEXR.File(header, chans) as f:
            f.write(str(path))
        return path.read_bytes()


VALUES = [None, True, "text", [], {}, [1, 2], 0, -1, 1e300, float("nan"), float("inf"), -0.0,
          0.5, 2.0, 3, [[0, 0, 0], [1, 1, 1]], list(range(16)), [1e-9, -1e-9]]


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
        out[i] = VALUES[int(rng.integers(len(VALUES)))] if rng.random() < 0.7 else \
            _edit(out[i], rng)
        return out if rng.random() < 0.8 else out[:-1]
    return VALUES[int(rng.integers(len(VALUES)))]


MUTATIONS = {
    "hologram": [bit_flips, truncate, splice, huge_dimensions, metadata_edit, metadata_edit],
    "ply": [bit_flips, truncate, splice, token_edit, token_edit, line_edit],
    "obj": [bit_flips, truncate, splice, token_edit, line_edit, bom_or_encoding],
    "scan": [bit_flips, truncate, splice, huge_dimensions],
}


# --- the readers and what a good result is -----------------------------------------------------

def read_case(reader, path):
    if reader == "hologram":
        from holo_core.io.hologram import read_hologram
        h = read_hologram(path)
        assert np.isfinite(h.intensity).all() and h.intensity.size
    elif reader in ("ply", "obj"):
        from holo_core.io.mesh import read_mesh
        m = read_mesh(path)
        assert np.isfinite(m.vertices).all() and len(m.triangles)
        assert m.triangles.min() >= 0 and m.triangles.max() < len(m.vertices)
    else:
        from holo_core.io.hologram import import_acquired
        h = import_acquired(path, pitch=5e-6, wavelength=532e-9)
        assert h.intensity.ndim == 3 and len(h.intensity) == 1
        assert np.isfinite(h.intensity).all() and (h.intensity >= 0).all()


def make(reader, rng):
    if reader == "scan":
        return scan_file(rng)
    return {"hologram": hologram_file, "ply": ply_file, "obj": obj_file}[reader](rng), \
        {"hologram": ".exr", "ply": ".ply", "obj": ".obj"}[reader]


def run(reader: str, cases: int, seed: int) -> dict:
    from holo_core.validate import InputError
    rng = np.random.default_rng([seed, sum(map(ord, reader))])
    counts, examples, slowest = Counter(), {}, 0.0
    with tempfile.TemporaryDirectory() as d:
        for case in range(cases):
            data, suffix = make(reader, rng)
            if case % 10:  # one case in ten is the valid file itself
                for _ in range(int(rng.integers(1, 3))):
                    data = MUTATIONS[reader][int(rng.integers(len(MUTATIONS[reader])))](
                        data, rng) or data
            path = Path(d) / f"case{suffix}"
            path.write_bytes(data)
            start = time.perf_counter()
            signal.alarm(CASE_SECONDS)
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    read_case(reader, path)
                outcome = "ok"
            except InputError:
                outcome = "InputError"
            except Hang:
                outcome = "hang"
            except BaseException as e:  # noqa: BLE001 -- every other ending is a finding
                outcome = f"other: {type(e).__name__}"
                examples.setdefault(outcome, []).append(f"case {case}: {str(e)[:200]}")
            finally:
                signal.alarm(0)
            slowest = max(slowest, time.perf_counter() - start)
            counts[outcome] += 1
    return {"reader": reader, "cases": cases, "seed": seed, "outcomes": dict(counts),
            "slowest_s": round(slowest, 3), "examples": {k: v[:10] for k, v in examples.items()}}


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
