"""Wavefront recording planes (holo_core.plate.recording_planes) against the direct sum of the
same points (Eq. 3 carried by Eq. 14), within the planes' stated tolerance."""

import numpy as np
from accuracy import WRP_VS_DIRECT, rel_err
from point_sums import LAM, PITCH

from holo_core.plate.point_sources import point_wave


def test_recording_planes_match_the_direct_sum(rng):
    shape, n = (256, 256), 3000
    half = shape[0] * PITCH / 2
    pos = np.c_[rng.uniform(-half, half, (n, 2)), rng.uniform(-0.2, -0.1, n)]
    amp = np.exp(2j * np.pi * rng.random(n))
    direct = point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=shape, method="direct")
    wrp = point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=shape, method="wrp")
    err = rel_err(wrp, direct)
    assert err < WRP_VS_DIRECT, f"wavefront recording planes vs direct sum: {err:.2e}"
