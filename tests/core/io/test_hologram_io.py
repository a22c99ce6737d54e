"""The hologram file: bit-exact round trip, and a clear error for each bad file."""

import dataclasses
import json

import numpy as np
import pinhole
import pytest
from cli import run_cli

from holo_core.io.acquired import read_acquired
from holo_core.io.hologram import (
    FORMAT_VERSION,
    HologramFileError,
    read_hologram,
    write_hologram,
)
from holo_core.io.image import write_png
from holo_core.io.view import write_view
from holo_core.scene.hologram import Hologram
from holo_core.validate import InputError
from holo_core.view import RenderResult


@pytest.fixture
def hologram(rng):
    shape = (3, 24, 40)
    return Hologram(
        intensity=rng.random(shape, np.float32),
        wavelengths=(633e-9, 532e-9, 473e-9),
        pitch=8e-6,
        reference_angle=0.02,
        reference_azimuth=0.5,
        reference_amplitudes=(1.0, 2.0, 3.0),
        object_wave=(rng.standard_normal(shape) + 1j * rng.standard_normal(shape)).astype(
            np.complex64
        ),
        plate=_pose(0.5, [1.0, -2.0, 3.0]),
        bounds=np.array([[-1, -2, -3], [1, 2, -1.0]]),
    )


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
    for name in (
        "wavelengths",
        "pitch",
        "reference_angle",
        "reference_azimuth",
        "reference_amplitudes",
    ):
        assert getattr(back, name) == getattr(hologram, name), name
    assert np.array_equal(back.plate, hologram.plate) and np.array_equal(
        back.bounds, hologram.bounds
    )
    assert not list(tmp_path.glob(".*")), "temporary file left behind"


def test_a_plate_is_written_uncompressed_and_reads_back_whole(tmp_path, hologram):
    """A carrier plate's samples (speckle, which ZIP barely shrinks) are written without
    compression, to be read fast by every frame; other holograms keep ZIP. Both bit-exact."""
    import OpenEXR

    from holo_core.scene.plate import Carrier

    plate = dataclasses.replace(
        hologram,
        intensity=None,
        encoding="complex",
        reference_amplitudes=(),
        reference_angle=0.0,
        carrier=Carrier(centre=(0, 0, 1.5), origin=(-1e-4, -1e-4), row_pitch=8e-6),
    )
    for h, codec in ((plate, OpenEXR.NO_COMPRESSION), (hologram, OpenEXR.ZIP_COMPRESSION)):
        path = write_hologram(tmp_path / f"{codec}.exr", h)
        with OpenEXR.File(str(path), header_only=True) as f:
            assert f.header()["compression"] == codec
        assert read_hologram(path).object_wave.tobytes() == h.object_wave.tobytes()


