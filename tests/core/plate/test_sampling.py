"""The optics chosen for a scene in ordinary metres (holo_core.plate.sampling) against the
conditions they are chosen to meet: the camera inside every object point's cone, the off-axis
reference separating the twin image (sin ϑ = 3b) and sampled by the plate (Eq. 19), and the
hologram's side N = 8·S·b/λ."""

import math

import numpy as np

from holo_core.plate.reference import Reference
from holo_core.plate.sampling import band_towards, choose


def test_the_band_towards_a_camera_is_its_widest_angle_from_the_normal():
    """Points at (±a, 0, −d) and a camera at (0, 0, D) on the axis: sin θ = a/√(a² + (D + d)²),
    the angle from the plate normal of the line from the farther side's point."""
    a, d, big_d = 0.02, 0.3, 0.5
    points = [[-a, 0, -d], [a / 2, 0, -d], [a, 0, -d]]
    assert math.isclose(band_towards(points, (0, 0, big_d)), a / math.hypot(a, big_d + d))
    off = band_towards(points, (0.1, 0, big_d))  # beside the axis: the point at −a is farthest
    assert math.isclose(off, (0.1 + a) / math.hypot(0.1 + a, big_d + d))


def test_the_chosen_sampling_holds_the_camera_in_every_cone_and_samples_its_reference():
    """A box of points 0.3 m behind a 5 cm plate, a camera 0.5 m in front: the chosen band
    holds the camera inside every point's cone, the reference at sin ϑ = 3·λ2/(8p) of the
    depth partner passes Eq. 19 on the chosen pitch (no aliasing, no warning), the colour
    wavelength is at least the depth partner's, and the side holds 8·S·b/λ samples within the
    band's margin."""
    rng = np.random.default_rng(7)
    points = np.c_[rng.uniform(-0.02, 0.02, (50, 2)), rng.uniform(-0.32, -0.28, 50)]
    camera = np.array([0.01, -0.005, 0.5])
    s = choose((0.05, 0.05), points, camera=(camera, 2e-4))
    assert s.band >= band_towards(points, camera)
    assert math.isclose(math.sin(s.reference_angle), 3 * s.depth_wavelength / (8 * s.pitch))
    Reference(angle=s.reference_angle).check(s.depth_wavelength, s.pitch)  # raises if aliased
    assert math.sin(s.reference_angle) + s.band <= s.depth_wavelength / (2 * s.pitch)
    assert s.depth_wavelength <= s.wavelength
    assert s.shape == (round(0.05 / s.pitch),) * 2
    assert math.isclose(s.shape[1], 8 * 0.05 * s.band / s.depth_wavelength, rel_tol=0.06)
