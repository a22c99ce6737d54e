"""Bad input gets a ValueError naming the argument and its allowed range."""

import numpy as np
import pytest

from holo_core.propagation import angular_spectrum, rayleigh_sommerfeld, resample, tilt

GOOD = dict(wavelength=633e-9, pitch=1e-6, distance=1e-3)
FIELD = np.ones((16, 16), np.complex64)


@pytest.mark.parametrize("field, changes, message", [
    (np.full((8, 8), np.nan), {}, "field must be finite"),
    (np.ones((8, 8)) * np.inf, {}, "field must be finite"),
    (np.ones((4, 4, 4)), {}, "field must be a 2-D array"),
    (FIELD, {"wavelength": 0.0}, r"wavelength must be in \[1e-12, 1000\] \[m\]; got 0.0"),
    (FIELD, {"wavelength": -5e-7}, r"wavelength must be in \[1e-12, 1000\] \[m\]"),
    (FIELD, {"pitch": 0}, r"pitch must be in \[1e-12, 1000\] \[m\]; got 0"),
    (FIELD, {"pitch": float("nan")}, r"pitch must be finite"),
    (FIELD, {"padding": 0.5}, r"padding must be >= 1"),
    (FIELD, {"padding": 100}, r"padding must be in \[1, 16\]"),
    (FIELD, {"offset": (1.0,)}, r"offset must be a pair"),
])
def test_angular_spectrum_rejects(field, changes, message):
    with pytest.raises(ValueError, match=message):
        angular_spectrum(field, **{**GOOD, **changes})


def test_device_arrays_are_checked_too(rt):
    bad = np.ones((8, 8), np.complex64)
    bad[3, 4] = np.nan
    with pytest.raises(ValueError, match="field must be finite"):
        angular_spectrum(rt.to_device(bad), **GOOD)
    with pytest.raises(ValueError, match="field must be finite"):
        tilt(rt.to_device(bad), wavelength=633e-9, pitch=1e-6, rotation=np.eye(3))


def test_other_stages_reject_bad_settings():
    with pytest.raises(ValueError, match="distance must be non-zero"):
        rayleigh_sommerfeld(FIELD, wavelength=633e-9, pitch=1e-6, distance=0.0)
    with pytest.raises(ValueError, match="rotation must be a rotation"):
        tilt(FIELD, wavelength=633e-9, pitch=1e-6, rotation=np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ValueError, match=r"out_shape must be a pair of integers >= 1"):
        resample(FIELD, pitch=1e-6, out_shape=(0, 4), out_pitch=1e-6)
    with pytest.raises(ValueError, match=r"out_pitch must be in \[1e-12, 1000\] \[m\]"):
        resample(FIELD, pitch=1e-6, out_shape=(4, 4), out_pitch=-1)
