"""Motion blur of camera holograms: a moving mesh averaged over the shutter against the
exposure's geometry (a straight edge moving L pixels fades linearly over L pixels) and
against the same mesh standing still."""

import numpy as np

from holo_core.camera.render import render_camera
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.mesh import Mesh

SIZE = (96, 64)
CAMERA = Camera(matrix_world=look_at((0.0, -3.0, 0.0), (0, 0, 0)), resolution=SIZE)


def _card(dx=0.0):
    """A square card 1 m wide facing the camera at 3 m, shifted ``dx`` [m] along x."""
    v = np.array([[-0.5, 0, -0.5], [0.5, 0, -0.5], [0.5, 0, 0.5], [-0.5, 0, 0.5]])
    return Mesh(
        vertices=v + (dx, 0, 0),
        triangles=np.array([[0, 1, 2], [0, 2, 3]]),
        colours=np.full((4, 3), 0.7),
    )


def _width(profile):
    """The 10-90 % width [px] of a falling edge profile from 1 to 0."""
    lo, hi = (
        np.interp(0.9, profile[::-1], np.arange(len(profile))[::-1]),
        np.interp(0.1, profile[::-1], np.arange(len(profile))[::-1]),
    )
    return hi - lo


def test_a_card_moving_eight_pixels_fades_over_eight_pixels():
    """The card's right edge moves 8 px during the shutter (its motion: the start and the
    end): the alpha across the edge falls linearly over those pixels (10-90 % width
    0.8 x 8 = 6.4 px, within 0.5 px for the pupil's own 1 px), the fade is one ramp (no
    step between the shutter's times deviates from it by more than 0.05), and the card's
    coverage summed over the image is the still card's (within 1 %: the shutter's times, a
    fine pixel of motion apart, sample the edge's bins; measured 0.5 %)."""
    still = render_camera([_card()], CAMERA, via="incoherent")
    px = 1.0 / np.ptp(CAMERA.project(np.array([[0.5, 0, 0], [1.5, 0, 0]]))[0][:, 0])  # m/px
    start, end = _card(-4 * px), _card(4 * px)
    moving = Mesh(
        vertices=_card().vertices,
        triangles=_card().triangles,
        colours=_card().colours,
        motion=np.stack([start.vertices, end.vertices]),
    )
    blurred = render_camera([moving], CAMERA, via="incoherent")
    rows = slice(24, 40)
    edge = CAMERA.project(np.array([[0.5, 0, 0]]))[0][0, 0]
    cols = np.arange(int(edge) - 10, int(edge) + 10)
    profile = blurred.alpha[rows][:, cols].mean(0)
    width = _width(profile)
    centres = cols + 0.5
    ramp = np.clip((edge + 4 - centres) / 8, 0, 1)
    inner = (centres > edge - 3) & (centres < edge + 3)
    deviation = np.abs(profile - ramp)[inner].max()
    area = blurred.alpha.sum() / still.alpha.sum()
    print(
        f"moving 8 px: 10-90 % width {width:.2f} px, largest step off the ramp "
        f"{deviation:.3f}, coverage x {area:.4f}"
    )
    assert abs(width - 6.4) <= 0.5, width
    assert deviation <= 0.05, deviation
    assert abs(area - 1) <= 0.01, area


def test_a_card_whose_motion_stands_still_renders_as_the_still_card():
    """Motion steps that do not move: bit for bit the still card's image."""
    card = _card()
    standing = Mesh(
        vertices=card.vertices,
        triangles=card.triangles,
        colours=card.colours,
        motion=np.stack([card.vertices] * 3),
    )
    a = render_camera([card], CAMERA, via="incoherent")
    b = render_camera([standing], CAMERA, via="incoherent")
    assert np.array_equal(a.rgb, b.rgb) and np.array_equal(a.alpha, b.alpha)