def test_a_complex_hologram_is_stored_as_pairs_and_version_4_still_reads(tmp_path, hologram):
    """Format 5 stores a complex hologram's samples as they lie in memory, (real, imaginary)
    pairs along each row of ``c<c>.O``; a file of format 4 (``O.re``, ``O.im``) reads the
    same samples; a pairs channel of the wrong width is refused, naming it."""
    import OpenEXR

    plate = dataclasses.replace(
        hologram, intensity=None, encoding="complex", reference_amplitudes=(), reference_angle=0.0
    )
    path = write_hologram(tmp_path / "h.exr", plate)
    with OpenEXR.File(str(path), separate_channels=True) as f:
        chans = {n: np.array(c.pixels) for n, c in f.channels().items()}
        header = dict(f.header())
    assert sorted(chans) == ["c0.O", "c1.O", "c2.O"]
    h, w = plate.shape
    for c, pairs in enumerate(chans[f"c{c}.O"] for c in range(3)):
        assert pairs.shape == (h, 2 * w)
        assert np.array_equal(pairs[:, 0::2], plate.object_wave[c].real)
        assert np.array_equal(pairs[:, 1::2], plate.object_wave[c].imag)
    old = {
        f"c{c}.O.{p}": np.ascontiguousarray(pairs[:, k::2])
        for c in range(3)
        for k, p in enumerate(("re", "im"))
        for pairs in [chans[f"c{c}.O"]]
    }
    meta = {**json.loads(header["holo"]), "format_version": 4}
    del header["dataWindow"], header["displayWindow"]
    with OpenEXR.File({**header, "holo": json.dumps(meta)}, old) as f:
        f.write(str(tmp_path / "v4.exr"))
    assert read_hologram(tmp_path / "v4.exr").object_wave.tobytes() == plate.object_wave.tobytes()
    narrow = {n: np.ascontiguousarray(a[:, :w]) for n, a in chans.items()}
    with OpenEXR.File(header, narrow) as f:
        f.write(str(tmp_path / "narrow.exr"))
    with pytest.raises(HologramFileError, match=f"narrow.exr: channel c0.O is \\({h}, {w}\\)"):
        read_hologram(tmp_path / "narrow.exr")
    _rewrite(path, drop="c0.O")
    with pytest.raises(HologramFileError, match=r"missing channel\(s\) c0.O$"):
        read_hologram(path)


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
    with pytest.raises(HologramFileError, match=r"h\.exr"):
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
    with pytest.raises(
        HologramFileError, match=f"format version {FORMAT_VERSION + 1} is not supported"
    ):
        read_hologram(path)
    path = write_hologram(tmp_path / "h.exr", hologram)
    _rewrite(path, drop="c1.H")
    with pytest.raises(HologramFileError, match=r"missing channel\(s\) c1.H"):
        read_hologram(path)


def test_import_acquired_png(tmp_path, rng):
    grey = rng.random((20, 30))
    write_png(tmp_path / "scan.png", grey)
    h = read_acquired(tmp_path / "scan.png", pitch=5e-6, wavelength=532e-9, reference_angle=0.01)
    assert h.shape == (20, 30) and h.wavelengths == (532e-9,) and h.pitch == 5e-6
    err = np.abs(h.intensity[0] - grey).max()
    assert err <= 0.5 / 255 + 1e-7, f"8-bit grey image read back off by {err:.2e}"
    with pytest.raises(ValueError, match=r"pitch must be in \[1e-12, 0.01\] \[m\] \(.*\); got 0"):
        read_acquired(tmp_path / "scan.png", pitch=0, wavelength=532e-9)


def test_a_non_finite_or_empty_hologram_is_never_written(tmp_path, point_hologram):
    bad = Hologram(
        intensity=np.full((1, 4, 4), np.nan, np.float32), wavelengths=(633e-9,), pitch=8e-6
    )
    with pytest.raises(HologramFileError, match="NaN"):
        write_hologram(tmp_path / "h.exr", bad)
    empty = Hologram(intensity=np.zeros((1, 0, 4), np.float32), wavelengths=(633e-9,), pitch=8e-6)
    with pytest.raises(HologramFileError, match="no samples"):
        write_hologram(tmp_path / "h.exr", empty)
    assert not list(tmp_path.iterdir())


def _with_meta(path, edit):
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        header = dict(f.header())
        chans = {n: np.array(c.pixels) for n, c in f.channels().items()}
    meta = json.loads(header["holo"])
    edit(meta, chans)
    header["holo"] = json.dumps(meta)
    with OpenEXR.File(header, chans) as f:
        f.write(str(path))


