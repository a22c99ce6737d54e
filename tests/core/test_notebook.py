"""Notebooks: the API listed, one-line summaries, pictures."""

import struct
import zlib

import numpy as np
import pytest

import holo_core
from holo_core import preview
from holo_core.scene import Hologram, Mesh
from holo_core.view import RenderResult


def decoded(png: bytes) -> np.ndarray:
    """The pixels of an 8-bit grey or RGB PNG written by :func:`preview.png`."""
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    w, h, _, colour = struct.unpack(">IIBB", png[16:26])
    at, data = 8, b""
    while at < len(png):
        (n,), kind = struct.unpack(">I", png[at : at + 4]), png[at + 4 : at + 8]
        if kind == b"IDAT":
            data += png[at + 8 : at + 8 + n]
        at += 12 + n
    c = 3 if colour == 2 else 1
    rows = np.frombuffer(zlib.decompress(data), np.uint8).reshape(h, 1 + w * c)
    return rows[:, 1:].reshape(h, w, c).squeeze()


def test_dir_and_all_list_the_api():
    names = dir(holo_core)
    for name in (
        "angular_spectrum",
        "sideband",
        "import_acquired",
        "to_device",
        "Hologram",
        "propagation",
        "plot",
        "scene",
    ):
        assert name in names, name
    assert sorted(holo_core.__all__) == sorted(holo_core._API)
    assert "plot" not in holo_core.__all__  # `import *` does not need matplotlib
    for name in holo_core.__all__:
        assert getattr(holo_core, name) is not None, name


def test_a_hologram_summarises_itself_and_shows_its_intensity(rng):
    intensity = rng.random((3, 600, 40)).astype(np.float32)
    h = Hologram(
        intensity=intensity,
        wavelengths=(633e-9, 532e-9, 473e-9),
        pitch=3.45e-6,
        reference_angle=0.02,
    )
    text = repr(h)
    assert text.startswith(
        "Hologram(600x40, 3 channels R/G/B at 633/532/473 nm, pitch "
        "3.45 µm, intensity, reference 0.02 rad"
    ), text
    assert len(text) < 200 and "array" not in text
    image = decoded(h._repr_png_())
    assert image.shape == (300, 20, 3)  # 600 rows in blocks of 2, at most 512 a side
    want = preview.normalised(np.stack([preview.thumbnail(c) for c in intensity], -1))
    assert np.abs(image / 255 - want).max() <= 0.5 / 255 + 1e-9


def test_a_view_and_a_mesh_summarise_themselves():
    rgb = np.zeros((4, 6, 3))
    rgb[1, 2] = 0.5
    depth = np.full((4, 6), 1e10)
    depth[1, 2] = 0.25
    result = RenderResult(
        rgb=rgb, alpha=(depth < 1).astype(float), depth=depth, info={"wavelengths": [1e-6]}
    )
    assert repr(result) == (
        "RenderResult(6x4, rgb max 0.5, 4.17 % opaque, depth 250 mm to 250 mm, info: wavelengths)"
    )
    image = decoded(result._repr_png_())
    assert image.shape == (4, 6, 3) and image[1, 2, 0] == round(255 * preview.srgb(0.5))
    mesh = Mesh(
        vertices=np.array([[0, 0, -1], [0.1, 0, -1], [0, 0.02, -1.0]]),
        triangles=np.array([[0, 1, 2]]),
    )
    assert repr(mesh) == "Mesh(1 triangle, 3 vertices, extent 100 mm x 20 mm x 0 m, no colours)"


@pytest.mark.parametrize(
    "metres, text",
    [(633e-9, "633 nm"), (3.45e-6, "3.45 µm"), (1e-6, "1 µm"), (0.0125, "12.5 mm"), (2.0, "2 m")],
)
def test_lengths_read_in_their_unit(metres, text):
    assert preview.length(metres) == text


def test_a_device_array_is_one_call_away(rt):
    u = np.ones((4, 6), np.complex64)
    d = holo_core.to_device(u)
    assert d.dtype == np.complex64 and d.shape == (4, 6) and np.array_equal(d.get(), u)
    out = holo_core.angular_spectrum(d, wavelength=633e-9, pitch=1e-6, distance=1e-5)
    assert preview.where(out).startswith("device ")
    with pytest.raises(holo_core.InputError, match="array must be finite"):
        holo_core.to_device(np.full((2, 2), np.nan))
