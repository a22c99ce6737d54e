"""Acquired holograms in and out: multi-page TIFF, 16-bit PNG, .npy, HDF5, .mat v7.3 and
arrays, each with its optics given or read from its metadata; writes in the format the suffix
names, or an error."""

import io
import json
import logging

import numpy as np
import pytest
from PIL import Image

from holo_core.io.acquired import read_acquired, write_acquired
from holo_core.io.hologram import read_hologram, write_hologram
from holo_core.io.image import write_exr
from holo_core.scene import Hologram
from holo_core.validate import InputError

PITCH, LAM = 3.45e-6, 633e-9
OPTICS = {"pitch": PITCH, "wavelength": LAM}


@pytest.fixture
def pages(rng):
    """Three 16-bit frames of 5 x 7 (not square, so a transposition shows)."""
    return rng.integers(0, 65536, (3, 5, 7)).astype(np.uint16)


def test_every_page_of_a_tiff_or_the_one_asked_for(tmp_path, pages):
    path = tmp_path / "stack.tif"
    frames = [Image.fromarray(p) for p in pages]
    frames[0].save(path, save_all=True, append_images=frames[1:])
    with pytest.raises(InputError, match=r"stack.tif: holds 3 pages; pass page=i \(0 to 2\)"):
        read_acquired(path, **OPTICS)
    second = read_acquired(path, **OPTICS, page=1)
    assert np.array_equal(second.intensity[0], (pages[1] / 65535).astype(np.float32))
    every = read_acquired(path, **OPTICS, page="all")
    assert [h.intensity[0].tolist() for h in every] == [
        (p / 65535).astype(np.float32).tolist() for p in pages
    ]
    with pytest.raises(InputError, match=r"page must be in \[0, 2\]"):
        read_acquired(path, **OPTICS, page=3)


def test_a_16_bit_png_keeps_its_16_bits(tmp_path, pages):
    path = tmp_path / "frame.png"
    Image.fromarray(pages[0]).save(path)
    h = read_acquired(path, **OPTICS)
    assert np.array_equal(np.round(h.intensity[0].astype(np.float64) * 65535), pages[0])


def test_a_dim_16_bit_png_is_not_read_as_8_bit(tmp_path):
    """Values all below 256 in a 16-bit file are still 16-bit counts."""
    path = tmp_path / "dim.png"
    Image.fromarray(np.full((4, 4), 200, np.uint16)).save(path)
    got = float(read_acquired(path, **OPTICS).intensity.max())
    assert abs(got - 200 / 65535) < 1e-9, got


def test_npy_with_its_metadata_beside_it(tmp_path, rng):
    frame = rng.random((5, 7)).astype(np.float32)
    np.save(tmp_path / "f.npy", frame)
    with pytest.raises(InputError, match=r"pitch must be given \[m\]: .*f.npy holds no pitch_m"):
        read_acquired(tmp_path / "f.npy", wavelength=LAM)
    (tmp_path / "f.json").write_text(
        json.dumps({"pitch_m": PITCH, "wavelength_m": LAM, "reference_angle_rad": 0.02})
    )
    h = read_acquired(tmp_path / "f.npy")
    assert (h.pitch, h.wavelengths, h.reference_angle) == (PITCH, (LAM,), 0.02)
    assert np.array_equal(h.intensity[0], frame)


def test_a_given_value_wins_and_the_difference_is_logged(tmp_path, rng, caplog):
    np.save(tmp_path / "f.npy", rng.random((5, 7)))
    (tmp_path / "f.json").write_text(json.dumps({"pitch_m": PITCH, "wavelength_m": LAM}))
    with caplog.at_level(logging.WARNING, logger="holo_core.io.acquired"):
        h = read_acquired(tmp_path / "f.npy", pitch=2 * PITCH)
    assert h.pitch == 2 * PITCH
    assert "pitch given as 6.9e-06, the file says 3.45e-06" in caplog.text, caplog.text


def test_metadata_in_the_wrong_unit_is_refused_naming_the_file(tmp_path, rng):
    np.save(tmp_path / "f.npy", rng.random((5, 7)))
    (tmp_path / "f.json").write_text(json.dumps({"pitch_m": 3.45, "wavelength_m": LAM}))
    with pytest.raises(
        InputError,
        match=r"f.npy: metadata pitch_m must be in \[1e-12, 0.01\] "
        r"\[m\] \(.*\); got 3.45 \(3.45 looks like micrometres",
    ):
        read_acquired(tmp_path / "f.npy")


def test_hdf5_attributes_of_the_dataset_or_a_group_above(tmp_path, pages):
    h5py = pytest.importorskip("h5py")
    path = tmp_path / "run.h5"
    with h5py.File(path, "w") as f:
        f.attrs["wavelength_m"] = LAM
        g = f.create_group("camera")
        d = g.create_dataset("frames", data=pages)
        d.attrs["pitch_m"] = PITCH
        f.create_dataset("dark", data=np.zeros((5, 7)))
    with pytest.raises(
        InputError,
        match="holds 2 2-D or 3-D numeric datasets; pass dataset= one of camera/frames, dark",
    ):
        read_acquired(path, page=0)
    h = read_acquired(path, dataset="camera/frames", page=2)
    assert (h.pitch, h.wavelengths) == (PITCH, (LAM,))
    assert np.array_equal(h.intensity[0], (pages[2] / 65535).astype(np.float32))
    with pytest.raises(InputError, match="dataset must name a dataset"):
        read_acquired(path, dataset="camera")


