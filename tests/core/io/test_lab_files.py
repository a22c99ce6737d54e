"""Lab files that cannot be turned against their user, and scans read by their layout:
nothing read from outside the file named, what cannot be bounded refused up front, every
damage named."""

import json
import struct
import zlib

import numpy as np
import pytest

from holo_core.io import jsonfile
from holo_core.io.acquired import MAX_PAGES, read_acquired, write_acquired
from holo_core.scene import Hologram
from holo_core.units import electron_wavelength
from holo_core.validate import InputError

OPTICS = {"pitch": 3.45e-6, "wavelength": 633e-9}
SECRET = np.arange(64, dtype=np.float64).reshape(8, 8)


@pytest.fixture
def h5py():
    return pytest.importorskip("h5py")


@pytest.fixture
def outside(tmp_path, h5py):
    """A file the user never named: raw bytes and an HDF5 file holding ``SECRET``."""
    raw = tmp_path / "outside.bin"
    raw.write_bytes(SECRET.astype(np.uint8).tobytes())
    other = tmp_path / "outside.h5"
    with h5py.File(other, "w") as f:
        f.create_dataset("secret", data=SECRET)
        f.create_dataset("pitch_m", data=np.array([[3.45e-6]]))
    return raw, other


def test_external_storage_is_refused_naming_the_file(tmp_path, h5py, outside):
    """A dataset whose bytes live in another file (external storage, here a file beside it)
    is refused naming the dataset and that file; its bytes are never read as the hologram."""
    raw, _ = outside
    path = tmp_path / "lab.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("x", shape=(8, 8), dtype="u1", external=[(str(raw), 0, 64)])
    with pytest.raises(
        InputError,
        match=rf"lab.h5:x stores its samples in another file "
        rf"\({raw}\); refused",
    ):
        read_acquired(path, **OPTICS)


def test_external_links_are_refused_on_the_way_to_the_dataset(tmp_path, h5py, outside):
    _, other = outside
    path = tmp_path / "lab.h5"
    with h5py.File(path, "w") as f:
        f["frames"] = h5py.ExternalLink(str(other), "/secret")
        f["group"] = h5py.ExternalLink(str(other), "/")
        f.create_dataset("own", data=np.ones((4, 4)))
    for name in ("frames", "group/secret"):
        with pytest.raises(
            InputError,
            match=rf"lab.h5:{name.split('/')[0]} is an external "
            rf"link to .*outside.h5",
        ):
            read_acquired(path, dataset=name, **OPTICS)
    # the search for the only dataset does not follow links either: the own one is found
    assert read_acquired(path, **OPTICS).shape == (4, 4)


def test_metadata_is_not_read_through_an_external_link(tmp_path, h5py, outside):
    """MATLAB's scalar variables are read from the file itself: a pitch_m linked to another
    file is not the pitch."""
    _, other = outside
    path = tmp_path / "lab.mat"
    with h5py.File(path, "w") as f:
        f.create_dataset("H", data=np.ones((4, 4)))
        f["pitch_m"] = h5py.ExternalLink(str(other), "/pitch_m")
    with pytest.raises(
        InputError,
        match=r"pitch must be given \[m\]: .*lab.mat holds no "
        r"pitch_m",
    ):
        read_acquired(path, wavelength=633e-9)


def test_virtual_datasets_are_refused_naming_their_sources(tmp_path, h5py, outside):
    _, other = outside
    path = tmp_path / "lab.h5"
    with h5py.File(path, "w") as f:
        layout = h5py.VirtualLayout(shape=(8, 8), dtype="f8")
        layout[:] = h5py.VirtualSource(str(other), "secret", shape=(8, 8))
        f.create_virtual_dataset("v", layout)
    with pytest.raises(InputError, match=rf"lab.h5:v is a virtual dataset mapping {other}"):
        read_acquired(path, **OPTICS)


