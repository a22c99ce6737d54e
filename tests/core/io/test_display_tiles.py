"""A display's pattern as 16-bit tiles and a JSON layout: the codes come back exactly, the
tiles' offsets put each in its place, and a failed write leaves nothing behind."""

import json
import math

import numpy as np
import pytest

from holo_core.io import display as tiles_io
from holo_core.validate import InputError

SETTINGS = {"pitch": 3.74e-6, "wavelength": 633e-9, "distance": -0.02, "encoding": "double-phase"}


def values(rng, quantity, shape=(37, 53)):
    """Phases spanning several turns [rad], or amplitudes in [0, 1]."""
    if quantity == "phase":
        return rng.uniform(-3 * math.pi, 3 * math.pi, shape)
    return rng.uniform(0, 1, shape)


@pytest.mark.parametrize("fmt", ["png", "tiff"])
@pytest.mark.parametrize("quantity", ["phase", "amplitude"])
@pytest.mark.parametrize("bits", [16, 8])
def test_tiles_and_layout_round_trip_exactly(tmp_path, rng, fmt, quantity, bits):
    """Read back, the pattern is the quantised one to the last bit, each tile holds the codes
    of its window, and writing what was read gives the same codes (nothing drifts)."""
    v = values(rng, quantity)
    path = tmp_path / "plate.json"
    tiles_io.write_tiles(
        path, v, quantity=quantity, bit_depth=bits, tile=(16, 20), fmt=fmt, **SETTINGS
    )
    back, layout = tiles_io.read_tiles(path)
    codes = tiles_io.to_codes(v, quantity, bits)
    assert np.array_equal(back, tiles_io.from_codes(codes, quantity))
    assert np.array_equal(tiles_io.to_codes(back, quantity, bits), codes)
    assert len(layout["tiles"]) == 3 * 3  # 37 rows in 16s, 53 cols in 20s
    for t in layout["tiles"]:
        window = codes[t["row"] : t["row"] + t["rows"], t["col"] : t["col"] + t["cols"]]
        assert np.array_equal(tiles_io.read_tile(tmp_path / t["file"]), window), t


def test_the_layout_says_what_a_printer_needs(tmp_path, rng):
    path = tiles_io.write_tiles(
        tmp_path / "p.json",
        values(rng, "phase"),
        quantity="phase",
        bit_depth=8,
        display="holoeye-gaea-4k",
        **SETTINGS,
    )
    layout = json.loads(path.read_text())
    assert (layout["pitch"], layout["wavelength"], layout["distance"]) == (3.74e-6, 633e-9, -0.02)
    assert layout["encoding"] == "double-phase" and layout["display"] == "holoeye-gaea-4k"
    assert layout["shape"] == [37, 53] and layout["bit_depth"] == 8
    assert layout["quantisation"]["step"] == 2 * math.pi / 65536
    assert layout["tiles"] == [{"file": "p_r0_c0.png", "row": 0, "col": 0, "rows": 37, "cols": 53}]


def test_quantisation_is_the_nearest_level():
    """Phase: 2^b levels over a turn, 2π wraps to 0, an error of at most half a level;
    amplitude: 2^b − 1 steps from 0 to 1, both ends exact."""
    phi = np.linspace(-2 * math.pi, 4 * math.pi, 10001)
    for bits in (8, 16):
        codes = tiles_io.to_codes(phi, "phase", bits)
        assert np.all(codes % 2 ** (16 - bits) == 0)
        err = np.angle(np.exp(1j * (tiles_io.from_codes(codes, "phase") - phi)))
        assert np.abs(err).max() <= math.pi / 2**bits * (1 + 1e-9), np.abs(err).max()
    assert tiles_io.to_codes([2 * math.pi - 1e-9, 0.0], "phase").tolist() == [0, 0]
    a = np.linspace(0, 1, 1001)
    codes = tiles_io.to_codes(a, "amplitude", 8)
    assert codes[0] == 0 and codes[-1] == 65535 and np.all(codes % 257 == 0)
    assert np.abs(tiles_io.from_codes(codes, "amplitude") - a).max() <= 0.5 / 255 + 1e-12


def test_a_failed_write_leaves_the_old_set(tmp_path, rng, monkeypatch):
    """The tiles and the layout are renamed together: a write that fails at its second tile
    leaves the earlier set whole and no temporary file."""
    path = tmp_path / "p.json"
    tiles_io.write_tiles(path, values(rng, "phase"), quantity="phase", tile=(20, 60), **SETTINGS)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    calls = []

    def failing(codes, fmt):
        calls.append(1)
        if len(calls) == 2:
            raise OSError("disk full")
        return b"partial"

    monkeypatch.setattr(tiles_io, "tile_bytes", failing)
    with pytest.raises(OSError, match="disk full"):
        tiles_io.write_tiles(
            path, values(rng, "phase"), quantity="phase", tile=(20, 60), **SETTINGS
        )
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


