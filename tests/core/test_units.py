"""Units guarded: a wavelength outside [1e-13, 1e-2] m (MeV electrons to microwaves) or a pitch
outside [1e-12, 1e-2] m is refused at every public entry, with the unit the number most likely
is in; the waves of electron and X-ray holography pass, and a scan's pitch that looks like
millimetres is warned."""

import numpy as np
import pytest

from holo_core import validate
from holo_core.io.acquired import read_acquired
from holo_core.plate import Reference, record_points
from holo_core.plate.point_sources import point_wave
from holo_core.plate.reference import reference_wave
from holo_core.plate.sampling import choose
from holo_core.propagation import (
    angular_spectrum,
    fraunhofer,
    fresnel,
    propagate_to_plane,
    rayleigh_sommerfeld,
    resample,
    tilt,
)
from holo_core.scene import Hologram
from holo_core.validate import InputError

FIELD = np.ones((16, 16), np.complex64)
NM = r"633 looks like nanometres: pass 633e-9"
UM = r"8 looks like micrometres: pass 8e-6"


def wave(**changes):
    return {"wavelength": 633e-9, "pitch": 1e-6, **changes}


CALLS = {
    "angular_spectrum": lambda w: angular_spectrum(FIELD, **w, distance=1e-3),
    "fresnel": lambda w: fresnel(FIELD, **w, distance=1e-3),
    "fraunhofer": lambda w: fraunhofer(FIELD, **w, distance=1.0),
    "rayleigh_sommerfeld": lambda w: rayleigh_sommerfeld(FIELD, **w, distance=1e-3),
    "tilt": lambda w: tilt(FIELD, **w, rotation=np.eye(3)),
    "propagate_to_plane": lambda w: propagate_to_plane(
        FIELD, **w, rotation=np.eye(3), position=(0, 0, 1e-3)
    ),
    "point_wave": lambda w: point_wave([[0, 0, -1e-3]], [1.0], **w, shape=(8, 8)),
    "reference_wave": lambda w: reference_wave((8, 8), **w, reference=Reference()),
    "record_points": lambda w: record_points(
        [[0, 0, -3e-3]], [[1.0]], shape=(8, 8), pitch=w["pitch"], wavelengths=(w["wavelength"],)
    ),
    "Hologram": lambda w: Hologram(
        intensity=np.ones((1, 4, 4), np.float32), wavelengths=(w["wavelength"],), pitch=w["pitch"]
    ),
    "read_acquired": lambda w: read_acquired("missing.png", **w),
}


@pytest.mark.parametrize("name", CALLS)
def test_a_wavelength_in_nanometres_is_refused_with_the_unit(name):
    with pytest.raises(
        InputError,
        match=r"wavelengths? must be in \[1e-13, 0.01\] \[m\] "
        r"\(MeV electrons to microwaves\); got 633(\.0)? \(" + NM,
    ):
        CALLS[name](wave(wavelength=633))


@pytest.mark.parametrize("name", CALLS)
def test_a_pitch_in_micrometres_is_refused_with_the_unit(name):
    with pytest.raises(
        InputError,
        match=r"pitch must be in \[1e-12, 0.01\] \[m\] \(.*\); "
        r"got 8(\.0)? \(" + UM,
    ):
        CALLS[name](wave(pitch=8))


def test_the_other_checks_refuse_with_the_unit():
    with pytest.raises(
        InputError,
        match=r"wavelength .* \(0.633 looks like micrometres: pass "
        r"0.633e-6\)",
    ):
        choose((0.01, 0.01), [[0, 0, -0.05]], wavelength=0.633)
    with pytest.raises(InputError, match=r"out_pitch .* \(8 looks like micrometres"):
        resample(FIELD, pitch=1e-6, out_shape=(4, 4), out_pitch=8)
    with pytest.raises(InputError, match=r"out_pitch .* \(8 looks like micrometres"):
        rayleigh_sommerfeld(FIELD, **wave(), distance=1e-3, out_pitch=8)


@pytest.mark.parametrize(
    "value, hint",
    [
        (633, "633 looks like nanometres: pass 633e-9"),
        (532.0, "532 looks like nanometres: pass 532e-9"),
        (0.633, "0.633 looks like micrometres: pass 0.633e-6"),
        (10.6, "10.6 looks like micrometres: pass 10.6e-6"),  # CO2 laser, µm
        (1.55, "1.55 looks like micrometres: pass 1.55e-6"),  # telecom, µm
        (1e6, "1e+06 looks like nanometres: pass 0.001"),
    ],
)
def test_the_likely_unit_of_a_wavelength(value, hint):
    with pytest.raises(InputError) as e:
        validate.wavelength("wavelength", value)
    assert hint in str(e.value), str(e.value)


