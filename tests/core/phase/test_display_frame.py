"""A display frame's stage: the SLM's codes within its bits and showing the asked phase, the
10-bit packing its drivers read, and the focal stack of a pattern against an independent
float64 propagation."""

import io
import math

import numpy as np
from PIL import Image

from holo_core.phase.display_frame import codes_of, focal_stack, pattern_png, shown_phase


def test_codes_never_leave_the_bit_depth_and_show_the_phase_within_half_a_level():
    """Phases over four waves, 8 and 10 bits, 2π and 3π, inverted or not: the codes lie in
    [0, 2^bits), and the phase each shows equals the asked one modulo 2π within half a
    level (the wrap checked by complex exponentials, independently of the code's)."""
    phase = np.linspace(-4 * math.pi, 4 * math.pi, 10001)
    for bits in (8, 10):
        for span in (2 * math.pi, 3 * math.pi):
            for inverted in (False, True):
                c = codes_of(phase, bit_depth=bits, phase_range=span, inverted=inverted)
                assert c.max() < 1 << bits, (bits, span, int(c.max()))
                got = shown_phase(c, bit_depth=bits, phase_range=span, inverted=inverted)
                error = np.angle(np.exp(1j * (got - phase)))
                level = span / (1 << bits)
                assert np.abs(error).max() <= level / 2 * (1 + 1e-9), \
                    (bits, span, inverted, float(np.abs(error).max()), level)


def test_ten_bits_are_packed_eight_in_red_and_two_in_blue():
    """Every 10-bit code packed and read back by Pillow: red holds code >> 2, blue's two
    high bits code & 3, green nothing."""
    codes = np.arange(1024, dtype=np.uint16).reshape(32, 32)
    rgb = np.asarray(Image.open(io.BytesIO(pattern_png(codes, "PACKED10"))))
    back = (rgb[..., 0].astype(np.int64) << 2) | (rgb[..., 2].astype(np.int64) >> 6)
    assert np.array_equal(back, codes) and not rgb[..., 1].any()
    grey = np.asarray(Image.open(io.BytesIO(pattern_png(codes * 64, "PNG16"))))
    assert np.array_equal(grey.astype(np.int64), codes * 64)


def test_a_point_comes_to_focus_where_its_wave_converges():
    """The wave of a point 4 mm behind a 128 x 128 display at 8 µm (a diverging spherical
    wave, 520 nm, inside the 4f filter's band): its focal stack's brightest slice is the
    one at its depth (−4 mm) among −8, −4 and 0 mm, more than five times brighter than either (8.8 measured), and
    there its peak is at the point, within a sample."""
    n, p, lam, z0 = 128, 8e-6, 520e-9, -4e-3
    x = (np.arange(n) - n / 2) * p
    r = np.sqrt(x[None, :]**2 + x[:, None]**2 + z0**2)
    # within the 4f filter's band: sin θ <= λ/4p = 0.01625, a footprint of 62 µm radius
    aperture = np.hypot(x[None, :], x[:, None]) < abs(z0) * 0.0155
    u = np.where(aperture, np.exp(2j * math.pi / lam * r) / r, 0)
    stack = focal_stack(u, lam, p, (-8e-3, z0, 0.0))
    peaks = stack.reshape(3, -1).max(1)
    assert peaks[1] > 5 * max(peaks[0], peaks[2]), peaks
    row, col = np.unravel_index(stack[1].argmax(), stack[1].shape)
    assert abs(row - n / 2) <= 1 and abs(col - n / 2) <= 1, (row, col)
