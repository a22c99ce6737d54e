"""The files a phase SLM's driver shows: 8- and 16-bit grey and 10-bit packed images (red the
8 high bits, blue the 2 low ones) that read back to the same codes, layouts beside them, all
of a frame written together or none, and nothing outside the bit depth ever written."""

import json
import math

import numpy as np
import pytest
from PIL import Image

from holo_core.io import slm as slm_io
from holo_core.validate import InputError


def fields(bits, **kw):
    return dict(
        response=np.arange(2**bits) * 2 * math.pi / 2**bits,
        display="lab",
        pitch=8e-6,
        bit_depth=bits,
        phase_range=2 * math.pi,
        inverted=False,
        wavelength=638e-9,
        power=0.05,
        distance=-0.01,
        encoding="double-phase",
        **kw,
    )


def test_every_10_bit_code_packs_as_8_high_bits_in_red_and_2_low_in_blue(tmp_path):
    codes = np.arange(1024, dtype=np.uint16).reshape(32, 32)
    image, layout = slm_io.write_pattern(tmp_path / "p.png", codes, **fields(10))
    with Image.open(image) as im:
        assert im.mode == "RGB"
        rgb = np.asarray(im).astype(int)
    assert np.array_equal(rgb[..., 0], codes >> 2) and np.array_equal(rgb[..., 2], codes & 3)
    assert not rgb[..., 1].any()
    assert np.array_equal(4 * rgb[..., 0] + rgb[..., 2], codes)
    back, meta = slm_io.read_pattern(layout)
    assert np.array_equal(back, codes) and meta["packing"] == "packed10"
    assert meta["laser"] == {"wavelength": 638e-9, "power": 0.05}
    assert meta["display"]["resolution"] == [32, 32] and len(meta["response"]) == 1024


@pytest.mark.parametrize(
    "bits, packing, mode",
    [(8, "grey8", "L"), (6, "grey8", "L"), (16, "grey16", "I;16"), (10, "grey16", "I;16")],
)
def test_grey_images_round_trip(tmp_path, rng, bits, packing, mode):
    codes = rng.integers(0, 2**bits, (17, 23)).astype(np.uint16)
    image, layout = slm_io.write_pattern(tmp_path / "p.png", codes, packing=packing, **fields(bits))
    with Image.open(image) as im:
        assert im.mode == mode and im.size == (23, 17)
        pixels = np.asarray(im).astype(np.int64)
    assert np.array_equal(pixels >> ((8 if packing == "grey8" else 16) - bits), codes)
    assert np.array_equal(slm_io.read_pattern(layout)[0], codes)


def test_codes_outside_the_bit_depth_or_not_integers_are_refused_and_nothing_written(tmp_path):
    for codes, why in (
        (np.array([[0, 256]]), r"codes must be in 0..255 for 8 bits; got 0..256"),
        (np.array([[-1, 3]]), r"0..255"),
        (np.array([[0.5, 1.0]]), "codes must be integers"),
    ):
        with pytest.raises(InputError, match=why):
            slm_io.write_pattern(tmp_path / "p.png", codes, **fields(8))
    with pytest.raises(InputError, match="packing grey8 holds at most 8 bits"):
        slm_io.write_pattern(
            tmp_path / "p.png", np.zeros((2, 2), int), packing="grey8", **fields(10)
        )
    bad = fields(8)
    bad["response"] = np.r_[bad["response"][:-1], np.inf]
    with pytest.raises(InputError, match="response must be 256 finite phases"):
        slm_io.write_pattern(tmp_path / "p.png", np.zeros((2, 2), int), **bad)
    assert list(tmp_path.iterdir()) == []


def test_a_frame_is_written_whole_or_not_at_all(tmp_path):
    """The second laser's codes are out of range: neither laser's files appear."""
    ok = np.zeros((4, 4), np.uint16)
    with pytest.raises(InputError):
        slm_io.write_patterns(
            [
                (tmp_path / "f_638nm.png", ok, fields(8)),
                (tmp_path / "f_520nm.png", ok + 300, fields(8)),
            ]
        )
    assert list(tmp_path.iterdir()) == []
    pairs = slm_io.write_patterns(
        [(tmp_path / "f_638nm.png", ok, fields(8)), (tmp_path / "f_520nm.png", ok + 3, fields(8))]
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "f_520nm.json",
        "f_520nm.png",
        "f_638nm.json",
        "f_638nm.png",
    ]
    assert json.loads(pairs[1][1].read_text())["image"] == "f_520nm.png"


def test_a_damaged_pattern_is_refused_naming_its_layout(tmp_path):
    image, layout = slm_io.write_pattern(
        tmp_path / "p.png", np.zeros((4, 4), np.uint16), **fields(10)
    )
    Image.fromarray(np.full((4, 4, 3), 7, np.uint8)).save(image)  # green set: not packed10
    with pytest.raises(InputError, match=f"{layout}: not a packed10 image"):
        slm_io.read_pattern(layout)


def test_a_stack_is_written_as_exr_with_its_contact_sheet(tmp_path, rng):
    from holo_core.io.image import read_exr

    stack = rng.random((4, 16, 24, 3)).astype(np.float32)
    exr, png = slm_io.write_stack(
        tmp_path / "s.exr",
        stack,
        reference=stack * 2,
        distances=[-1e-3, 0, 1e-3, 2e-3],
        metrics={"psnr_db": [1.0]},
        labels=["a", "b", "c", "d"],
    )
    header, channels = read_exr(exr)
    assert np.array_equal(channels["z02.G"], stack[2, ..., 1])
    assert np.array_equal(channels["ref.z03.B"], 2 * stack[3, ..., 2])
    assert png.is_file()
    with pytest.raises(InputError, match="finite"):
        slm_io.write_stack(tmp_path / "t.exr", stack * np.nan, distances=[0, 1, 2, 3])
