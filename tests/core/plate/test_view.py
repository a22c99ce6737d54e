"""A plate's view refuses what it cannot render (bad settings, holograms of other optics, a
view whose arithmetic overflows) and says when a camera outside the light sees nothing."""

import dataclasses
import math

import numpy as np
import pinhole
import pytest

from holo_core.plate.view import EmptyViewWarning, NoDepthWarning, render_view
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.hologram import Hologram
from holo_core.validate import InputError


def test_render_settings_are_checked(point_hologram):
    cam = pinhole.camera()
    for kwargs, problem in [({"exposure": float("nan")}, "exposure"),
                            ({"exposure": -1.0}, "exposure"),
                            ({"opacity_threshold": float("nan")}, "opacity_threshold")]:
        with pytest.raises(InputError, match=problem):
            render_view(point_hologram, cam, **kwargs)
    other = Hologram(intensity=point_hologram.intensity, wavelengths=(532e-9,), pitch=1e-6)
    with pytest.raises(InputError, match=r"holograms\[1\] has wavelengths"):
        render_view([point_hologram, other], cam)
    with pytest.warns(NoDepthWarning, match="no depth channel"):
        render_view(point_hologram, cam)


def test_a_camera_outside_the_viewing_zone_warns_that_the_view_is_black(point_hologram):
    """Finding 9: a camera far off the plate's axis rendered black without a word. The light
    of this hologram (pitch 1 µm, λ 633 nm) leaves within asin(λ/2p) = 18.5° of the normal."""
    for degrees in (30, 60, 89):
        a = math.radians(degrees)
        eye = 8e-3 * np.array([math.sin(a), 0, math.cos(a)])
        cam = Camera(matrix_world=look_at(eye, (0, 0, -3e-3)), lens=50, resolution=(16, 16),
                     sensor_width=50 * 16 * 4e-3)
        with pytest.warns(EmptyViewWarning, match=r"the view is black: the camera is "
                                                  r"\d+\.\d° off the plate's normal.*"
                                                  r"within 18.5°"):
            view = render_view(point_hologram, cam)
        assert not view.rgb.any() and not view.alpha.any()


def test_a_view_that_overflows_is_refused_not_nan(point_hologram):
    """Found by the fuzz suite: one pixel at 3e38 (finite, so the file reads) overflowed the
    view's float32 arithmetic and rendered NaN."""
    hot = point_hologram.intensity.copy()
    hot[0, 5, 7] = 3e38
    with pytest.raises(InputError, match=r"intensity must stay within float32 .* reaches 3e\+38"):
        render_view(dataclasses.replace(point_hologram, intensity=hot), pinhole.camera())


def test_an_exposure_that_overflows_the_view_is_refused_by_name():
    """A plate of emitters with a known density and a depth partner, seen at an exposure that
    takes its pixels past float32's largest number: the project's error naming the exposure
    (it once ended in a TypeError of the view's own variables)."""
    from holo_core.plate.points import record_points
    h = record_points([[0, 0, -3e-3]], [[1.0, 1.0]], shape=(128, 128), pitch=1e-6,
                      wavelengths=(633e-9, 0.98 * 633e-9), channels=("R", "Z"),
                      point_density=1e6)
    assert h.depth_channel() == 1 and h.point_density
    with pytest.raises(InputError, match=r"exposure must keep the view's pixels within "
                                         r"float32 \(finite\); got 1e\+38"):
        render_view(h, pinhole.camera(), exposure=1e38)
