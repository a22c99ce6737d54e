"""The camera: Blender's model of a pose, a lens and pixels."""

import numpy as np
import pytest

from holo_core.scene.camera import Camera, look_at
from holo_core.validate import InputError


def test_a_cropped_camera_keeps_every_pixels_ray():
    cam = Camera(
        matrix_world=look_at((0.3, -3, 0.2), (0, 0, 0)),
        resolution=(64, 48),
        shift_x=0.1,
        shift_y=-0.05,
        pixel_aspect=(1, 1.2),
        sensor_fit="VERTICAL",
    )
    crop = cam.cropped(10, 5, 30, 20)
    (tx, ty), (cx, cy) = cam.pixel_tangents(), crop.pixel_tangents()
    assert np.allclose(tx[5:25, 10:40], cx, atol=1e-12) and np.allclose(
        ty[5:25, 10:40], cy, atol=1e-12
    )
    with pytest.raises(InputError, match="inside the 64x48 image"):
        cam.cropped(50, 0, 30, 10)


def test_a_singular_pose_is_refused():
    with pytest.raises(InputError, match="singular"):
        Camera(matrix_world=np.diag([1.0, 0.0, 1.0, 1.0]))


@pytest.mark.parametrize("shift", [(0.0, 0.0), (0.4, -0.3), (-1.2, 0.9)])
def test_the_direction_range_is_that_of_every_pixel(shift):
    """Camera.direction_range reads the image's edge pixels only: it equals the least and
    greatest direction cosines of all pixels, the axis inside the image or beyond it; and
    Camera.tangent_steps gives every pixel's tangents."""
    cam = Camera(
        matrix_world=np.eye(4),
        lens=30,
        sensor_width=36,
        resolution=(64, 36),
        shift_x=shift[0],
        shift_y=shift[1],
    )
    alpha, beta, _ = cam.direction_cosines()
    least, greatest = cam.direction_range()
    t0, dt, r0, dr = cam.tangent_steps()  # the kernels' pixel rays
    tx, ty = cam.pixel_tangents()
    assert np.allclose(tx, t0 + np.arange(64) * dt, rtol=0, atol=1e-15)
    assert np.allclose(ty, r0 + np.arange(36)[:, None] * dr, rtol=0, atol=1e-15)
    assert np.array_equal(least, [alpha.min(), beta.min()])
    assert np.array_equal(greatest, [alpha.max(), beta.max()])
