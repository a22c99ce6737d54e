"""A pinhole camera's view of a carrier plate (holo_core.plate.window.pinhole_view_pupil): the
smallest pupil that makes the view sharp, λ/D a fine pixel (half a pixel), so its pupil grid
holds about as many samples as the view has fine pixels, and a point's image is about a pixel
wide. A flat object (no depth range, so defocus allows any pupil) is the case that asked a
pupil of 2e6 m and a spectrum of 1e20 samples before.

The scene: a pinhole camera of 50 mm (36 mm sensor) at 320 x 180 px, 1 m in front of a 20 cm
plate, its viewing zone 5 cm around the camera; a 10 cm card 1.5 m behind the plate, parallel
to it, sets the plate's plan, and one emitter on the card's plane is the point seen."""

import numpy as np
import pytest

from holo_core.plate.emitters import Emitters, grid_points
from holo_core.plate.recording import plate_plan, prepare_plate
from holo_core.plate.view import render_view
from holo_core.plate.window import camera_in_plate, nyquist_supersample, pinhole_view_pupil
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.mesh import Mesh
from holo_core.scene.plate import Plate

W, H = 320, 180
CAMERA = Camera(
    matrix_world=look_at((0, 0, 1.0), (0, 0, -1.5), up=(0, 1, 0)), resolution=(W, H), lens=50
)
PLATE = Plate(matrix_world=np.eye(4), width=0.2, height=0.2)
CARD = Mesh(
    vertices=np.array(
        [[-0.05, -0.05, -1.5], [0.05, -0.05, -1.5], [0.05, 0.05, -1.5], [-0.05, 0.05, -1.5]]
    ),
    triangles=np.array([[0, 1, 2], [0, 2, 3]]),
    colours=np.ones((4, 3)),
)
POINT = (0.004, -0.003, -1.5)  # [m] off the axis and off a pixel's centre


@pytest.fixture(scope="module")
def point_plate():
    """The plate of one emitter at POINT seen from the whole zone, planned for the card."""
    planned = plate_plan([CARD], plate=PLATE, camera=CAMERA, looks=1)
    g = grid_points(planned.plan.zone)
    hx, hy = planned.plan.zone.half_extents[:2]
    em = Emitters(
        position=np.array([POINT]),
        colour=np.ones((1, 3)),
        cell=np.zeros((1, 2), int),
        visibility=np.ones((1, *g), np.float32),
        grid=((-hx, 2 * hx / (g[1] - 1)), (-hy, 2 * hy / (g[0] - 1))),
    )
    (h,) = prepare_plate(planned, codes=(None,), emitters=em).record()
    return h


def test_a_pinholes_pupil_resolves_a_fine_pixel_and_no_more(point_plate):
    """D = s·λ/Δ (s = 2 fine pixels a pixel): λ/D is half a pixel, and the pupil lies within
    the zone. Before, defocus over the card's zero depth range allowed any pupil, and the
    zone's cut kept 1e-3 of it: 2.25e6 m."""
    h, cam = point_plate, CAMERA
    pupil = pinhole_view_pupil(h, cam, *camera_in_plate(h, cam))
    lam = h.wavelengths[0]
    spot = lam / pupil.diameter / cam.pixel_angle()
    assert abs(spot - 0.5) < 1e-9, (pupil.diameter, spot)
    assert pupil.diameter <= 2 * h.zone.half_extents[0], pupil.diameter
    assert abs(pupil.focus - 2.5) < 1e-9, pupil.focus  # the card's depth from the camera
    # |A|² at the Nyquist rate: fine pixels of λ/(2D) = a quarter pixel
    assert nyquist_supersample(h, cam) == 4


def test_a_pinhole_view_is_sharp_on_a_grid_of_about_its_fine_pixels(point_plate):
    """At Supersample 2 the pupil's spectrum holds at most 2x the 640 x 360 fine pixels
    (bins of a fine pixel over the directions the plate's window sends, its edge bins
    included; before: 1e20 asked), and the point's image peaks on its projected pixel with a
    full width at half maximum of 1-2 px along both axes (the pupil's resolution λ/D = 0.5 px,
    its cosine window and the pixels' own width)."""
    view = render_view(point_plate, CAMERA, supersample=2)
    samples = int(np.prod(view.info["pupil_samples"]))
    assert samples <= 2 * (2 * W) * (2 * H), view.info["pupil_samples"]
    img = view.rgb.mean(-1)
    i, j = np.unravel_index(np.argmax(img), img.shape)
    ((col, row),) = CAMERA.project([POINT])[0]
    assert abs(j + 0.5 - col) <= 1 and abs(i + 0.5 - row) <= 1, ((j, i), (col, row))

    def fwhm(profile, k):
        half = profile[k] / 2
        left = k - next(n for n in range(1, k) if profile[k - n] < half)
        right = k + next(n for n in range(1, len(profile) - k) if profile[k + n] < half)
        lo = left + (half - profile[left]) / (profile[left + 1] - profile[left])
        hi = right - (half - profile[right]) / (profile[right - 1] - profile[right])
        return hi - lo

    widths = fwhm(img[i], j), fwhm(img[:, j], i)
    assert all(1.0 <= w <= 2.0 for w in widths), widths


@pytest.mark.parametrize("phases", ["smooth", "random"])
def test_smooth_phases_send_every_emitter_in_phase(phases):
    """phases='smooth': each emitter's amplitude the sum takes is √I·|p − Z|, its phase
    −k·|p − Z| at its channel's wavelength (its light reaches the zone's centre Z in phase:
    its colours' and its depth's alike, within 1e-6 rad); 'random': the same moduli with
    phases spread over the circle (three emitters: not all within 0.1 rad of that)."""
    planned = plate_plan([CARD], plate=PLATE, camera=CAMERA, looks=1)
    g = grid_points(planned.plan.zone)
    hx, hy = planned.plan.zone.half_extents[:2]
    pos = np.array([POINT, (0.01, 0.02, -1.5), (-0.03, 0.0, -1.5)])
    colour = np.array([[1.0, 0.25, 0.0], [0.5, 0.5, 0.5], [0.0, 1.0, 0.04]])
    em = Emitters(
        position=pos,
        colour=colour,
        cell=np.zeros((3, 2), int),
        visibility=np.ones((3, *g), np.float32),
        grid=((-hx, 2 * hx / (g[1] - 1)), (-hy, 2 * hy / (g[0] - 1))),
    )
    job = prepare_plate(planned, codes=(None,), emitters=em, phases=phases)
    reach = np.linalg.norm(pos - np.asarray(planned.plan.zone.centre), axis=1)
    (_, colours), (_, depth) = job.groups
    want = np.sqrt(colour) * reach[:, None]
    assert np.allclose(np.abs(colours.amplitude), want, rtol=1e-12)
    arrive = [
        colours.amplitude * np.exp(2j * np.pi / lam * reach)[:, None]
        for (lam, colours) in job.groups
    ]
    angles = np.angle(np.concatenate([arrive[0][colour > 0], arrive[1][:, 0]]))
    if phases == "smooth":
        assert np.abs(angles).max() <= 1e-6, angles
    else:
        assert np.abs(angles).max() > 0.1, angles
