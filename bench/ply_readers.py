"""PLY readers: holo's own (holo_core.io.mesh.read_mesh) against plyfile, the well-kept
library for the format, on speed and on the fuzz suite's mutated files, in one run.

    python bench/ply_readers.py      (needs: pip install plyfile; not a dependency of holo)

plyfile is measured, not used: plyfile >= 1.1 requires NumPy 2, which bpy 5.0 (NumPy < 2) and
Blender's bundled Python cannot load, and the figures below decide the rest.
"""

import sys
import tempfile
import time
import warnings
from collections import Counter
from pathlib import Path

import numpy as np
import results  # the bench folder's own: the figures as data

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))

import fuzz

from holo_core.io.mesh import read_mesh
from holo_core.validate import InputError

FACES = 1_000_000
CASES = 2000


def big_ply(path: Path) -> None:
    """A binary little-endian PLY of a 1000x500 grid: 500k vertices, ~1M triangles."""
    n, m = 1000, 500
    y, x = np.mgrid[0:m, 0:n].astype(np.float32)
    verts = np.stack([x.ravel(), y.ravel(), np.zeros(n * m, np.float32)], 1)
    idx = np.arange(n * m).reshape(m, n)
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]
    tris = np.concatenate(
        [np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)]
    )
    rows = np.zeros(len(tris), [("n", "u1"), ("v", "<i4", (3,))])
    rows["n"], rows["v"] = 3, tris
    head = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(verts)}\n"
        f"property float x\nproperty float y\nproperty float z\nelement face {len(tris)}\n"
        f"property list uchar int vertex_indices\nend_header\n"
    ).encode()
    path.write_bytes(head + verts.astype("<f4").tobytes() + rows.tobytes())


def plyfile_mesh(path):
    from plyfile import PlyData

    data = PlyData.read(str(path))
    v = data["vertex"]
    verts = np.stack([v["x"], v["y"], v["z"]], 1)
    faces = [np.asarray(f) for f in data["face"]["vertex_indices"]]
    return verts, faces


def timed(read, path, repeats=3):
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        read(path)
        best = min(best, time.perf_counter() - start)
    return best


def fuzz_outcomes(read, clear):
    rng = np.random.default_rng([20261122, 1])
    counts = Counter()
    with tempfile.TemporaryDirectory() as d:
        for case in range(CASES):
            data, suffix = fuzz.make("ply", rng)
            if case % 10:
                for _ in range(int(rng.integers(1, 3))):
                    data = fuzz.MUTATIONS["ply"][int(rng.integers(6))](data, rng) or data
            path = Path(d) / "case.ply"
            path.write_bytes(data)
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    read(path)
                counts["ok"] += 1
            except clear:
                counts["clear error"] += 1
            except Exception as e:  # noqa: BLE001
                counts[type(e).__name__] += 1
    return dict(counts)


def main():
    from plyfile import PlyParseError

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "grid.ply"
        big_ply(path)
        ours, theirs = timed(read_mesh, path), timed(plyfile_mesh, path)
        print(
            f"1M-triangle binary PLY: holo {ours:.3f} s, plyfile {theirs:.3f} s "
            f"(plyfile/holo = {theirs / ours:.2f})"
        )
    holo, other = fuzz_outcomes(read_mesh, InputError), fuzz_outcomes(plyfile_mesh, PlyParseError)
    print(f"fuzz, {CASES} mutated PLYs: holo {holo}")
    print(f"fuzz, {CASES} mutated PLYs: plyfile {other}")
    results.write(
        "ply_readers",
        {
            "1M-triangle binary PLY, holo [s]": ours,
            "… plyfile [s]": theirs,
            "plyfile / holo": theirs / ours,
            f"{CASES} mutated PLYs, holo": str(holo),
            f"{CASES} mutated PLYs, plyfile": str(other),
        },
    )


if __name__ == "__main__":
    main()
