"""A view's images formed at the camera's pupil (holo_core.plate.pupil_images) against geometric
and wave optics (Sect. VII): the camera's projection and direction cosines as Blender's, a point
seen through a pinhole on its pixel, the Airy disc in focus, the geometric blur out of focus,
and a lower resolution served by the wavelength (no aliasing)."""

import numpy as np
import pytest
from accuracy import (
    AIRY_RADIUS,
    ALIAS_ENERGY,
    DEFOCUS_DIAMETER,
    PIXEL_POSITION,
)
from point_views import EYE, LAM, camera, point_hologram

from holo_core.optics.pupil import Pupil
from holo_core.plate.points import record_points
from holo_core.plate.record import record_hologram
from holo_core.plate.view import render_view
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.mesh import Mesh
from holo_core.scene.plate import Plate


def radial_profile(img, centre, step):
    """Mean of ``img`` in rings of width ``step`` px around ``centre`` (col, row)."""
    yy, xx = np.mgrid[0 : img.shape[0], 0 : img.shape[1]] + 0.5
    ring = (np.hypot(xx - centre[0], yy - centre[1]) / step).astype(int)
    sums = np.bincount(ring.ravel(), img.ravel())
    counts = np.bincount(ring.ravel())
    return sums / np.maximum(counts, 1), counts


def test_projection_follows_blenders_view_plane():
    """Blender's default camera (50 mm, 36 mm sensor, AUTO fit): a point at tangent
    (0.36, 0) lies on the right edge of a 1920-wide image; vertical fit, shift and pixel
    aspect move it as BKE_camera_params_compute_viewplane does."""
    cam = Camera(resolution=(1920, 1080))
    ((col, row),) = cam.project([[0.36, 0.0, -1.0]])[0]
    assert abs(col - 1920) < 1e-9 and abs(row - 540) < 1e-9
    ((col, row),) = cam.project([[0.0, 0.09, -1.0]])[0]  # 0.09·50/36·1920 = 240 px above centre
    assert abs(row - 300) < 1e-9
    tall = Camera(resolution=(1080, 1920), sensor_fit="VERTICAL", sensor_height=24.0)
    ((col, row),) = tall.project([[0.0, 0.24, -1.0]])[0]  # 0.24·50/24·1920 = 960 px: top edge
    assert abs(row) < 1e-9
    shifted = Camera(resolution=(1920, 1080), shift_x=0.1)  # 0.1 of the width: 192 px
    assert abs(shifted.project([[0, 0, -1.0]])[0][0, 0] - (960 - 192)) < 1e-9
    wide = Camera(resolution=(1000, 1000), pixel_aspect=(2.0, 1.0))  # pixels twice as wide
    ((col, row),) = wide.project([[0.0, 0.18, -1.0]])[0]  # 0.18·50/36·1000 = 250 → 500 rows
    assert abs(row - (500 - 500)) < 1e-9


def test_direction_cosines_invert_the_projection(rng):
    """Eq. 22: each pixel's (α, β, γ) points back along the ray to the point it shows."""
    cam = Camera(
        matrix_world=look_at((1, 2, 3), (0, 0, 0)),
        resolution=(64, 48),
        shift_y=0.05,
        sensor_fit="VERTICAL",
    )
    alpha, beta, gamma = cam.direction_cosines()
    ray = -np.stack([alpha, beta, gamma], -1) @ cam.rotation.T
    world = cam.position + 2.5 * ray.reshape(-1, 3)
    xy, _ = cam.project(world)
    rows, cols = np.mgrid[0:48, 0:64] + 0.5
    assert np.allclose(xy[:, 0], cols.ravel()) and np.allclose(xy[:, 1], rows.ravel())


def test_point_through_pinhole_lands_on_its_pixel():
    """A point recorded, reconstructed and seen through an off-axis, rotated pinhole camera
    peaks within 0.5 px of the camera's projection (Eq. 22)."""
    p = np.array([[0.12e-3, -0.08e-3, -3e-3]])
    cam = Camera(
        matrix_world=look_at((0.4e-3, 0.2e-3, 4e-3), (0, 0, -3e-3), up=(0, 1, 0)),
        lens=50,
        sensor_width=50 * 48 * 4e-3,
        resolution=(48, 40),
        shift_x=0.05,
    )
    img = render_view(point_hologram(p), cam).rgb[..., 0]
    expected = cam.project(p)[0][0]
    i, j = np.unravel_index(np.argmax(img), img.shape)
    win = img[i - 2 : i + 3, j - 2 : j + 3]
    rows, cols = np.mgrid[i - 2 : i + 3, j - 2 : j + 3] + 0.5
    got = np.array([(win * cols).sum(), (win * rows).sum()]) / win.sum()
    assert np.abs(got - expected).max() <= PIXEL_POSITION, (got, expected)


