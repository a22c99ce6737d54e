"""The camera: Blender's model of a pose, a lens and pixels."""

import numpy as np
import pytest

from holo_core.scene.camera import Camera, look_at
from holo_core.validate import InputError


def test_a_cropped_camera_keeps_every_pixels_ray():
    cam = Camera(matrix_world=look_at((0.3, -3, 0.2), (0, 0, 0)), resolution=(64, 48),
                 shift_x=0.1, shift_y=-0.05, pixel_aspect=(1, 1.2), sensor_fit="VERTICAL")
    crop = cam.cropped(10, 5, 30, 20)
    (tx, ty), (cx, cy) = cam.pixel_tangents(), crop.pixel_tangents()
    assert np.allclose(tx[5:25, 10:40], cx, atol=1e-12) and np.allclose(ty[5:25, 10:40], cy,
                                                                        atol=1e-12)
    with pytest.raises(InputError, match="inside the 64x48 image"):
        cam.cropped(50, 0, 30, 10)


def test_a_singular_pose_is_refused():
    with pytest.raises(InputError, match="singular"):
        Camera(matrix_world=np.diag([1.0, 0.0, 1.0, 1.0]))
