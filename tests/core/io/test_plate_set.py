"""A plate set's folder: its parts and their manifest written and read back as they were,
and every part missing, damaged or foreign refused by name, never read as zeros."""

import json
import shutil

import numpy as np
import pytest

from holo_core.io.hologram import HologramFileError
from holo_core.io.plate_set import MANIFEST, read_plate_set, write_plate_set
from holo_core.scene.hologram import Hologram
from holo_core.scene.plate import Plate, ViewingZone
from holo_core.scene.plate_set import PathPart, PlateSet


def small_set(rng, shift=0.0) -> PlateSet:
    """Two parts of two looks each, 6x10 samples of random complex values."""
    parts, looks = [], []
    for k in range(2):
        pose = np.eye(4)
        pose[0, 3] = 0.05 * k + shift
        zone = ViewingZone(
            centre=(0.0, 0.0, 0.3), half_extents=(0.02, 0.01, 0.005), pupil=0.01, pixel=1e-3
        )
        parts.append(
            PathPart(
                plate=Plate(matrix_world=pose, width=0.06, height=0.04, zone=zone),
                stretch=(0.04 * k, 0.04 * k + 0.05),
                frames=(2 * k, 2 * k + 1),
            )
        )
        looks.append(
            tuple(
                Hologram(
                    object_wave=(
                        rng.normal(size=(4, 6, 10)) + 1j * rng.normal(size=(4, 6, 10))
                    ).astype(np.complex64),
                    encoding="complex",
                    wavelengths=(5e-6,) * 3 + (5.5e-6,),
                    pitch=2e-5,
                    band=0.1,
                    channels=("R", "G", "B", "Z"),
                    zone=zone,
                    plate=pose,
                    point_density=1e6,
                )
                for _ in range(2)
            )
        )
    return PlateSet(parts=tuple(parts), looks=tuple(looks), seed=4, recording="ab12")


def test_a_set_reads_back_as_it_was_written(tmp_path, rng):
    plates = small_set(rng)
    write_plate_set(tmp_path / "set", plates)
    back = read_plate_set(tmp_path / "set")
    assert (back.seed, back.recording, len(back)) == (4, "ab12", 2)
    for a, b in zip(plates.parts, back.parts):
        assert np.array_equal(a.plate.matrix_world, b.plate.matrix_world)
        assert (a.plate.width, a.plate.height, a.stretch, a.frames) == (
            b.plate.width,
            b.plate.height,
            b.stretch,
            b.frames,
        )
        assert a.plate.zone.centre == b.plate.zone.centre
    for k in range(len(plates)):
        for ha, hb in zip(plates.part_looks(k), back.part_looks(k)):
            assert np.array_equal(ha.object_wave, hb.object_wave)


def test_a_missing_damaged_or_foreign_part_is_refused_by_name(tmp_path, rng):
    folder = tmp_path / "set"
    write_plate_set(folder, small_set(rng))
    saved = tmp_path / "saved"
    shutil.copytree(folder, saved)

    def fresh():
        shutil.rmtree(folder)
        shutil.copytree(saved, folder)

    (folder / "part001.look1.exr").unlink()
    with pytest.raises(HologramFileError, match=r"part 1 \(part001.look1.exr\) is missing"):
        read_plate_set(folder)
    fresh()
    data = bytearray((folder / "part000.look0.exr").read_bytes())
    data[len(data) // 2] ^= 0xFF  # one sample's byte: the file still parses, its size kept
    (folder / "part000.look0.exr").write_bytes(bytes(data))
    opened = read_plate_set(folder)  # its bytes are checked when the part is read ...
    assert len(opened.part_looks(1)) == 2  # ... and the other part serves its frames
    with pytest.raises(HologramFileError, match=r"part 0 \(part000.look0.exr\) is damaged"):
        opened.part_looks(0)
    fresh()
    (folder / "part000.look1.exr").write_bytes(b"\x76\x2f\x31\x01" + bytes(100))
    with pytest.raises(HologramFileError, match=r"part 0 \(part000.look1.exr\) is damaged"):
        read_plate_set(folder)  # not its listed size: refused as the set is opened
    fresh()
    other = tmp_path / "other"  # another set's part in its place
    write_plate_set(other, small_set(rng, shift=0.3))
    shutil.copy(other / "part001.look0.exr", folder / "part001.look0.exr")
    with pytest.raises(HologramFileError, match=r"part 1 \(part001.look0.exr\) is foreign"):
        read_plate_set(folder).part_looks(1)
    # ... and its digest written into this manifest: its plate is not the part's
    manifest = json.loads((folder / MANIFEST).read_text())
    manifest["parts"][1]["files"][0] = json.loads((other / MANIFEST).read_text())["parts"][1][
        "files"
    ][0]
    (folder / MANIFEST).write_text(json.dumps(manifest))
    opened = read_plate_set(folder)  # its bytes are the manifest's: its plate is checked
    with pytest.raises(HologramFileError, match=r"part 1 \(part001.look0.exr\) is foreign"):
        opened.part_looks(1)
    fresh()
    manifest = json.loads((folder / MANIFEST).read_text())
    manifest["parts"][0]["files"][0]["name"] = "../part000.look0.exr"
    (folder / MANIFEST).write_text(json.dumps(manifest))
    with pytest.raises(HologramFileError, match=r"files\[0\].name must be a file name"):
        read_plate_set(folder)
    with pytest.raises(HologramFileError, match="not a plate set"):
        read_plate_set(tmp_path)


def test_parts_kept_as_text_are_the_parts(rng):
    """A scene keeps the parts it placed as JSON (parts_to_json): read back, each part's pose,
    size, zone, stretch and frames are the same; a part malformed is refused naming it."""
    from holo_core.io.plate_set import parts_from_json, parts_to_json
    from holo_core.validate import InputError

    parts = small_set(rng).parts
    back = parts_from_json(parts_to_json(parts))
    for a, b in zip(back, parts, strict=True):
        assert np.array_equal(a.plate.matrix_world, b.plate.matrix_world)
        assert (a.plate.width, a.plate.height, a.stretch, a.frames) == (
            b.plate.width,
            b.plate.height,
            b.stretch,
            b.frames,
        )
        za, zb = a.plate.zone, b.plate.zone
        assert (za.centre, za.half_extents, za.pupil, za.pixel) == (
            zb.centre,
            zb.half_extents,
            zb.pupil,
            zb.pixel,
        )
    listed = json.loads(parts_to_json(parts))
    del listed[1]["zone"]
    with pytest.raises(InputError, match="part 1: not a plate set's part"):
        parts_from_json(json.dumps(listed))
    listed = json.loads(parts_to_json(parts))
    listed[0]["width_m"] = -1.0
    with pytest.raises(InputError, match=r"part 0: .*width"):
        parts_from_json(json.dumps(listed))
    with pytest.raises(InputError, match="a non-empty list"):
        parts_from_json("[]")
