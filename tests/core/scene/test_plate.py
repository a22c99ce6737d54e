"""The plate and its viewing zone: the box in the plate's frame a camera's pupil looks from."""

import numpy as np
import pytest

from holo_core.scene.camera import Camera, look_at
from holo_core.scene.plate import Plate, ViewingZone
from holo_core.validate import InputError


def test_zone_around_a_camera_covers_its_pupil():
    cam = Camera(
        matrix_world=look_at((0.01, 0.02, 0.3), (0, 0, -0.3)),
        lens=50,
        fstop=2.8,
        focus_distance=0.6,
    )
    plate = Plate(matrix_world=np.eye(4), width=0.1, height=0.1)
    zone = plate.zone_for(cam, margin=0.03)
    assert np.allclose(zone.centre, (0.01, 0.02, 0.3))
    assert np.allclose(zone.half_extents[:2], 0.05 / 2.8 / 2 + 0.03)
    assert zone.pupil == pytest.approx(0.05 / 2.8)
    assert zone.distance_outside(cam.position, cam.aperture_diameter / 2) == 0
    # a camera 5 cm to the side: its pupil's rim reaches 5 + 0.89 - 3.89 = 2 cm beyond
    beyond = zone.distance_outside(cam.position + [0.05, 0, 0], cam.aperture_diameter / 2)
    assert beyond == pytest.approx(0.02, abs=1e-9), beyond


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"centre": (0, 0, 0.1), "half_extents": (0.1, 0.1, 0.2)}, "in front of the plate"),
        ({"centre": (0, 0, 1), "half_extents": (-0.1, 0.1, 0.1)}, "half_extents"),
        ({"centre": (0, np.nan, 1), "half_extents": (0.1, 0.1, 0.1)}, "zone centre"),
        ({"centre": (0, 0, 1), "half_extents": (0.1, 0.1, 0.1), "pupil": -1}, "pupil"),
    ],
)
def test_bad_zones_are_refused_by_name(kwargs, field):
    with pytest.raises(InputError, match=field):
        ViewingZone(**kwargs)
