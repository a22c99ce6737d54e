"""Transfer functions made on the device against the float64 host reference
``transfer_function``, on both routes: float64 on the device, and the split into float32 terms
for devices without it."""

import numpy as np
import pytest
from accuracy import TRANSFER_ON_DEVICE

from holo_core.propagation import grid, transfer_function
from holo_core.propagation.angular_spectrum import BAND_EDGE
from holo_core.propagation.transfer import asm_transfer, fresnel_transfer

LAM = 633e-9


@pytest.mark.parametrize("split", [False, True])
@pytest.mark.parametrize(
    "pitch, distance, offset, band",
    [
        ((2e-6, 2e-6), 5e-3, (0.0, 0.0), True),
        ((2e-6, 2e-6), -0.8, (0.0, 0.0), False),  # k·z = 7.9e6 rad
        ((1e-6, 3e-6), 0.02, (3e-5, -1e-5), True),  # anisotropic, shifted
        ((4e-6, 4e-6), 1.0, (1e-4, 0.0), True),  # k·z = 9.9e6 rad, far into the band limit
    ],
)
def test_device_transfer_equals_float64(rt, split, pitch, distance, offset, band):
    if not split and not rt.has_fp64:
        pytest.skip("the device has no float64")
    shape = (96, 128)
    got = asm_transfer(
        rt,
        shape,
        wavelength=LAM,
        pitch=pitch,
        distance=distance,
        offset=offset,
        band_limit=band,
        edge=BAND_EDGE,
        split=split,
    ).get() * (96 * 128)
    ref = transfer_function(
        shape, wavelength=LAM, pitch=pitch, distance=distance, offset=offset, band_limit=band
    )
    err = float(np.abs(got - ref).max())
    assert err <= TRANSFER_ON_DEVICE, f"max |device - float64| = {err:.3g}"
    assert np.array_equal(got != 0, ref != 0) or band  # evanescent waves dropped alike


def test_fresnel_transfer_on_the_device(rt):
    if not rt.has_fp64:
        pytest.skip("the device has no float64")
    shape, pitch, z, (x0, y0) = (64, 80), (2e-6, 3e-6), 0.3, (2e-5, 0.0)
    got = fresnel_transfer(
        rt, shape, wavelength=LAM, pitch=pitch, distance=z, offset=(x0, y0)
    ).get() * (64 * 80)
    fy, fx = grid.freqs(64, pitch[1])[:, None], grid.freqs(80, pitch[0])[None, :]
    phase = (
        2 * np.pi * z / LAM - np.pi * LAM * z * (fx**2 + fy**2) + 2 * np.pi * (fx * x0 + fy * y0)
    )
    keep = (np.abs(x0 - LAM * z * fx) <= 80 * pitch[0] / 2) & (
        np.abs(y0 - LAM * z * fy) <= 64 * pitch[1] / 2
    )
    ref = np.where(keep, np.exp(1j * phase), 0)
    err = float(np.abs(got - ref).max())
    assert err <= TRANSFER_ON_DEVICE, f"{err:.3g}"