@pytest.mark.parametrize(
    "value, hint",
    [
        (8, "8 looks like micrometres: pass 8e-6"),
        (3.74, "3.74 looks like micrometres: pass 3.74e-6"),  # an SLM's pixel
        (0.5, "0.5 looks like micrometres: pass 0.5e-6"),
    ],
)
def test_the_likely_unit_of_a_pitch(value, hint):
    with pytest.raises(InputError) as e:
        validate.pitch("pitch", value)
    assert hint in str(e.value), str(e.value)


@pytest.mark.parametrize("value", [0.0, -633e-9, 1e-300, 0.05])
def test_lengths_that_name_no_unit_get_no_hint(value):
    """Zero, negative, tiny, or a small number of metres (5 cm: a real, if odd, length): the
    range alone, no guessed unit."""
    with pytest.raises(InputError) as e:
        validate.wavelength("wavelength", value)
    assert "looks like" not in str(e.value), str(e.value)


def test_the_range_ends_are_accepted():
    lo, hi = validate.WAVELENGTH_RANGE
    assert (validate.wavelength("w", lo), validate.wavelength("w", hi)) == (1e-13, 1e-2)
    lo, hi = validate.PITCH_RANGE
    assert (validate.pitch("p", lo), validate.pitch("p", hi)) == (1e-12, 1e-2)


@pytest.mark.parametrize(
    "wavelength, pitch",
    [
        (1.9687e-12, 0.92e-9),  # 300 kV electrons, holospy's Fe needle sampled at 0.92 nm
        (0.87e-12, 5e-12),  # a 1 MV holography microscope at atomic resolution
        (1.54e-10, 13.5e-6),  # Cu K-alpha X-rays on a 13.5 µm detector
        (3e-3, 1e-3),  # 100 GHz millimetre waves on a 1 mm array
    ],
)
def test_electron_x_ray_and_millimetre_waves_pass(wavelength, pitch):
    """Real waves and samplings of other holographies are accepted everywhere, with no
    scale-free context: a Hologram holds them and a propagation runs at them."""
    h = Hologram(intensity=np.ones((1, 4, 4), np.float32), wavelengths=(wavelength,), pitch=pitch)
    assert (h.wavelengths, h.pitch) == ((wavelength,), pitch)
    angular_spectrum(FIELD, wavelength=wavelength, pitch=pitch, distance=10 * pitch)


def test_a_scan_pitch_in_millimetres_is_warned_with_the_value():
    """0.00345 (3.45 µm typed in millimetres) is a real but implausible pixel: warned with
    what it would be in metres; 3.45e-6 passes quietly."""
    with pytest.warns(
        validate.UnitWarning,
        match=r"pitch 0.00345 m is 3.45 mm, coarser than "
        r"any camera's .* pass 3.45e-06",
    ):
        assert validate.pitch_typed("pitch", 0.00345) == 0.00345
    assert validate.pitch_typed("pitch", 3.45e-6) == 3.45e-6


def test_the_plate_renderer_keeps_its_scale_free_wavelengths():
    """The plate renderer chooses its own wavelength for the image (Sect. VII-B): inside
    ``scale_free`` (record_hologram, render_view, reconstruct, read_hologram) any length in
    [1e-13, 1e3] m passes; the same number typed by a person outside it is refused."""
    with validate.scale_free():
        assert validate.wavelength("wavelength", 2e-2) == 2e-2
        assert validate.pitch("pitch", 0.05) == 0.05
    with pytest.raises(InputError, match="wavelength must be in"):
        validate.wavelength("wavelength", 2e-2)
    with pytest.raises(InputError, match="pitch must be in"):
        Hologram(intensity=np.ones((1, 4, 4), np.float32), wavelengths=(633e-9,), pitch=0.05)


@pytest.mark.parametrize(
    "text, metres",
    [
        ("3.45um", 3.45e-6),
        ("3.45 µm", 3.45e-6),
        ("5cm", 0.05),
        ("0.05", 0.05),
        ("1.97pm", 1.97e-12),
        ("2e-3 m", 2e-3),
        ("1.5angstrom", 1.5e-10),
    ],
)
def test_lengths_with_their_units(text, metres):
    from holo_core import units

    assert units.length(text, "length") == metres


def test_an_electron_microscope_states_its_wave_as_a_voltage():
    """λ = h/√(2·m·e·U·(1 + e·U/(2·m·c²))): 1.9687 pm at 300 kV (holospy's Fe needle), 2.5079
    pm at 200 kV, 0.8719 pm at 1 MV (tabulated relativistic values)."""
    from holo_core import units

    for text, pm in (("300kV", 1.9687), ("200 kV", 2.5079), ("1MV", 0.8719)):
        assert units.wavelength(text) == pytest.approx(pm * 1e-12, rel=1e-4), text
    assert units.wavelength("633") == 633e-9  # a plain number: nm, as --wavelengths
    with pytest.raises(InputError, match="unknown unit 'furlong'"):
        units.length("3 furlong", "length")
    with pytest.raises(InputError, match="millivolts"):
        units.wavelength("300mV")