def test_a_damaged_hdf5_file_is_named(tmp_path, h5py, rng):
    """Every damage to an HDF5 or .mat file here ends in a hologram or in an error naming the
    file, never a RuntimeError or KeyError without it."""
    good = tmp_path / "good.mat"
    write_acquired(
        good,
        Hologram(
            intensity=rng.random((1, 16, 16)).astype(np.float32),
            wavelengths=(633e-9,),
            pitch=3.45e-6,
        ),
    )
    data = good.read_bytes()
    outcomes = set()
    for case in range(60):
        damaged = bytearray(data)
        if case % 3 == 0:
            damaged = damaged[: int(rng.integers(600, len(data)))]
        else:
            at = int(rng.integers(512, len(data) - 16))
            damaged[at : at + 8] = rng.integers(0, 256, 8, dtype=np.uint8).tobytes()
        path = tmp_path / f"case{case}.mat"
        path.write_bytes(bytes(damaged))
        try:
            read_acquired(path)
            outcomes.add("read")
        except InputError as e:
            assert str(path) in str(e), str(e)
            outcomes.add("refused")
    assert "refused" in outcomes, outcomes


def test_a_chunk_larger_than_the_memory_is_refused_before_reading(tmp_path, h5py, monkeypatch):
    path = tmp_path / "lab.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("x", shape=(8, 8), maxshape=(None, None), chunks=(4096, 4096), dtype="f8")
    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "64M")
    with pytest.raises(InputError, match=r"lab.h5:x \(chunks of 4096x4096\) needs"):
        read_acquired(path, **OPTICS)


@pytest.mark.parametrize("where", ["sidecar", "tiff"])
def test_deeply_nested_json_is_refused_naming_the_file(tmp_path, where):
    """100,000 nested brackets gave RecursionError; the bounded loader counts the depth
    before it parses."""
    nested = '{"pitch_m": ' + "[" * 100_000 + "]" * 100_000 + "}"
    if where == "sidecar":
        np.save(tmp_path / "f.npy", np.ones((4, 4)))
        (tmp_path / "f.json").write_text(nested)
        path = tmp_path / "f.npy"
    else:
        from PIL import Image

        path = tmp_path / "f.tif"
        Image.fromarray(np.ones((4, 4), np.float32)).save(path, description=nested)
    with pytest.raises(
        InputError,
        match=r"f\.(json|tif).*JSON nested 100001 levels deep; "
        r"metadata may nest at most 64",
    ):
        read_acquired(path, **OPTICS)


def test_the_json_depth_ignores_brackets_in_strings():
    assert jsonfile.depth('{"a": "[[[[{{{{", "b": [1, [2]]}') == 3
    assert jsonfile.loads('{"k": "[[["}', "x") == {"k": "[[["}


def test_an_npz_named_npy_is_named(tmp_path):
    np.savez(tmp_path / "f.npz", a=np.ones((4, 4)))
    (tmp_path / "f.npz").rename(tmp_path / "f.npy")
    with pytest.raises(
        InputError,
        match=r"f.npy: a zip archive \(.npz, several arrays\) "
        r"named .npy",
    ):
        read_acquired(tmp_path / "f.npy", **OPTICS)


def test_a_million_pages_are_refused_up_front_and_one_is_read(tmp_path):
    """10⁶ pages of a .npy took two minutes to be read in full: now the pages asked for are
    read alone (memory-mapped) and page='all' is refused before any page is touched."""
    path = tmp_path / "stack.npy"
    pages = np.lib.format.open_memmap(path, mode="w+", dtype=np.float32, shape=(1_000_000, 2, 2))
    pages[123_456] = 0.5
    del pages
    with pytest.raises(InputError, match=r"holds 1000000 pages; pass page=i"):
        read_acquired(path, **OPTICS)
    with pytest.raises(InputError, match=rf"page='all' returns at most {MAX_PAGES} holograms"):
        read_acquired(path, **OPTICS, page="all")
    assert float(read_acquired(path, **OPTICS, page=123_456).intensity.max()) == 0.5


# --- scans read by their layout ---------------------------------------------------------------


