"""A hologram's description apart from its samples: one HologramInfo that Hologram, the file
reader, the tiled store and the recorder share, its fields checked when it is made and
nowhere else."""

import dataclasses

import numpy as np
import pytest

from holo_core.io.hologram import HologramFileError, metadata, read_hologram, write_hologram
from holo_core.plate.points import record_points
from holo_core.scene.hologram import Hologram, HologramInfo
from holo_core.scene.plate import ViewingZone
from holo_core.validate import InputError

GOOD = {"wavelengths": (633e-9,), "pitch": 8e-6, "shape": (4, 4)}


@pytest.mark.parametrize(
    "change, field",
    [
        ({"pitch": 1e-300}, "pitch"),
        ({"wavelengths": (1e9,)}, "wavelengths"),
        ({"wavelengths": ()}, "wavelengths"),
        ({"shape": (4, -1)}, "shape"),
        ({"shape": 4}, "shape"),
        ({"encoding": "phase"}, "encoding"),
        ({"encoding": "complex", "keeps_object_wave": False}, "keeps_object_wave"),
        ({"reference_amplitudes": (0.0,)}, "reference_amplitudes"),
        ({"reference_amplitudes": (1.0, 1.0)}, "reference_amplitudes"),
        ({"band": 1.0}, "band"),
        ({"point_density": -1.0}, "point_density"),
        ({"bounds": [[0, 0, 0], [-1, 0, 0]]}, "bounds"),
        ({"channels": ("Q",)}, "channels"),
        ({"channels": ("Z",)}, "channels"),
        ({"reference_angle": 2.0}, "reference_angle"),
        ({"plate": 2 * np.eye(4)}, "plate"),
        ({"zone": (0, 0, 1)}, "zone"),
    ],
)
def test_a_description_names_the_field_it_refuses(change, field):
    with pytest.raises(InputError, match=f"^{field} (rotation )?must"):
        HologramInfo(**{**GOOD, **change})


def test_a_description_needs_no_samples():
    """A 32768² plate described (a tiled store's, a recording's early check) holds no array."""
    info = HologramInfo(wavelengths=(532e-9,), pitch=4e-6, shape=(32768, 32768), encoding="complex")
    assert info.keeps_object_wave and info.size == pytest.approx((0.131072, 0.131072))
    assert info.channels == ("Y",) and info.colour_channels() == [0]
    assert not any(
        isinstance(getattr(info, f.name), np.ndarray) and getattr(info, f.name).size > 16
        for f in dataclasses.fields(info)
    )


def test_a_hologram_reads_its_description_and_its_samples_give_the_shape():
    h = Hologram(
        intensity=np.ones((1, 4, 6), np.float32), **{k: v for k, v in GOOD.items() if k != "shape"}
    )
    assert h.shape == h.info.shape == (4, 6) and h.pitch == h.info.pitch == 8e-6
    assert not h.info.keeps_object_wave
    wider = dataclasses.replace(h, intensity=np.ones((1, 4, 8), np.float32), band=0.25)
    assert wider.shape == (4, 8) and wider.band == 0.25 and h.band == 0.0
    with pytest.raises(InputError, match=r"intensity must be \(C, H, W\) with C = 1"):
        Hologram(info=h.info, intensity=np.ones((2, 4, 6), np.float32))


def test_a_file_is_checked_once_and_read_as_written(tmp_path, monkeypatch):
    """Reading a hologram builds its description once: no second check in Hologram."""
    zone = ViewingZone(centre=(0, 0, 0.01), half_extents=(1e-3, 1e-3, 1e-3))
    h = dataclasses.replace(
        record_points([[0, 0, -3e-3]], [[1.0]], shape=(32, 32), pitch=1e-6, wavelengths=(633e-9,)),
        zone=zone,
    )
    path = write_hologram(tmp_path / "h.exr", h)
    made = []
    check = HologramInfo.__post_init__
    monkeypatch.setattr(HologramInfo, "__post_init__", lambda self: made.append(check(self)))
    back = read_hologram(path)
    assert len(made) == 1, f"the description was checked {len(made)} times"
    assert metadata(back.info) == metadata(h) and back.zone.centre == zone.centre


def test_the_recorder_checks_the_description_before_it_records(monkeypatch):
    """A channel list that no hologram may hold is refused before any wave is summed."""
    summed = []
    monkeypatch.setattr("holo_core.plate.points.point_wave", lambda *a, **k: summed.append(1))
    with pytest.raises(InputError, match=r"^channels must name each"):
        record_points(
            [[0, 0, -3e-3]],
            [[1.0]],
            shape=(32, 32),
            pitch=1e-6,
            wavelengths=(633e-9,),
            channels=("R", "G"),
        )
    assert summed == []


def test_a_file_names_the_field_as_the_file_does(tmp_path):
    h = record_points([[0, 0, -3e-3]], [[1.0]], shape=(16, 16), pitch=1e-6, wavelengths=(633e-9,))
    info = dataclasses.replace(h.info)
    object.__setattr__(info, "point_density", -2.0)
    with pytest.raises(
        HologramFileError,
        match=r"h.exr: metadata point_density_per_m2 must "
        r"be >= 0",
    ):
        write_hologram(
            tmp_path / "h.exr",
            Hologram(info=info, intensity=h.intensity, object_wave=h.object_wave),
        )
    assert not list(tmp_path.iterdir())


def test_holograms_in_memory_are_held_to_the_file_schema():
    """A Hologram made in memory is held to the file's schema: the fields a file may not hold
    are refused when it is made."""
    good = {"intensity": np.ones((1, 4, 4), np.float32), "wavelengths": (633e-9,), "pitch": 8e-6}
    for change, field in [
        ({"pitch": 1e-300}, "pitch"),
        ({"wavelengths": (1e9,)}, "wavelengths"),
        ({"reference_amplitudes": (0.0,)}, "reference_amplitudes"),
        ({"band": 1.0}, "band"),
        ({"point_density": -1.0}, "point_density"),
        ({"bounds": [[0, 0, 0], [-1, 0, 0]]}, "bounds"),
        ({"channels": ("Q",)}, "channels"),
        ({"reference_angle": 2.0}, "reference_angle"),
    ]:
        with pytest.raises(InputError, match=field):
            Hologram(**{**good, **change})
