"""The rendered view's multilayer EXR (Blender's naming) and the hologram's new metadata."""

import numpy as np
import pytest

from holo_core.io.hologram import read_hologram, write_hologram
from holo_core.io.view import write_view
from holo_core.plate.points import record_points
from holo_core.validate import InputError
from holo_core.view import RenderResult


def test_view_exr_has_blenders_multilayer_channels(tmp_path, rng):
    import OpenEXR

    rgb = rng.random((6, 8, 3)).astype(np.float32)
    alpha = (rng.random((6, 8)) > 0.5).astype(np.float32)
    depth = rng.uniform(1, 2, (6, 8)).astype(np.float32)
    exr, png = write_view(
        RenderResult(rgb=rgb, alpha=alpha, depth=depth), tmp_path / "v.exr", layer="Holo"
    )
    assert png.is_file() and png.read_bytes()[:4] == b"\x89PNG"
    with OpenEXR.File(str(exr), separate_channels=True) as f:
        ch = {n: np.array(c.pixels) for n, c in f.channels().items()}
    assert set(ch) == {
        "Holo.Combined.R",
        "Holo.Combined.G",
        "Holo.Combined.B",
        "Holo.Combined.A",
        "Holo.Depth.Z",
    }
    assert np.array_equal(ch["Holo.Combined.G"], rgb[..., 1] * alpha)  # premultiplied
    assert np.array_equal(ch["Holo.Depth.Z"], depth)  # row 0 stays the top row


def test_hologram_keeps_band_channels_and_density(tmp_path):
    h = record_points(
        [[0, 0, -1e-3]],
        [[1, 1]],
        shape=(16, 16),
        pitch=1e-6,
        wavelengths=(633e-9, 632e-9),
        channels=("Y", "Z"),
        band=0.05,
        point_density=4e6,
    )
    back = read_hologram(write_hologram(tmp_path / "h.exr", h))
    assert back.channels == ("Y", "Z") and back.depth_channel() == 1
    assert back.band == 0.05 and back.point_density == 4e6


def test_a_non_finite_view_is_not_written(tmp_path):
    view = RenderResult(
        rgb=np.full((2, 2, 3), np.nan, np.float32), alpha=np.ones((2, 2)), depth=np.ones((2, 2))
    )
    with pytest.raises(InputError, match="rgb is empty or not finite"):
        write_view(view, tmp_path / "v.exr")
    assert not list(tmp_path.iterdir())