def _png(path, samples: np.ndarray, colour_type: int) -> None:
    """A 16-bit PNG of (H, W, C) samples with each PNG row filter in turn (None, Sub, Up,
    Average, Paeth), so the reader's unfiltering is exercised, not only stored rows."""
    h, w, c = samples.shape
    raw = samples.astype(">u2").view(np.uint8).reshape(h, w * c * 2).astype(np.int64)
    bpp, rows = 2 * c, []
    for i in range(h):
        kind, row = i % 5, raw[i]
        up = raw[i - 1] if i else np.zeros_like(row)
        left = np.concatenate([np.zeros(bpp, np.int64), row[:-bpp]])
        upleft = np.concatenate([np.zeros(bpp, np.int64), up[:-bpp]])
        if kind == 1:
            row = row - left
        elif kind == 2:
            row = row - up
        elif kind == 3:
            row = row - (left + up) // 2
        elif kind == 4:
            p = left + up - upleft
            pa, pb, pc = np.abs(p - left), np.abs(p - up), np.abs(p - upleft)
            row = row - np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, up, upleft))
        rows.append(bytes([kind]) + (row % 256).astype(np.uint8).tobytes())

    def chunk(kind, data):
        return (
            struct.pack(">I", len(data))
            + kind
            + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
        )

    header = struct.pack(">IIBBBBB", w, h, 16, colour_type, 0, 0, 0)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(b"".join(rows)))
        + chunk(b"IEND", b"")
    )


@pytest.mark.parametrize("colour_type, channels", [(2, 3), (6, 4)])
def test_16_bit_colour_pngs_keep_their_16_bits(tmp_path, rng, colour_type, channels):
    """16-bit RGB (and RGBA) was cut to its high 8 bits: now the grey is the mean of the
    colours at 16 bits (alpha dropped), exactly."""
    samples = rng.integers(0, 65536, (7, 9, channels)).astype(np.uint16)
    path = tmp_path / "colour16.png"
    _png(path, samples, colour_type)
    want = samples[..., :3].astype(np.float64).mean(-1) / 65535
    got = read_acquired(path, **OPTICS).intensity[0]
    assert np.abs(got - want).max() <= 1e-7, np.abs(got - want).max()


def test_16_bit_grey_with_alpha_is_refused_naming_its_layout(tmp_path, rng):
    """Pillow has no 16-bit reading of grey + alpha: refused, never cut to 8 bits."""
    path = tmp_path / "la16.png"
    _png(path, rng.integers(0, 65536, (7, 9, 2)).astype(np.uint16), 4)
    with pytest.raises(
        InputError,
        match=r"la16.png: 16-bit samples laid out as LA;16B, of "
        r"which Pillow reads only 8 bits a sample",
    ):
        read_acquired(path, **OPTICS)


def _tiff(path, planes: np.ndarray, planar: bool, compress=False) -> None:
    """A little-endian TIFF of (P, H, W) uint16 samples, one strip per plane: separate planes
    (PlanarConfiguration 2, as tifffile writes a (P, H, W) array) or interleaved (1)."""
    p, h, w = planes.shape
    data = (
        [planes[k].astype("<u2").tobytes() for k in range(p)]
        if planar
        else [np.moveaxis(planes, 0, -1).astype("<u2").tobytes()]
    )
    if compress:
        data = [zlib.compress(d) for d in data]
    offset = 8
    strips = []
    for d in data:
        strips.append(offset)
        offset += len(d)
    entries = [
        (256, 3, 1, w),
        (257, 3, 1, h),
        (258, 3, p, None),
        (259, 3, 1, 8 if compress else 1),
        (262, 3, 1, 2 if p == 3 else 1),
        (273, 4, len(data), None),
        (277, 3, 1, p),
        (278, 3, 1, h),
        (279, 4, len(data), None),
        (284, 3, 1, 2 if planar else 1),
    ]
    arrays = {
        258: struct.pack(f"<{p}H", *[16] * p),
        273: struct.pack(f"<{len(data)}I", *strips),
        279: struct.pack(f"<{len(data)}I", *map(len, data)),
    }
    extra = offset
    ifd_at = extra + sum(len(a) for a in arrays.values())
    blob, tail = b"".join(data), b""
    table = struct.pack("<H", len(entries))
    for tag, kind, count, value in entries:
        if value is None and len(arrays[tag]) > 4:
            table += struct.pack("<HHII", tag, kind, count, extra + len(tail))
            tail += arrays[tag]
        elif value is None:
            table += struct.pack("<HHI", tag, kind, count) + arrays[tag].ljust(4, b"\0")
        else:
            table += struct.pack("<HHI", tag, kind, count) + struct.pack(
                "<H" if kind == 3 else "<I", value
            ).ljust(4, b"\0")
    ifd_at = extra + len(tail)
    path.write_bytes(
        b"II*\0" + struct.pack("<I", ifd_at) + blob + tail + table + struct.pack("<I", 0)
    )


