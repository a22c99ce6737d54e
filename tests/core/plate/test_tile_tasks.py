"""The tasks of a tiled recording (holo_core.plate.tile_tasks), run here one after another as
a Dask worker runs them: each tile written from the points whose cones reach it equals the
plate recorded whole in memory cut to its rows and columns (float32 rounding: 1e-5 of the
largest sample); a task of a recording the store no longer holds writes nothing."""

import numpy as np
import pytest

pytest.importorskip("zarr")

from holo_core.io import store
from holo_core.io.files import check_output
from holo_core.io.tiled_wave import open_plate
from holo_core.plate import tile_tasks, tiles
from holo_core.plate.points import point_amplitudes, record_points
from holo_core.scene.hologram import HologramInfo
from holo_core.validate import InputError

SHAPE, PITCH, TILE, WAVELENGTHS = (200, 264), 8e-6, 64, (633e-9, 532e-9)


def points(n=30, seed=5):
    rng = np.random.default_rng(seed)
    return np.c_[rng.uniform(-1e-3, 1e-3, (n, 2)), rng.uniform(-0.03, -0.02, n)], rng.uniform(
        0.2, 1, (n, len(WAVELENGTHS))
    )


def opened(url, positions, colours):
    """The store at ``url`` made for the points' recording, as the client opens it."""
    info = HologramInfo(shape=SHAPE, encoding="complex", wavelengths=WAVELENGTHS, pitch=PITCH)
    recording = tiles._recording(
        np.asarray(positions, np.float64),
        colours,
        None,
        0,
        method="direct",
        shape=SHAPE,
        pitch=PITCH,
        band=None,
        wavelengths=WAVELENGTHS,
        tile=TILE,
    )
    return store.recording_into(check_output(url), info, TILE, recording, overwrite=False)


def test_each_tile_is_the_whole_plate_cut_to_it(tmp_path):
    positions, colours = points()
    pos, _, amp = point_amplitudes(positions, colours, WAVELENGTHS, None, 0)
    url = tmp_path / "p.zarr"
    with opened(url, positions, colours) as plate:
        spec = {"urls": [str(url)], "recordings": [plate.recording["digest"]]}
        for i, j in np.ndindex(*store.tile_grid(SHAPE, TILE)):
            assert tile_tasks.record_tile((pos, amp), spec, i, j) == (i, j)
    whole = record_points(
        positions, colours, shape=SHAPE, pitch=PITCH, wavelengths=WAVELENGTHS, method="direct"
    ).object_wave
    tiled = open_plate(url).object_wave[...]
    err = float(np.abs(tiled - whole).max() / np.abs(whole).max())
    assert err < 1e-5, f"tiles against the plate recorded whole: {err:.2e}"


def test_a_task_of_a_recording_the_store_no_longer_holds_writes_nothing(tmp_path):
    positions, colours = points()
    pos, _, amp = point_amplitudes(positions, colours, WAVELENGTHS, None, 0)
    url = tmp_path / "p.zarr"
    with opened(url, positions, colours):
        pass
    before = {p: p.read_bytes() for p in url.rglob("*") if p.is_file()}
    with pytest.raises(InputError, match=r"now holds another recording; tile \(1, 2\)"):
        tile_tasks.record_tile((pos, amp), {"urls": [str(url)], "recordings": ["ab" * 32]}, 1, 2)
    assert {p: p.read_bytes() for p in url.rglob("*") if p.is_file()} == before