@pytest.fixture(scope="module")
def two_depths():
    """Two points at different depths; a lens of D = 0.6 mm (Fresnel number of the defocus
    ~9, so the blur is geometric), inside the flat part of both points' cones (b = 0.15)."""
    p = np.array([[0.02e-3, -0.01e-3, -3e-3], [-0.02e-3, 0.03e-3, -0.8e-3]])
    return p, point_hologram(p, n=1536, pitch=0.5e-6), 0.6e-3


def test_focused_point_is_an_airy_disc(two_depths):
    """In focus, a hard-edged lens of diameter D images a point to the Airy pattern: first
    zero at 1.22 λ/D (Sect. VII-A, Eq. 24)."""
    p, h, d = two_depths
    pixel = 1e-4
    f = float(np.linalg.norm(p[0] - EYE))
    cam = camera(pixel, 160, fstop=50e-3 / d, focus_distance=f)
    img = render_view(h, cam, apodize=False).rgb[..., 0]
    prof, counts = radial_profile(img, cam.project(p[:1])[0][0], 0.5)
    dark = np.argmax(prof < 0.1 * prof.max())
    first = dark + np.argmax(np.diff(prof[dark:80]) > 0)  # the first rise: past the first zero
    k = (
        first
        - 1
        + 0.5
        * (prof[first - 1] - prof[first + 1])
        / (prof[first - 1] - 2 * prof[first] + prof[first + 1])
    )
    radius = (k + 0.5) * 0.5 * pixel
    airy = 1.22 * LAM / d
    assert abs(radius / airy - 1) <= AIRY_RADIUS, (radius, airy)


def test_defocused_point_blurs_to_the_geometric_disc(two_depths):
    """Focused on the far point, the near one blurs to a disc of angular diameter
    D·|1/r − 1/f| (thin lens, Eq. 23-24). Its edge is where the intensity falls to a quarter
    of the plateau: at a geometric shadow's edge the field is half the free field (Fresnel)."""
    p, h, d = two_depths
    f, r = (float(np.linalg.norm(q - EYE)) for q in p)
    pixel = 5e-4
    cam = camera(pixel, 160, fstop=50e-3 / d, focus_distance=f)
    img = render_view(h, cam, apodize=False).rgb[..., 0]
    prof, _ = radial_profile(img, cam.project(p[1:])[0][0], 0.5)
    plateau = np.median(prof[:20])
    edge = np.argmax(prof < plateau / 4)
    diameter = 2 * edge * 0.5 * pixel
    expected = d * abs(1 / r - 1 / f)
    assert abs(diameter / expected - 1) <= DEFOCUS_DIAMETER, (diameter, expected)


def checkerboard(squares=24):
    tex = (np.add.outer(np.arange(squares), np.arange(squares)) % 2).astype(float)
    tex = np.repeat(0.1 + 0.8 * tex[..., None], 3, -1)
    v = np.array([[-0.1, -0.1, -0.02], [0.1, -0.1, -0.02], [0.1, 0.1, -0.3], [-0.1, 0.1, -0.3]])
    return Mesh(
        vertices=v,
        triangles=np.array([[0, 1, 2], [0, 2, 3]]),
        uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]),
        texture=tex,
    )


def raster(mesh, cam):
    """Point-sampled rasterization of the (planar) checkerboard: each pixel centre's ray hits
    the plane and reads the nearest texel."""
    a, b, c = mesh.vertices[:3]
    normal = np.cross(b - a, c - a)
    alpha, beta, gamma = cam.direction_cosines()
    ray = -np.stack([alpha, beta, gamma], -1) @ cam.rotation.T
    t = ((a - cam.position) @ normal) / (ray @ normal)
    hit = cam.position + t[..., None] * ray
    u = (hit - a) @ (b - a) / np.dot(b - a, b - a)
    v = (hit - a) @ (mesh.vertices[3] - a) / np.dot(mesh.vertices[3] - a, mesh.vertices[3] - a)
    inside = (u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)
    tex = mesh.texture[..., 0]
    n = tex.shape[0]
    texel = tex[
        np.clip(((1 - v) * n).astype(int), 0, n - 1), np.clip((u * n).astype(int), 0, n - 1)
    ]
    return np.where(inside, texel, 0.0)


