"""Point holograms on a 1 µm plate at 633 nm, recorded off axis, and cameras 4 mm in front of
the plate looking at its centre: the scenes of the tests of image formation."""

import math

import numpy as np

from holo_core.plate.points import record_points
from holo_core.plate.reference import Reference
from holo_core.scene.camera import Camera, look_at

LAM, PITCH, N = 633e-9, 1e-6, 512
EYE = np.array([0.0, 0.0, 4e-3])


def off_axis(lam2=LAM, pitch=PITCH):
    """The off-axis recording of holo_core.plate.sampling: cone b = λ/(8d), reference sin ϑ = 3b."""
    return dict(
        band=0.95 * lam2 / (8 * pitch), reference=Reference(angle=math.asin(3 * lam2 / (8 * pitch)))
    )


def point_hologram(points, wavelengths=(LAM,), channels=(), n=N, seeds=(0,), pitch=PITCH):
    pts = np.asarray(points, np.float64)
    return [
        record_points(
            pts,
            np.ones((len(pts), len(wavelengths))),
            shape=(n, n),
            pitch=pitch,
            wavelengths=wavelengths,
            channels=channels,
            seed=s,
            **off_axis(min(wavelengths), pitch),
        )
        for s in seeds
    ]


def camera(pixel_angle, size, **kw):
    """A camera at EYE looking at the plate centre with the given pixel angle [rad]."""
    kw.setdefault("matrix_world", look_at(EYE, (0, 0, 0), up=(0, 1, 0)))
    return Camera(lens=50, sensor_width=50 * size * pixel_angle, resolution=(size, size), **kw)
