"""A plate under its name is current only as the recording it must be: a plate file or tiled
store that another recording made (a folder synced from another shot, a file copied by hand)
is not current, so it is recorded again instead of rendered."""

import json

import numpy as np
import pytest

from holo_core.io.digests import digest_of
from holo_core.io.files import Files
from holo_core.io.hologram import HologramFileError, read_hologram, recording_of, write_hologram
from holo_core.io.image import exr_attribute, read_exr, write_exr
from holo_core.io.plate_paths import plate_current, store_of
from holo_core.scene.hologram import Hologram

OURS, THEIRS = "0123456789abcdef", "fedcba9876543210"


def plate(recording="") -> Hologram:
    wave = (np.arange(64 * 64).reshape(1, 64, 64) * (1 - 1j)).astype(np.complex64)
    return Hologram(
        object_wave=wave, encoding="complex", wavelengths=(633e-9,), pitch=8e-6, recording=recording
    )


def test_a_plate_file_carries_its_recording_and_is_current_only_as_it(tmp_path):
    path = write_hologram(tmp_path / "p_hologram_0123.exr", plate(OURS))
    assert read_hologram(path).recording == OURS and recording_of(path) == OURS
    assert plate_current(path) and plate_current(path, OURS)
    write_hologram(path, plate(THEIRS))  # another scene's valid plate under this name
    assert not plate_current(path, OURS)
    write_hologram(path, plate())  # an earlier file names none: not known to be ours
    assert recording_of(path) == "" and not plate_current(path, OURS)


def test_a_damaged_plate_file_is_left_to_the_reader_which_names_it(tmp_path):
    """A file whose description cannot be read is not recorded over (a half-copied plate
    would vanish unsaid): it counts as current, and reading it is refused naming the file."""
    path = tmp_path / "p_hologram_0123.exr"
    path.write_bytes(b"not an exr")
    assert recording_of(path) is None and plate_current(path, OURS)
    with pytest.raises(HologramFileError, match=r"p_hologram_0123\.exr: not an OpenEXR file"):
        read_hologram(path)


def test_a_tiled_store_carries_its_recording_and_is_current_only_as_it(tmp_path):
    pytest.importorskip("zarr")
    from holo_core.io import store

    path = tmp_path / "p.exr"
    for recording, current in ((THEIRS, False), (OURS, True)):
        h = plate(recording)
        with store.recording_into(
            Files(store_of(path)),
            h.info,
            64,
            {"digest": digest_of({"r": recording}), "parts": {}},
            overwrite=True,
        ) as s:
            s.write_tile(0, 0, h.object_wave)
        assert plate_current(path) and plate_current(path, OURS) == current


def test_a_recording_that_is_not_a_digest_is_refused_by_name(tmp_path):
    with pytest.raises(
        ValueError,
        match=r"recording must be the recording's digest \(up to 64 "
        r"hexadecimal digits\) or ''; got 'not hex!'",
    ):
        plate("not hex!")
    path = write_hologram(tmp_path / "p.exr", plate(OURS))
    meta = json.loads(exr_attribute(path, "holo"))
    _, channels = read_exr(path)
    write_exr(path, channels, holo=json.dumps({**meta, "recording": 7}))
    with pytest.raises(
        HologramFileError,
        match=rf"{path}: metadata recording must be the "
        rf"recording's digest",
    ):
        read_hologram(path)
