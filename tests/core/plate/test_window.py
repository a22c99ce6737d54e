"""The part of a plate a camera's pupil sees the objects through (holo_core.plate.window),
against the rays it is made of, computed here independently."""

from types import SimpleNamespace

import numpy as np

from holo_core.plate.window import carrier_window, image_corners, plate_window
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.plate import Carrier

BOUNDS = np.array([[-0.01, -0.008, -0.06], [0.012, 0.01, -0.04]])  # the objects' box [m]
PITCH, SHAPE = 20e-6, (1001, 1201)  # a 24 x 20 mm plate


def _crossings(position, rotation, diameter):
    """(x, y) [m] where the lines from the pupil's rim (and centre) to the box's corners cross
    the plate z = 0."""
    rim = [position] + [
        position + s * diameter / 2 * rotation[:, a] for a in (0, 1) for s in (-1, 1)
    ]
    corners = np.array(
        [[x, y, z] for x in BOUNDS[:, 0] for y in BOUNDS[:, 1] for z in BOUNDS[:, 2]]
    )
    return np.array([p[:2] + p[2] / (p[2] - c[2]) * (c[:2] - p[:2]) for p in rim for c in corners])


def test_the_window_holds_every_ray_from_the_pupils_rim_to_the_objects(rng):
    h = SimpleNamespace(bounds=BOUNDS, pitch=PITCH, shape=SHAPE)
    rows, cols = SHAPE
    for _ in range(20):
        position = np.array([*rng.uniform(-0.01, 0.01, 2), rng.uniform(0.05, 0.2)])
        camera = Camera(matrix_world=look_at(position, (0, 0, -0.05)), resolution=(8, 6))
        rotation = camera.rotation
        diameter = rng.uniform(1e-3, 8e-3)
        r0, r1, c0, c1 = plate_window(h, position, rotation, diameter)
        xy = _crossings(position, rotation, diameter)
        j, i = xy[:, 0] / PITCH + (cols - 1) / 2, xy[:, 1] / PITCH + (rows - 1) / 2
        assert c0 <= j.min() and j.max() <= c1 - 1, (c0, c1, j.min(), j.max())
        assert r0 <= i.min() and i.max() <= r1 - 1, (r0, r1, i.min(), i.max())


def test_a_carrier_plates_window_lies_on_its_samples_or_is_none_beside_them():
    """Looking at the objects, the window is a part of the samples holding the rays' middle;
    looking away from the plate, the pupil sees the objects beside it: None."""
    origin = (-(SHAPE[1] - 1) / 2 * PITCH, -(SHAPE[0] - 1) / 2 * PITCH)
    h = SimpleNamespace(
        bounds=BOUNDS,
        pitch=PITCH,
        shape=SHAPE,
        carrier=Carrier(centre=(0.0, 0.0, 0.1), origin=origin, row_pitch=PITCH),
    )
    position = np.array([0.002, -0.001, 0.1])
    at = Camera(matrix_world=look_at(position, (0, 0, -0.05)), resolution=(16, 12), lens=20)
    r0, r1, c0, c1 = carrier_window(h, position, at.rotation, 4e-3, image_corners(at, at.rotation))
    assert 0 <= r0 < r1 <= SHAPE[0] and 0 <= c0 < c1 <= SHAPE[1]
    middle = _crossings(position, at.rotation, 4e-3).mean(0)
    j, i = (middle - origin) / PITCH
    assert c0 <= j < c1 and r0 <= i < r1, ((r0, r1, c0, c1), (i, j))
    away = Camera(matrix_world=look_at(position, (1.0, 0, 0.05)), resolution=(16, 12), lens=50)
    assert (
        carrier_window(h, position, away.rotation, 4e-3, image_corners(away, away.rotation)) is None
    )