def test_a_planar_16_bit_tiff_stack_is_read_as_pages(tmp_path, rng):
    """A (3, H, W) 16-bit stack saved with its samples as separate planes imported as noise:
    each plane is now a page, at 16 bits."""
    planes = rng.integers(0, 65536, (3, 5, 7)).astype(np.uint16)
    path = tmp_path / "stack.tif"
    _tiff(path, planes, planar=True)
    with pytest.raises(InputError, match=r"stack.tif: holds 3 pages"):
        read_acquired(path, **OPTICS)
    every = read_acquired(path, **OPTICS, page="all")
    for h, plane in zip(every, planes):
        assert np.array_equal(h.intensity[0], (plane / 65535).astype(np.float32))


def test_interleaved_16_bit_rgb_tiff_is_colour_at_16_bits(tmp_path, rng):
    planes = rng.integers(0, 65536, (3, 5, 7)).astype(np.uint16)
    path = tmp_path / "rgb.tif"
    _tiff(path, planes, planar=False)
    got = read_acquired(path, **OPTICS).intensity[0]
    assert np.abs(got - planes.mean(0) / 65535).max() <= 1e-7


def test_a_compressed_planar_16_bit_tiff_is_refused_naming_its_layout(tmp_path, rng):
    path = tmp_path / "packed.tif"
    _tiff(path, rng.integers(0, 65536, (3, 5, 7)).astype(np.uint16), planar=True, compress=True)
    with pytest.raises(
        InputError,
        match=r"packed.tif: a TIFF of 3 16-bit samples per pixel "
        r"stored as separate planes, deflate: not read",
    ):
        read_acquired(path, **OPTICS, page=0)


def test_a_hyperspy_file_gives_its_calibration(tmp_path, h5py, rng):
    """A HyperSpy signal (as holospy's Fe-needle data is stored): the pitch from its signal
    axes in nm, the wavelength from the microscope's beam energy in kV (300 kV: 1.9687 pm,
    relativistic)."""
    path = tmp_path / "needle.hdf5"
    with h5py.File(path, "w") as f:
        f.attrs["file_format"] = "HyperSpy"
        g = f.create_group("Experiments/Hologram")
        g.create_dataset("data", data=rng.integers(0, 4000, (16, 16)))
        for k, name in enumerate("yx"):
            axis = g.create_group(f"axis-{k}")
            axis.attrs.update(
                {"name": name, "navigate": False, "scale": 0.9197, "units": "nm", "size": 16}
            )
        g.create_group("metadata/Acquisition_instrument/TEM").attrs["beam_energy"] = 300.0
        g.create_dataset("original_metadata/lut", data=np.ones((4, 4)))
    h = read_acquired(path)
    assert h.pitch == pytest.approx(0.9197e-9) and h.wavelengths[0] == electron_wavelength(3e5)
    assert electron_wavelength(3e5) == pytest.approx(1.9687e-12, rel=1e-4)


@pytest.mark.parametrize("name", ["h.exr", "h.npy", "h.png"])
def test_every_written_format_reads_back_with_its_optics(tmp_path, rng, name):
    """Whatever write_acquired writes, read_acquired reads: its .exr (a Holo hologram file)
    was unreadable."""
    frame = rng.random((1, 5, 7)).astype(np.float32)
    h = Hologram(
        intensity=frame,
        wavelengths=(532e-9,),
        pitch=2e-6,
        reference_angle=0.02,
        reference_azimuth=0.5,
        reference_amplitudes=(1.5,),
    )
    back = read_acquired(write_acquired(tmp_path / name, h))
    assert (back.pitch, back.wavelengths, back.reference_angle, back.reference_azimuth) == (
        2e-6,
        (532e-9,),
        0.02,
        0.5,
    )
    assert np.abs(back.intensity - frame).max() <= 1.5 / 65535 * frame.max()
    if name == "h.exr":
        assert back.reference_amplitudes == (1.5,)
    json.dumps(back.reference_amplitudes)  # plain numbers, as a file's metadata holds them
