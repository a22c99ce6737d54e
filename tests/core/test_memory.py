"""Sizes refused before allocation, with the size needed and the size available; host
buffers reused."""

import struct

import numpy as np
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


def test_host_buffers_are_reused_page_aligned_and_kept_to_their_number():
    """A buffer handed back serves the next request it holds (the same memory, its start on a
    page, any shape or type that fits); a larger request is new; at most ``kept`` wait, the
    smallest let go first."""
    from holo_core.memory import PAGE, HostBuffers

    pool = HostBuffers(kept=2)
    a = pool.take((3, 100, 70))
    assert a.shape == (3, 100, 70) and a.dtype == np.complex64 and not a.any()
    assert a.ctypes.data % PAGE == 0 and a.flags.c_contiguous
    a[...] = 1 + 2j
    where = a.ctypes.data
    pool.give(a)
    b = pool.take((2, 90, 70), np.float32)  # fits in a's buffer
    assert b.ctypes.data == where and b.ctypes.data % PAGE == 0
    bigger = pool.take((4, 100, 70))
    assert not np.shares_memory(bigger, b)
    for x in (b, bigger, pool.take((1, 8, 8))):
        pool.give(x)
    kept = [pool.take((1, 8, 8)), pool.take((1, 8, 8))]
    assert {k.ctypes.data for k in kept} >= {where}, "the two largest stay"
