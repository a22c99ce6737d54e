"""A point 3 mm behind a 128 µm plate (the geometry of the pinhole physics test) and a camera
4 mm in front of the plate that sees it: the hologram the readers', the renderer's and the
command line's refusals are tried on."""

from holo_core.plate.points import record_points
from holo_core.scene.camera import Camera, look_at


def record():
    return record_points(
        [[0, 0, -3e-3]], [[1.0]], shape=(128, 128), pitch=1e-6, wavelengths=(633e-9,)
    )


def camera(resolution=(16, 16)):
    return Camera(
        matrix_world=look_at((0, 0, 4e-3), (0, 0, -3e-3)),
        lens=50,
        sensor_width=50 * 48 * 4e-3 * resolution[0] / 48,
        resolution=resolution,
    )


# the camera's settings on the command line
CAMERA_ARGS = ["--camera", 0, 0, 4e-3, "--sensor-width", 50 * 16 * 4e-3, "--resolution", 16, 16]
