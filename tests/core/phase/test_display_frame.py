"""A display's frame (holo_core.phase.display_frame): one laser's recorded wave of a point
behind the display encoded, its pattern and layout readable as the driver and a lab would
read them, its focal stack in focus at the point's depth, every file of the frame named by
its layout; a wave recorded in front of the display carried back to it; a table given for
one laser and not another refused; the frame's typed description checked."""

import json
import math

import numpy as np
import pytest

from holo_core.io.hologram import write_hologram
from holo_core.io.image import read_exr
from holo_core.io.slm import read_pattern
from holo_core.job import DisplayFrame, FrameLaser
from holo_core.phase.display_frame import make_frame, wave_at_display
from holo_core.scene.hologram import Hologram
from holo_core.validate import InputError

N, PITCH, LAM = 128, 8e-6, 520e-9


def _point_wave(z0: float, *, n=N) -> np.ndarray:
    """A point's wave on an n x n grid at PITCH [m], the point at signed depth z0 [m]
    (negative: behind; a diverging wave), its footprint kept inside the band the display's
    filter passes (sin θ <= 0.5·λ/2p)."""
    x = (np.arange(n) - (n - 1) / 2) * PITCH
    r2 = x[None, :] ** 2 + x[:, None] ** 2
    r = np.sqrt(r2 + z0**2)
    inside = np.sqrt(r2) < abs(z0) * 0.9 * 0.5 * LAM / (2 * PITCH)
    sign = 1 if z0 < 0 else -1  # behind: diverging at the plane; in front: converging to it
    return np.where(inside, np.exp(sign * 2j * math.pi / LAM * r) / r, 0)


def _plate(path, wave):
    h = Hologram(
        encoding="complex",
        object_wave=np.stack([wave] * 3).astype(np.complex64),
        wavelengths=(LAM,) * 3,
        pitch=PITCH,
    )
    write_hologram(path, h)
    return path


def _frame(tmp_path, hologram, **changes):
    fields = dict(
        name="Display",
        frame=7,
        folder=str(tmp_path / "out"),
        resolution=(N, N),
        pitch=PITCH,
        bit_depth=8,
        phase_range=2 * math.pi,
        inverted=False,
        packing="grey8",
        lasers=(
            FrameLaser(name="green", wavelength=LAM, power=0.01, hologram=str(hologram), channel=1),
        ),
        scale=0.01,
        front=0.0,
        behind=8e-3,
        eye_distance=0.1,
        eye_box=1e-3,
        pupil=4e-3,
        distance=-4e-3,
        slices=3,
        digest="ab12",
    )
    fields.update(changes)
    return DisplayFrame(**fields)


def test_a_point_behind_the_display_is_in_focus_at_its_depth(tmp_path):
    """A point 4 mm behind: the frame's files are the pattern (8-bit grey, 128 x 128, codes
    read back through its layout), its layout, the stack and its sheet and the frame's
    layout naming them all; seen through a 4 mm pupil 100 mm in front (its Airy radius 2
    samples, the point 4 mm out of focus a disc of 19), the stack's slice at −4 mm (of −8,
    −4, 0 mm) is the brightest at the point, its peak within a sample of the point, in the
    pattern's stack and in the wave's alike."""
    frame = _frame(tmp_path, _plate(tmp_path / "wave.exr", _point_wave(-4e-3)))
    layout = make_frame(frame)
    folder = tmp_path / "out"
    names = sorted(p.name for p in folder.iterdir())
    assert names == [
        "frame_0007.json",
        "frame_0007_520nm.json",
        "frame_0007_520nm.png",
        "frame_0007_stack.exr",
        "frame_0007_stack.png",
    ], names
    assert json.loads((folder / "frame_0007.json").read_text()) == layout
    codes, pattern = read_pattern(folder / "frame_0007_520nm.json")
    assert codes.shape == (N, N) and codes.max() < 256 and pattern["packing"] == "grey8"
    assert pattern["laser"]["wavelength"] == LAM and pattern["extra"]["digest"] == "ab12"
    assert layout["stack"]["depths"] == pytest.approx([-8e-3, -4e-3, 0.0])
    _, stack = read_exr(folder / "frame_0007_stack.exr")
    for prefix in ("", "ref."):
        slices = np.stack([stack[f"{prefix}z{k:02d}.G"] for k in range(3)])
        peaks = slices.reshape(3, -1).max(1)
        assert peaks.argmax() == 1, (prefix, peaks)
        row, col = np.unravel_index(slices[1].argmax(), slices[1].shape)
        assert abs(row - (N - 1) / 2) <= 1 and abs(col - (N - 1) / 2) <= 1, (prefix, row, col)
    green = layout["lasers"][0]
    assert len(green["psnr_db"]) == 3 and all(math.isfinite(v) for v in green["psnr_db"])


