"""A view's colours (holo_core.view): one channel is grey, three are R, G, B, any other count
spreads the channels over the hues, equal radiance in every channel is white; a view of two
channels shows the first red and the second cyan."""

import numpy as np
import pytest

from holo_core.plate.points import record_points
from holo_core.plate.view import render_view
from holo_core.scene.camera import Camera, look_at
from holo_core.view import as_rgb, channel_colours


@pytest.mark.parametrize("count", [1, 2, 3, 4, 5, 16])
def test_every_channel_count_has_stated_colours(count):
    """One channel is grey, three are R, G, B as recorded, any other count spreads the
    channels over the hues; equal radiance in every channel is white of that radiance."""
    m = channel_colours(count)
    assert m.shape == (count, 3) and (m >= 0).all()
    assert np.allclose(np.ones(count) @ m, 1), np.ones(count) @ m
    if count in (1, 3):
        assert np.array_equal(m, np.ones((1, 3)) if count == 1 else np.eye(3))
    if count == 2:  # red and its complement, cyan
        assert np.array_equal(m, [[1, 0, 0], [0, 1, 1]])
    radiance = np.random.default_rng(count).random((4, 5, count))
    assert as_rgb(radiance).shape == (4, 5, 3)


def test_a_two_channel_view_shows_the_first_red_and_the_second_cyan():
    """A point lit in the first channel only shows red: its G and B are exactly zero."""
    h = record_points(
        [[0, 0, -3e-3]], [[1.0, 0.0]], shape=(128, 128), pitch=1e-6, wavelengths=(633e-9, 532e-9)
    )
    cam = Camera(
        matrix_world=look_at((0, 0, 4e-3), (0, 0, -3e-3)),
        lens=50,
        sensor_width=50 * 16 * 4e-3,
        resolution=(16, 16),
    )
    with pytest.warns(UserWarning, match="no depth channel"):
        view = render_view(h, cam, supersample=1)
    assert view.rgb.shape == (16, 16, 3)
    assert view.rgb[..., 0].max() > 0 and not view.rgb[..., 1:].any()