@pytest.mark.parametrize(
    "edit, problem",
    [
        (lambda m, c: m.pop("pitch_m"), r"pitch_m must be a number \[m\]; got 'missing'"),
        (lambda m, c: m.update(pitch_m=0), "pitch_m"),
        (lambda m, c: m.update(pitch_m=-8e-6), "pitch_m"),
        (lambda m, c: m.update(pitch_m=float("nan")), "pitch_m"),
        (lambda m, c: m.update(pitch_m="8e-6"), "pitch_m"),
        (lambda m, c: m.update(wavelengths_m=[0.0]), "wavelengths_m"),
        (lambda m, c: m.update(band_sin=2.0), r"band_sin must be in \[0, 1\)"),
        (lambda m, c: m.update(size_px=[16.5, 16]), "size_px"),
        (lambda m, c: m["reference"].update(angle_rad=2.0), "reference.angle_rad"),
        (lambda m, c: m.update(plate_to_world=(2 * np.eye(4)).ravel().tolist()), "rotation"),
        (lambda m, c: m.update(bounds_m=[[0, 0, 0], [-1, 0, 0]]), "bounds_m"),
        (lambda m, c: m.update(channels=["Q"]), "channels"),
        (lambda m, c: c["c0.H"].__setitem__((3, 3), np.nan), "NaN"),
    ],
)
def test_hologram_metadata_and_pixels_are_checked(tmp_path, point_hologram, edit, problem):
    path = write_hologram(tmp_path / "h.exr", point_hologram)
    _with_meta(path, edit)
    with pytest.raises(HologramFileError, match=f"{path}.*{problem}"):
        read_hologram(path)


def test_the_writer_refuses_what_the_reader_would(tmp_path, point_hologram):
    """The writer applies the reader's schema: a description bent after construction is
    refused with the file and the field named, and nothing is written."""
    for field, value, problem in [
        ("band", 1.5, r"band_sin must be in \[0, 1\)"),
        ("pitch", 1e-300, r"pitch_m must be in \[1e-13, 1000\]"),
        ("reference_amplitudes", (0.0,), "amplitudes.*> 0"),
    ]:
        info = dataclasses.replace(point_hologram.info)
        object.__setattr__(info, field, value)
        bent = Hologram(
            info=info, intensity=point_hologram.intensity, object_wave=point_hologram.object_wave
        )
        with pytest.raises(HologramFileError, match=f"h.exr: metadata .*{problem}"):
            write_hologram(tmp_path / "h.exr", bent)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    "edit, problem",
    [
        (lambda m: m.update(pitch_m=1e-300), r"pitch_m must be in \[1e-13, 1000\] \[m\]"),
        (lambda m: m.update(wavelengths_m=[1e300]), "wavelengths_m must be in"),
        (lambda m: m["reference"].update(amplitudes=[0.0]), "reference.amplitudes must be 1 numb"),
    ],
)
def test_a_file_of_absurd_optics_is_refused_by_the_reader_and_the_cli(
    tmp_path, point_hologram, capsys, edit, problem
):
    """A file of absurd optics (pitch 1e-300, a wavelength of 1e300 m, a zero reference
    amplitude) is refused on reading, naming the file and the field, by the API and by the
    command line (one line, exit 2, no view written)."""
    path = write_hologram(tmp_path / "h.exr", point_hologram)
    _with_meta(path, lambda m, c: edit(m))
    with pytest.raises(HologramFileError, match=f"{path}: metadata {problem}"):
        read_hologram(path)
    status, _, err = run_cli(capsys, "render", path, "-o", tmp_path / "v.exr", *pinhole.CAMERA_ARGS)
    assert status == 2 and err.count("\n") == 1 and str(path) in err, err
    assert not (tmp_path / "v.exr").exists()


def test_write_hologram_and_write_view_refuse_other_suffixes(tmp_path, point_hologram):
    """The EXR writers refuse another suffix, naming it, instead of writing EXR bytes under
    that name or another."""
    with pytest.raises(InputError, match=r"r.png: the file is written as OpenEXR"):
        write_hologram(tmp_path / "r.png", point_hologram)
    view = RenderResult(rgb=np.ones((2, 2, 3)), alpha=np.ones((2, 2)), depth=np.ones((2, 2)))
    with pytest.raises(InputError, match=r"v.png: the file is written as OpenEXR"):
        write_view(view, tmp_path / "v.png")
    assert not list(tmp_path.iterdir())