def test_a_wave_recorded_in_front_is_carried_back_to_the_display(tmp_path):
    """The wave of a point 4 mm behind the display recorded on the volume's front, 3 mm in
    front of it (the point's wave there, on a wider grid), carried back by −3 mm: on the
    display it is the point's own wave there, against an independent float64 NumPy
    angular spectrum of the same wave, to 1e-3 of its peak."""
    pad = 24
    wide = _point_wave(-7e-3, n=N + 2 * pad)  # 4 mm behind the display is 7 mm behind
    path = _plate(tmp_path / "front.exr", wide)
    frame = _frame(tmp_path, path, front=3e-3)
    got = wave_at_display(frame, frame.lasers[0])
    n = N + 2 * pad
    f = np.fft.fftfreq(2 * n, PITCH)
    arg = 1 / LAM**2 - f[None, :] ** 2 - f[:, None] ** 2
    padded = np.zeros((2 * n, 2 * n), complex)
    padded[n // 2 : n // 2 + n, n // 2 : n // 2 + n] = wide
    h = np.where(arg > 0, np.exp(2j * math.pi * np.sqrt(np.maximum(arg, 0)) * -3e-3), 0)
    want = np.fft.ifft2(np.fft.fft2(padded) * h)[n // 2 : n // 2 + n, n // 2 : n // 2 + n]
    want = want[pad : pad + N, pad : pad + N]
    want /= np.abs(want).max()
    error = np.abs(got - want).max()
    assert error < 1e-3, error


def test_a_table_for_one_laser_and_not_another_is_refused(tmp_path):
    """Tables for the red laser but none for the green: refused naming the green one."""
    path = _plate(tmp_path / "wave.exr", _point_wave(-4e-3))
    table = tmp_path / "red.txt"
    table.write_text("\n".join(str(2 * math.pi * k / 256) for k in range(256)))
    lasers = (
        FrameLaser(
            name="red",
            wavelength=638e-9,
            power=0.01,
            hologram=str(path),
            channel=0,
            table=str(table),
        ),
        FrameLaser(name="green", wavelength=LAM, power=0.01, hologram=str(path), channel=1),
    )
    with pytest.raises(InputError, match="not for green"):
        make_frame(_frame(tmp_path, path, lasers=lasers))
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_the_frame_description_is_checked_and_crosses_as_plain_data(tmp_path):
    """DisplayFrame.to_dict → from_dict gives the same frame; an unknown field, a packing
    the writers lack and a negative volume are refused naming them."""
    frame = _frame(tmp_path, tmp_path / "wave.exr")
    assert DisplayFrame.from_dict(json.loads(json.dumps(frame.to_dict()))) == frame
    data = frame.to_dict()
    with pytest.raises(InputError, match="no field 'colour'"):
        DisplayFrame.from_dict({**data, "colour": 1})
    with pytest.raises(InputError, match="packing"):
        _frame(tmp_path, tmp_path / "wave.exr", packing="grey10")
    with pytest.raises(InputError, match="behind must be >= 0"):
        _frame(tmp_path, tmp_path / "wave.exr", behind=-1e-3)
