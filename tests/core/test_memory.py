"""Sizes refused before allocation, with the size needed and the size available."""

import struct

import pinhole
import pytest

from holo_core.io.hologram import HologramFileError, read_hologram, write_hologram
from holo_core.plate.points import record_points
from holo_core.plate.view import render_view
from holo_core.validate import InputError


def test_sizes_are_refused_before_allocation(tmp_path, point_hologram):
    with pytest.raises(InputError, match=r"needs [\d.e+]+ GiB of memory; [\d.]+ GiB is available"):
        record_points(
            [[0, 0, -1.0]], [[1.0]], shape=(200000, 200000), pitch=8e-6, wavelengths=(633e-9,)
        )
    with pytest.raises(InputError, match="20000x20000 view"):
        render_view(point_hologram, pinhole.camera((20000, 20000)))
    # an EXR header declaring 100000² pixels: refused from the header alone
    path = write_hologram(tmp_path / "h.exr", point_hologram)
    data = path.read_bytes()
    at = data.find(b"dataWindow\x00box2i\x00") + len(b"dataWindow\x00box2i\x00") + 4
    path.write_bytes(data[: at + 8] + struct.pack("<ii", 99999, 99999) + data[at + 16 :])
    with pytest.raises(HologramFileError, match="100000x100000 pixels"):
        read_hologram(path)
