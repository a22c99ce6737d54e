"""A phase SLM as a lab drives it: presets, look-up tables refused naming the file, a laser
without its table named, and scenes the display cannot show refused before any work with
the numbers."""

import math

import numpy as np
import pytest

from holo_core.phase.display import PHASE_PRESETS, Display, display_preset
from holo_core.phase.slm import (
    EyeBox,
    Laser,
    PhaseTable,
    SLMSetup,
    check_scene,
    diffraction_angle,
    read_phase_table,
)
from holo_core.validate import InputError


def test_the_presets_are_the_common_phase_slms():
    got = {n: (display_preset(n).resolution, display_preset(n).pitch) for n in PHASE_PRESETS}
    assert got == {
        "slm-1080p-8um": ((1920, 1080), 8e-6),
        "slm-1080p-6.4um": ((1920, 1080), 6.4e-6),
        "slm-4k-3.74um": ((3840, 2160), 3.74e-6),
        "slm-4k-3.6um": ((3840, 2160), 3.6e-6),
    }
    custom = display_preset("slm-1080p-8um", bit_depth=10, phase_range=3 * math.pi, inverted=True)
    assert (custom.bit_depth, custom.phase_range, custom.inverted) == (10, 3 * math.pi, True)
    with pytest.raises(InputError, match="phase_range must be in"):
        Display(name="x", resolution=(4, 4), pitch=8e-6, phase_range=math.pi)
    with pytest.raises(InputError, match="inverted must be True or False"):
        Display(name="x", resolution=(4, 4), pitch=8e-6, inverted="yes")


def linear(bits, span=2 * math.pi):
    return np.arange(2**bits) * span / 2**bits


@pytest.mark.parametrize("suffix", [".npy", ".csv", ".txt"])
def test_a_table_file_reads_back(tmp_path, suffix):
    phases = linear(8, 2.9 * math.pi)
    path = tmp_path / f"lut{suffix}"
    if suffix == ".npy":
        np.save(path, phases)
    elif suffix == ".csv":
        path.write_text(
            "code,phase\n" + "".join(f"{k},{float(p)!r}\n" for k, p in enumerate(phases))
        )
    else:
        path.write_text("".join(f"{float(p)!r}\n" for p in phases))
    t = read_phase_table(path, wavelength=638e-9, bit_depth=8)
    assert np.array_equal(t.phases, phases) and t.source == path.name and t.bit_depth == 8


@pytest.mark.parametrize(
    "content, why",
    [
        (linear(7), "128 entries; a 8-bit display's table has 256"),  # wrong size
        (np.stack([linear(8), linear(8)]), "one column of phases"),  # wrong shape
        (linear(8, 1.0), "span 0.9961 rad"),  # waves, not radians
        (linear(8, 6 * math.pi), "span 18.78 rad"),  # beyond 4π
        (np.r_[linear(8)[:-1], np.nan], "NaN or infinite"),  # not finite
    ],
)
def test_a_wrong_table_is_refused_naming_the_file(tmp_path, content, why):
    path = tmp_path / "red_lut.npy"
    np.save(path, content)
    with pytest.raises(InputError) as e:
        read_phase_table(path, wavelength=638e-9, bit_depth=8)
    assert str(path) in str(e.value) and why in str(e.value), str(e.value)


def test_a_damaged_or_missing_table_is_refused_naming_the_file(tmp_path):
    path = tmp_path / "lut.csv"
    path.write_text("0,0.0\n1,zero\n")
    with pytest.raises(InputError, match=f"{path}: line 2 is not numbers"):
        read_phase_table(path, wavelength=638e-9, bit_depth=1)
    path.write_text("".join(f"{k + 1},{p}\n" for k, p in enumerate(linear(8))))
    with pytest.raises(InputError, match=f"{path}: its first column must be the codes"):
        read_phase_table(path, wavelength=638e-9, bit_depth=8)
    with pytest.raises(InputError, match="no such phase table"):
        read_phase_table(tmp_path / "none.npy", wavelength=638e-9, bit_depth=8)


def test_a_laser_without_its_table_is_named():
    d = display_preset("slm-1080p-8um")
    red = PhaseTable(wavelength=638e-9, phases=linear(8), source="red.npy")
    with pytest.raises(
        InputError,
        match=r"no phase table for the wavelength 520 nm; the tables "
        r"given are for 638 nm \(red.npy\)",
    ):
        SLMSetup(
            display=d, lasers=[Laser(wavelength=638e-9), Laser(wavelength=520e-9)], tables=[red]
        )
    s = SLMSetup(display=d, lasers=[Laser(wavelength=638e-9, power=0.02)], tables=[red])
    assert s.table_for(638e-9) is red and s.lasers[0].power == 0.02
    with pytest.raises(InputError, match="256"):
        SLMSetup(
            display=display_preset("slm-1080p-8um", bit_depth=10),
            lasers=[Laser(wavelength=638e-9)],
            tables=[red],
        )


def test_the_eye_box_beyond_the_diffraction_angle_is_refused_with_what_fits():
    """asin(λ/2p) at 488 nm and 8 µm is 1.748°; at 300 mm the eye box's diagonal may reach
    ±9.16 mm. A 14 x 14 mm box reaches hypot(7, 7) = 9.90 mm: refused, naming the fits."""
    assert math.degrees(diffraction_angle(488e-9, 8e-6)) == pytest.approx(1.7477, abs=1e-4)
    lasers = [Laser(wavelength=w) for w in (638e-9, 520e-9, 488e-9)]
    s = SLMSetup(
        display="slm-1080p-8um", lasers=lasers, eye_box=EyeBox(size=(14e-3, 14e-3), distance=0.3)
    )
    with pytest.raises(InputError) as e:
        check_scene(s, extent=(0, 0))
    msg = str(e.value)
    for part in (
        "reaches 1.89°",
        "beyond the 1.75°",
        "8 µm",
        "488 nm",
        "diagonal of 18.3 mm",
        "move it to >= 324.4 mm",
        "pitch <= 7.4 µm",
    ):
        assert part in msg, msg
    ok = SLMSetup(
        display="slm-1080p-8um",
        lasers=lasers,
        band=1.0,
        eye_box=EyeBox(size=(12e-3, 12e-3), distance=0.3),
    )
    assert check_scene(ok, extent=(0, 0)) == []


def test_objects_too_close_for_the_pitch_are_refused_with_the_numbers():
    """A scene ±2 mm wide seen from a 2 mm eye box at 100 mm through the half-Nyquist filter
    (0.874° at 488 nm): rays from its corner at z = −1 mm need atan(hypot(3, 3)/101) = 2.41°, so
    it must sit at z <= 100 − 4.243/tan(0.874°) = −178 mm."""
    s = SLMSetup(
        display="slm-1080p-8um",
        lasers=[Laser(wavelength=488e-9)],
        eye_box=EyeBox(size=(2e-3, 2e-3), distance=0.1),
        depth_range=(-1e-3, 0.0),
    )
    with pytest.raises(InputError) as e:
        check_scene(s, extent=(2e-3, 2e-3))
    msg = str(e.value)
    for part in (
        "objects too close for the pitch",
        "z = -1 mm",
        "2.41°",
        "0.874°",
        "z <= -178",
        "pitch <= 2.9",
    ):
        assert part in msg, msg
    far = SLMSetup(
        display="slm-1080p-8um",
        lasers=[Laser(wavelength=488e-9)],
        eye_box=EyeBox(size=(2e-3, 2e-3), distance=0.1),
        depth_range=(-0.5, -0.2),
    )
    assert check_scene(far, extent=(2e-3, 2e-3)) == []
