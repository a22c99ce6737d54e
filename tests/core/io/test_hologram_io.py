"""The hologram file: bit-exact round trip, and a clear error for each bad file."""

import json

import numpy as np
import pytest

from holo_core.io.hologram import (
    FORMAT_VERSION,
    HologramFileError,
    import_acquired,
    read_hologram,
    write_hologram,
)
from holo_core.io.image import write_png
from holo_core.scene.hologram import Hologram


@pytest.fixture
def hologram(rng):
    shape = (3, 24, 40)
    return Hologram(intensity=rng.random(shape, np.float32), wavelengths=(633e-9, 532e-9, 473e-9),
                    pitch=8e-6, reference_angle=0.02, reference_azimuth=0.5,
                    reference_amplitudes=(1.0, 2.0, 3.0),
                    object_wave=(rng.standard_normal(shape) + 1j * rng.standard_normal(shape)
                                 ).astype(np.complex64),
                    plate=_pose(0.5, [1.0, -2.0, 3.0]), bounds=np.array([[-1, -2, -3], [1, 2, -1.0]]))


def _pose(angle, shift):
    c, s = np.cos(angle), np.sin(angle)
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    m[:3, 3] = shift
    return m


def test_round_trip_is_bit_exact(tmp_path, hologram):
    back = read_hologram(write_hologram(tmp_path / "h.exr", hologram))
    assert back.intensity.tobytes() == hologram.intensity.tobytes()
    assert back.object_wave.tobytes() == hologram.object_wave.tobytes()
    for name in ("wavelengths", "pitch", "reference_angle", "reference_azimuth",
                 "reference_amplitudes"):
        assert getattr(back, name) == getattr(hologram, name), name
    assert np.array_equal(back.plate, hologram.plate) and np.array_equal(back.bounds, hologram.bounds)
    assert not list(tmp_path.glob(".*")), "temporary file left behind"


def test_missing_and_non_exr_files(tmp_path):
    with pytest.raises(HologramFileError, match="no such file"):
        read_hologram(tmp_path / "absent.exr")
    bad = tmp_path / "text.exr"
    bad.write_text("not an image")
    with pytest.raises(HologramFileError, match=f"{bad}: not an OpenEXR file"):
        read_hologram(bad)


def test_truncated_file(tmp_path, hologram):
    path = write_hologram(tmp_path / "h.exr", hologram)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(HologramFileError, match="h.exr"):
        read_hologram(path)


def _rewrite(path, header_change=None, drop=None):
    import OpenEXR
    with OpenEXR.File(str(path)) as f:
        header = dict(f.header())
        chans = {n: np.array(c.pixels) for n, c in f.channels().items() if n != drop}
    if header_change:
        header["holo"] = json.dumps(header_change(json.loads(header["holo"])))
    with OpenEXR.File(header, chans) as f:
        f.write(str(path))


def test_unknown_version_and_missing_channel(tmp_path, hologram):
    path = write_hologram(tmp_path / "h.exr", hologram)
    _rewrite(path, header_change=lambda m: {**m, "format_version": FORMAT_VERSION + 1})
    with pytest.raises(HologramFileError, match=f"format version {FORMAT_VERSION + 1} is not supported"):
        read_hologram(path)
    path = write_hologram(tmp_path / "h.exr", hologram)
    _rewrite(path, drop="c1.H")
    with pytest.raises(HologramFileError, match=r"missing channel\(s\) c1.H"):
        read_hologram(path)


def test_import_acquired_png(tmp_path, rng):
    grey = rng.random((20, 30))
    write_png(tmp_path / "scan.png", grey)
    h = import_acquired(tmp_path / "scan.png", pitch=5e-6, wavelength=532e-9, reference_angle=0.01)
    assert h.shape == (20, 30) and h.wavelengths == (532e-9,) and h.pitch == 5e-6
    err = np.abs(h.intensity[0] - grey).max()
    assert err <= 0.5 / 255 + 1e-7, f"8-bit grey image read back off by {err:.2e}"
    with pytest.raises(ValueError, match=r"pitch must be in \[1e-08, 0.01\] \[m\]; got 0"):
        import_acquired(tmp_path / "scan.png", pitch=0, wavelength=532e-9)