def high_energy(img, factor):
    """Fraction of the (Hann-windowed, mean-free) image's spectral energy above 1/factor of
    its Nyquist frequency in either axis."""
    h, w = img.shape
    win = np.outer(np.hanning(h), np.hanning(w))
    s = np.abs(np.fft.fft2((img - img.mean()) * win)) ** 2
    fy, fx = np.abs(np.fft.fftfreq(h))[:, None], np.abs(np.fft.fftfreq(w))[None, :]
    above = (fy > 0.5 / factor) | (fx > 0.5 / factor)
    return float(s[above].sum() / s.sum())


def test_lower_resolution_is_served_by_the_wavelength():
    """A tilted checkerboard recorded for a 40-pixel view, then rendered 4× magnified: the
    wave image holds (almost) nothing above the 40-pixel Nyquist frequency, where a
    point-sampled rasterization holds a lot (Sect. VII-D)."""
    board = checkerboard()
    plate = Plate(matrix_world=np.eye(4), width=0.3, height=0.3)
    pose = look_at((0.02, -0.05, 0.7), (0, 0, -0.15), up=(0, 1, 0))
    low = Camera(matrix_world=pose, lens=50, resolution=(40, 40), sensor_width=20)
    h = record_hologram(board, plate=plate, camera=low, max_resolution=512, depth=False)
    fine = Camera(matrix_world=pose, lens=50, resolution=(160, 160), sensor_width=20)
    lam = h.wavelengths[0]
    pinhole = Pupil(diameter=lam / (2 * low.pixel_angle()))
    wave = render_view(h, fine, aperture=pinhole).rgb.mean(-1)
    ratio = high_energy(wave, 4) / high_energy(raster(board, fine), 4)
    assert ratio <= ALIAS_ENERGY, ratio


@pytest.fixture(scope="module")
def small_plate():
    """A point 3 cm behind a 0.5 mm plate of 64² at 8 µm, seen from 2 cm: the plate's light
    reaches 2.2 mm across on the pupil's plane."""
    return record_points(
        [[0, 0, -0.03]], [[1.0]], shape=(64, 64), pitch=8e-6, wavelengths=(633e-9,)
    )


def _pupil_view(h, diameter, monkeypatch, *, crop=True):
    """(rgb at exposure 1, the pupil grid's samples per side) of a pinhole-less view through
    a pupil of ``diameter`` [m]."""
    from holo_core.plate import pupil_images

    grids = []
    real = pupil_images.pupil_grid
    monkeypatch.setattr(pupil_images, "pupil_grid", lambda *a: grids.append(real(*a)) or grids[-1])
    if not crop:
        monkeypatch.setattr(pupil_images, "lit_diameter", lambda h, p, r, d: d)
    cam = Camera(
        matrix_world=look_at((0, 0, 0.02), (0, 0, -0.03)),
        lens=50,
        sensor_width=2,
        resolution=(16, 16),
    )
    with pytest.warns(UserWarning, match="no depth channel"):
        rgb = render_view(
            h, cam, aperture=Pupil(diameter=diameter), supersample=1, exposure=1.0
        ).rgb
    monkeypatch.undo()
    return rgb, grids[-1][0]


def test_a_pupil_larger_than_the_plates_light_is_read_where_light_arrives(small_plate, monkeypatch):
    """A 4 mm pupil before the plate's 2.2 mm of light: its grid cut to the light (675
    samples a side instead of 1215) gives the same view (measured 1.8e-3 of the peak: the
    spectrum read on another bin spacing)."""
    cut, n_cut = _pupil_view(small_plate, 4e-3, monkeypatch)
    whole, n_whole = _pupil_view(small_plate, 4e-3, monkeypatch, crop=False)
    assert n_cut < 0.6 * n_whole, (n_cut, n_whole)
    err = np.abs(cut - whole).max() / whole.max()
    assert err <= 5e-3, err


def test_a_10_m_aperture_reads_only_the_light_and_dims_by_its_area(small_plate, monkeypatch):
    """A 10 m aperture's pupil grid and window span the plate's light, not the 10 m (the same
    675 samples as a 4 mm pupil), and its view is the 4 mm one dimmed by the ratio of the
    irises' areas, (4 mm / 10 m)², the light the larger lens spreads over its whole iris."""
    small, n_small = _pupil_view(small_plate, 4e-3, monkeypatch)
    large, n_large = _pupil_view(small_plate, 10.0, monkeypatch)
    assert n_large == n_small, (n_large, n_small)
    err = np.abs(large * (10.0 / 4e-3) ** 2 - small).max() / small.max()
    assert err <= 1e-4, err
