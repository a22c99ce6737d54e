"""A frame for a field-sequential display: every laser's pattern and layout written together,
the focal stack simulated from the quantised patterns and written beside them, and a scene
the display cannot show refused before a file is written."""

import json
import math

import numpy as np
import pytest

from holo_core.io import slm as slm_io
from holo_core.io.image import read_exr
from holo_core.phase.display import Display
from holo_core.phase.export import export_frame, laser_name
from holo_core.phase.slm import EyeBox, Laser, PhaseTable, SLMSetup
from holo_core.phase.stack import Optics
from holo_core.validate import InputError

WAVELENGTHS = (638e-9, 520e-9, 488e-9)


def setup(**kw):
    d = Display(name="lab-slm", resolution=(96, 64), pitch=8e-6, bit_depth=10)
    return SLMSetup(
        display=d,
        lasers=[Laser(wavelength=w, power=p) for w, p in zip(WAVELENGTHS, (0.03, 0.02, 0.01))],
        depth_range=(-6e-3, -2e-3),
        slices=4,
        **kw,
    )


def waves(rng, s):
    obj = rng.random((64, 96)) * np.exp(2j * np.pi * rng.random((64, 96)))
    out = []
    for w in WAVELENGTHS:
        op = Optics((64, 96), pitch=8e-6, wavelength=w, distances=[4e-3], band=1.0)
        out.append(op.to_plane(op.spectrum(obj), 0))
    return out


def test_a_frame_writes_each_lasers_pattern_and_the_stack(tmp_path, rng):
    k = np.arange(1024)
    tables = [
        PhaseTable(wavelength=w, phases=2.4 * math.pi * k / 1024, source=f"{i}.npy")
        for i, w in enumerate(WAVELENGTHS)
    ]
    s = setup(tables=tables)
    f = export_frame(waves(rng, s), s, tmp_path, stem="frame_0007", distance=-4e-3, frame=7)
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == sorted(
        [f"frame_0007_{laser_name(w)}.{x}" for w in WAVELENGTHS for x in ("png", "json")]
        + ["frame_0007_stack.exr", "frame_0007_stack.png"]
    )
    for w, p, table in zip(WAVELENGTHS, f.patterns, tables):
        codes, layout = slm_io.read_pattern(tmp_path / f"frame_0007_{laser_name(w)}.json")
        assert np.array_equal(codes, p.codes) and layout["packing"] == "packed10"
        assert layout["laser"]["wavelength"] == w and layout["table"] == table.source
        assert layout["response"] == pytest.approx(table.phases.tolist())
        assert layout["extra"]["frame"] == 7 and layout["distance"] == -4e-3
    header, channels = read_exr(tmp_path / "frame_0007_stack.exr")
    assert {"z00.R", "z03.B", "ref.z03.B"} <= set(channels)
    metrics = json.loads(header["holo_metrics"])
    assert metrics["638nm"]["psnr_db"] == pytest.approx(f.comparisons[0].psnr_db)
    assert all(np.isfinite(c.psnr_db).all() and len(c.ssim) == 4 for c in f.comparisons)


def test_a_scene_the_display_cannot_show_is_refused_before_any_file(tmp_path, rng):
    s = setup(eye_box=EyeBox(size=(30e-3, 30e-3), distance=0.3))
    with pytest.raises(InputError, match="eye box: 30 x 30 mm at 300 mm"):
        export_frame(waves(rng, s), s, tmp_path, stem="frame_0001")
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(InputError, match="one wave per laser"):
        export_frame(waves(rng, s)[:2], setup(), tmp_path)


def test_a_frame_is_bit_identical_whatever_came_before(tmp_path, rng):
    """Frame 1 written, then frame 2, then frame 1 again into another folder: the same bytes
    (the descent's planes are drawn from its seed, the FFTs are deterministic)."""
    s = setup()
    one, two = waves(rng, s), waves(rng, s)
    first, second = tmp_path / "a", tmp_path / "b"
    first.mkdir()
    second.mkdir()
    kw = dict(
        stem="frame_0001",
        method="gradient-descent",
        iterations=6,
        slices_per_step=2,
        simulate=False,
    )
    export_frame(one, s, first, **kw)
    export_frame(two, s, second, **kw)
    export_frame(one, s, second, **kw)
    for w in WAVELENGTHS:
        name = f"frame_0001_{laser_name(w)}.png"
        assert (first / name).read_bytes() == (second / name).read_bytes(), name