@pytest.mark.parametrize(
    "change, field",
    [
        ({"values": np.full((4, 4), 1.5)}, "amplitude values"),
        ({"pitch": 3.74}, "pitch"),
        ({"wavelength": 633}, "wavelength"),
        ({"distance": float("nan")}, "distance"),
        ({"tile": (0, 5)}, "tile"),
        ({"fmt": "jpg"}, "fmt"),
        ({"bit_depth": 17}, "bit_depth"),
        ({"quantity": "intensity"}, "quantity"),
        ({"encoding": ""}, "encoding"),
        ({"values": np.ones((4, 4)) * 0.5j}, "values"),
        ({"path": "p.png"}, "json"),
    ],
)
def test_bad_settings_are_refused_naming_the_field(tmp_path, change, field):
    kw = dict(SETTINGS, path=tmp_path / "p.json", values=np.full((4, 4), 0.5), quantity="amplitude")
    kw.update(change)
    if not isinstance(kw["path"], type(tmp_path)):
        kw["path"] = tmp_path / kw["path"]
    with pytest.raises(InputError, match=field):
        tiles_io.write_tiles(kw.pop("path"), kw.pop("values"), **kw)
    assert not list(tmp_path.iterdir())


def test_damaged_sets_are_refused_naming_the_file(tmp_path, rng):
    path = tiles_io.write_tiles(
        tmp_path / "p.json", values(rng, "phase"), quantity="phase", tile=(20, 60), **SETTINGS
    )
    layout = json.loads(path.read_text())

    def rewrite(**tile0):
        changed = dict(layout, tiles=[dict(layout["tiles"][0], **tile0)] + layout["tiles"][1:])
        path.write_text(json.dumps(changed))

    rewrite(file="../elsewhere.png")
    with pytest.raises(InputError, match="plain file name"):
        tiles_io.read_tiles(path)
    rewrite(row=1)  # overlaps the next tile, leaves row 0 bare
    with pytest.raises(InputError, match="exactly once"):
        tiles_io.read_tiles(path)
    rewrite(rows=10)
    with pytest.raises(InputError, match="the layout says"):
        tiles_io.read_tiles(path)
    rewrite(file="missing.png")
    with pytest.raises(InputError, match="no such tile"):
        tiles_io.read_tiles(path)
    path.write_text("{")
    with pytest.raises(InputError, match="not a JSON layout"):
        tiles_io.read_tiles(path)
    path.write_text(json.dumps({k: v for k, v in layout.items() if k != "pitch"}))
    with pytest.raises(InputError, match="lacks the field 'pitch'"):
        tiles_io.read_tiles(path)
    (tmp_path / "p_r0_c0.png").write_bytes(b"not a png")
    path.write_text(json.dumps(layout))
    with pytest.raises(InputError, match=r"p_r0_c0\.png: not a readable"):
        tiles_io.read_tiles(path)


def test_a_tile_listed_257_times_is_refused_not_counted_round(tmp_path, rng):
    """A uint8 coverage count wrapped at 256: one tile listed 257 times counted once and the
    layout passed. Each sample now belongs to one tile: the second listing is refused, before
    its file is read."""
    path = tiles_io.write_tiles(
        tmp_path / "p.json", values(rng, "phase", (8, 8)), quantity="phase", **SETTINGS
    )
    layout = json.loads(path.read_text())
    path.write_text(json.dumps(dict(layout, tiles=layout["tiles"] * 257)))
    with pytest.raises(
        InputError,
        match=r"p.json: the tiles do not cover the 8x8 grid exactly "
        r"once: tile p_r0_c0.png \(row 0, col 0\) covers",
    ):
        tiles_io.read_tiles(path)


def test_a_deeply_nested_layout_is_the_projects_error(tmp_path):
    path = tmp_path / "p.json"
    path.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(InputError, match=r"p.json: not a JSON layout \(RecursionError"):
        tiles_io.read_tiles(path)
    path.write_text(" " * (tiles_io.MAX_LAYOUT_BYTES + 1))
    with pytest.raises(InputError, match=r"p.json: \d+ bytes; a layout of 4096 tiles"):
        tiles_io.read_tiles(path)