def test_a_matlab_v73_file_keeps_its_orientation(tmp_path, rng):
    """MATLAB writes column-major (an H x W matrix is W x H in the HDF5 file) with a 512-byte
    header; its scalar variables carry the optics."""
    h5py = pytest.importorskip("h5py")
    frame = rng.random((5, 7))
    path = tmp_path / "scan.mat"
    with h5py.File(path, "w", userblock_size=512) as f:
        d = f.create_dataset("H", data=frame.T)
        d.attrs["MATLAB_class"] = np.bytes_("double")
        for key, value in (("pitch_m", PITCH), ("wavelength_m", LAM)):
            f.create_dataset(key, data=np.array([[value]]))
    with open(path, "r+b") as f:
        f.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64".ljust(116) + b"\0" * 8 + b"\0\2IM")
    h = read_acquired(path)
    assert h.shape == (5, 7) and (h.pitch, h.wavelengths) == (PITCH, (LAM,))
    assert np.allclose(h.intensity[0], frame, rtol=1e-7)


def test_an_old_mat_file_says_how_to_save_it(tmp_path):
    pytest.importorskip("h5py")
    path = tmp_path / "old.mat"
    path.write_bytes(b"MATLAB 5.0 MAT-file, Platform: PCWIN64".ljust(128) + b"\0" * 64)
    with pytest.raises(InputError, match=r"old.mat: a MATLAB v5 .*'-v7.3'"):
        read_acquired(path, **OPTICS)


def test_a_hologram_from_an_array_in_memory(rng):
    frame = rng.integers(0, 256, (5, 7)).astype(np.uint8)
    h = read_acquired(frame, **OPTICS, reference_angle=0.01)
    assert (h.shape, h.pitch, h.reference_angle) == ((5, 7), PITCH, 0.01)
    assert np.array_equal(h.intensity[0], (frame / 255).astype(np.float32))
    with pytest.raises(InputError, match="holds complex values"):
        read_acquired(frame + 1j, **OPTICS)
    with pytest.raises(InputError, match="source must be a path or an"):
        read_acquired(np.zeros(4), **OPTICS)


@pytest.mark.parametrize("name", ["h.npy", "h.h5", "h.mat", "h.tif", "h.png"])
def test_written_and_read_back(tmp_path, rng, name):
    if name.endswith((".h5", ".mat")):
        pytest.importorskip("h5py")
    frame = rng.random((1, 5, 7)).astype(np.float32) * 3
    h = Hologram(
        intensity=frame,
        wavelengths=(LAM,),
        pitch=PITCH,
        reference_angle=0.03,
        reference_azimuth=1.0,
    )
    back = read_acquired(write_acquired(tmp_path / name, h))
    assert (back.pitch, back.wavelengths, back.reference_angle, back.reference_azimuth) == (
        PITCH,
        (LAM,),
        0.03,
        1.0,
    )
    tolerance = 3 / 65535 if name.endswith(".png") else 0  # 16 bits of the peak
    err = float(np.abs(back.intensity - frame).max())
    assert err <= tolerance * 0.5 + 1e-7, f"{name}: {err:.3g}"


def test_writes_follow_the_suffix_or_refuse(tmp_path, rng):
    h = Hologram(
        intensity=rng.random((1, 5, 7)).astype(np.float32), wavelengths=(LAM,), pitch=PITCH
    )
    with pytest.raises(InputError, match=r"h.jpg: write_acquired writes .png, .tif"):
        write_acquired(tmp_path / "h.jpg", h)
    with pytest.raises(InputError, match=r"h.png: the file is written as OpenEXR; name it \*.exr"):
        write_hologram(tmp_path / "h.png", h)
    assert not list(tmp_path.iterdir())
    exr = write_acquired(tmp_path / "h.exr", h)
    assert np.array_equal(read_hologram(exr).intensity, h.intensity)


def _scan(tmp_path, image, name="s.png", **save):
    path = tmp_path / name
    image.save(path, **save)
    return read_acquired(path, pitch=5e-6, wavelength=532e-9).intensity


def test_scans_are_read_by_image_mode(tmp_path, rng):
    grey = rng.integers(0, 256, (6, 7), dtype=np.uint8)
    want = grey / 255.0
    rgb = Image.fromarray(np.repeat(grey[..., None], 3, 2))
    palette = rgb.convert("P", palette=Image.ADAPTIVE)
    assert np.allclose(_scan(tmp_path, palette), want, atol=1e-6)  # the colours
    la = Image.fromarray(np.stack([grey, 255 - grey], -1), "LA")
    assert np.allclose(_scan(tmp_path, la), want, atol=1e-6)  # alpha dropped
    cmyk = _scan(tmp_path, rgb.convert("CMYK"), "s.tif")
    assert np.allclose(cmyk, want, atol=1 / 255)
    sixteen = rng.integers(0, 65536, (6, 7)).astype(np.int32)  # int32 TIFF
    assert np.allclose(_scan(tmp_path, Image.fromarray(sixteen), "i.tif"), sixteen / 65535)
    exr = write_exr(tmp_path / "s.exr", {c: want * (i + 1) for i, c in enumerate("RGB")})
    assert read_acquired(exr, pitch=5e-6, wavelength=532e-9).intensity.shape == (1, 6, 7)
    assert np.allclose(read_acquired(exr, pitch=5e-6, wavelength=532e-9).intensity, 2 * want)


def test_a_decompression_bomb_is_refused_from_its_header(tmp_path, monkeypatch):
    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "1G")
    out = io.BytesIO()
    Image.new("L", (12000, 12000)).save(out, "PNG")
    (tmp_path / "bomb.png").write_bytes(out.getvalue())
    with pytest.raises(InputError, match="12000x12000 pixels"):
        read_acquired(tmp_path / "bomb.png", pitch=5e-6, wavelength=532e-9)
