"""Image generation against geometric and wave optics (Sect. VII): pixel positions, Airy spot,
defocus blur, two-wavelength depth, anti-aliasing, speckle composition."""

import dataclasses
import math

import numpy as np
import pytest
from accuracy import (
    AIRY_RADIUS,
    ALIAS_ENERGY,
    DEFOCUS_DIAMETER,
    DEPTH_SINGLE_POINT,
    PIXEL_POSITION,
    SPECKLE_SQRT_N,
)

from holo_core.optics import speckle
from holo_core.optics.depth import partner_wavelength
from holo_core.optics.pupil import Pupil
from holo_core.plate.points import record_points
from holo_core.plate.record import record_hologram
from holo_core.plate.reference import Reference
from holo_core.plate.view import render_view
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.mesh import Mesh
from holo_core.scene.plate import Plate

LAM, PITCH, N = 633e-9, 1e-6, 512
EYE = np.array([0.0, 0.0, 4e-3])


def off_axis(lam2=LAM, pitch=PITCH):
    """The off-axis recording of holo_core.plate.sampling: cone b = λ/(8d), reference sin ϑ = 3b."""
    return dict(band=0.95 * lam2 / (8 * pitch),
                reference=Reference(angle=math.asin(3 * lam2 / (8 * pitch))))


def point_hologram(points, wavelengths=(LAM,), channels=(), n=N, seeds=(0,), pitch=PITCH):
    pts = np.asarray(points, np.float64)
    return [record_points(pts, np.ones((len(pts), len(wavelengths))), shape=(n, n),
                          pitch=pitch, wavelengths=wavelengths, channels=channels, seed=s,
                          **off_axis(min(wavelengths), pitch)) for s in seeds]


def camera(pixel_angle, size, **kw):
    """A camera at EYE looking at the plate centre with the given pixel angle [rad]."""
    kw.setdefault("matrix_world", look_at(EYE, (0, 0, 0), up=(0, 1, 0)))
    return Camera(lens=50, sensor_width=50 * size * pixel_angle, resolution=(size, size), **kw)


def radial_profile(img, centre, step):
    """Mean of ``img`` in rings of width ``step`` px around ``centre`` (col, row)."""
    yy, xx = np.mgrid[0:img.shape[0], 0:img.shape[1]] + 0.5
    ring = (np.hypot(xx - centre[0], yy - centre[1]) / step).astype(int)
    sums = np.bincount(ring.ravel(), img.ravel())
    counts = np.bincount(ring.ravel())
    return sums / np.maximum(counts, 1), counts


# --- camera model ------------------------------------------------------------------------------

def test_projection_follows_blenders_view_plane():
    """Blender's default camera (50 mm, 36 mm sensor, AUTO fit): a point at tangent
    (0.36, 0) lies on the right edge of a 1920-wide image; vertical fit, shift and pixel
    aspect move it as BKE_camera_params_compute_viewplane does."""
    cam = Camera(resolution=(1920, 1080))
    (col, row), = cam.project([[0.36, 0.0, -1.0]])[0]
    assert abs(col - 1920) < 1e-9 and abs(row - 540) < 1e-9
    (col, row), = cam.project([[0.0, 0.09, -1.0]])[0]  # 0.09·50/36·1920 = 240 px above centre
    assert abs(row - 300) < 1e-9
    tall = Camera(resolution=(1080, 1920), sensor_fit="VERTICAL", sensor_height=24.0)
    (col, row), = tall.project([[0.0, 0.24, -1.0]])[0]  # 0.24·50/24·1920 = 960 px: top edge
    assert abs(row) < 1e-9
    shifted = Camera(resolution=(1920, 1080), shift_x=0.1)  # 0.1 of the width: 192 px
    assert abs(shifted.project([[0, 0, -1.0]])[0][0, 0] - (960 - 192)) < 1e-9
    wide = Camera(resolution=(1000, 1000), pixel_aspect=(2.0, 1.0))  # pixels twice as wide
    (col, row), = wide.project([[0.0, 0.18, -1.0]])[0]  # 0.18·50/36·1000 = 250 → 500 rows
    assert abs(row - (500 - 500)) < 1e-9


def test_direction_cosines_invert_the_projection(rng):
    """Eq. 22: each pixel's (α, β, γ) points back along the ray to the point it shows."""
    cam = Camera(matrix_world=look_at((1, 2, 3), (0, 0, 0)), resolution=(64, 48), shift_y=0.05,
                 sensor_fit="VERTICAL")
    alpha, beta, gamma = cam.direction_cosines()
    ray = -np.stack([alpha, beta, gamma], -1) @ cam.rotation.T
    world = cam.position + 2.5 * ray.reshape(-1, 3)
    xy, _ = cam.project(world)
    rows, cols = np.mgrid[0:48, 0:64] + 0.5
    assert np.allclose(xy[:, 0], cols.ravel()) and np.allclose(xy[:, 1], rows.ravel())


# --- pinhole, lens ---------------------------------------------------------------------------

def test_point_through_pinhole_lands_on_its_pixel():
    """A point recorded, reconstructed and seen through an off-axis, rotated pinhole camera
    peaks within 0.5 px of the camera's projection (Eq. 22)."""
    p = np.array([[0.12e-3, -0.08e-3, -3e-3]])
    cam = Camera(matrix_world=look_at((0.4e-3, 0.2e-3, 4e-3), (0, 0, -3e-3), up=(0, 1, 0)),
                 lens=50, sensor_width=50 * 48 * 4e-3, resolution=(48, 40), shift_x=0.05)
    img = render_view(point_hologram(p), cam).rgb[..., 0]
    expected = cam.project(p)[0][0]
    i, j = np.unravel_index(np.argmax(img), img.shape)
    win = img[i - 2:i + 3, j - 2:j + 3]
    rows, cols = np.mgrid[i - 2:i + 3, j - 2:j + 3] + 0.5
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
    k = first - 1 + 0.5 * (prof[first - 1] - prof[first + 1]) / (
        prof[first - 1] - 2 * prof[first] + prof[first + 1])
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


# --- depth -------------------------------------------------------------------------------------

def depth_pair(half_range):
    lam2 = partner_wavelength(LAM, half_range)
    return (LAM, lam2), ("Y", "Z")


def test_two_wavelength_depth_of_a_point():
    """Eq. 26-30: the depth from the phase difference equals the true planar depth."""
    p = np.array([[0.05e-3, -0.03e-3, -3e-3]])
    lams, names = depth_pair(1e-3)
    cam = camera(2e-3, 48, matrix_world=look_at(EYE + [0.3e-3, 0, 0], (0, 0, -3e-3),
                                                 up=(0, 1, 0)))
    for focus in (None, 6.5e-3):
        kw = {} if focus is None else dict(fstop=50e-3 / 0.1e-3, focus_distance=focus)
        cam_k = dataclasses.replace(cam, **kw)
        r = render_view(point_hologram(p, lams, names), cam_k)
        i, j = np.unravel_index(np.argmax(r.rgb[..., 0]), r.alpha.shape)
        true = cam_k.project(p)[1][0]
        assert abs(r.depth[i, j] / true - 1) <= DEPTH_SINGLE_POINT, (focus, r.depth[i, j], true)


def test_interfering_points_get_a_depth_between_them():
    """Two points on one pixel's ray interfere; keeping the brightest of several random-phase
    iterations puts the depth between them (Fig. 11)."""
    p = np.array([[0.05e-3, -0.03e-3, -3e-3], [0.05e-3, -0.03e-3, -3.4e-3]])
    lams, names = depth_pair(1e-3)
    cam = camera(2e-3, 32, matrix_world=look_at(EYE, p[0], up=(0, 1, 0)))
    r = render_view(point_hologram(p, lams, names, seeds=range(6)), cam)
    i, j = np.unravel_index(np.argmax(r.rgb[..., 0]), r.alpha.shape)
    near, far = sorted(cam.project(p)[1])
    assert near - 1e-6 <= r.depth[i, j] <= far + 1e-6, (r.depth[i, j], near, far)


# --- anti-aliasing and speckle (a scene in metres, optics chosen automatically) -----------------

def checkerboard(squares=24):
    tex = (np.add.outer(np.arange(squares), np.arange(squares)) % 2).astype(float)
    tex = np.repeat(0.1 + 0.8 * tex[..., None], 3, -1)
    v = np.array([[-0.1, -0.1, -0.02], [0.1, -0.1, -0.02], [0.1, 0.1, -0.3], [-0.1, 0.1, -0.3]])
    return Mesh(vertices=v, triangles=np.array([[0, 1, 2], [0, 2, 3]]),
                uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]), texture=tex)


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
    texel = tex[np.clip(((1 - v) * n).astype(int), 0, n - 1), np.clip((u * n).astype(int), 0, n - 1)]
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


def test_temporal_composition_lowers_speckle_as_one_over_sqrt_n(rng):
    """N renders of a diffuse patch (dense points, independent random phases per render),
    averaged: the speckle contrast falls as 1/√N (Sect. VII-E). The lens (0.3 mm) resolves
    spots holding some 5 points each, so that the points' placement, the same in every
    render, adds little contrast of its own (measured 1/N^0.41 against 1/√N: 17 %)."""
    n_pts, half = 3000, 0.15e-3
    p = np.column_stack([rng.uniform(-half, half, (n_pts, 2)), np.full(n_pts, -3e-3)])
    holos = point_hologram(p, n=1024, seeds=range(8))
    f = float(np.linalg.norm(EYE - [0, 0, -3e-3]))
    cam = camera(5e-4, 100, fstop=50e-3 / 0.3e-3, focus_distance=f)
    corners = cam.project([[-half, -half, -3e-3], [half, half, -3e-3]])[0]
    (c0, r1), (c1, r0) = corners + [[4, -4], [-4, 4]]
    inner = np.zeros((100, 100), bool)
    inner[int(r0):int(r1), int(c0):int(c1)] = True
    one = np.mean([speckle.contrast(render_view(h, cam).rgb[..., 0], inner) for h in holos[:3]])
    eight = speckle.contrast(render_view(holos, cam).rgb[..., 0], inner)
    assert abs(one / eight / math.sqrt(8) - 1) <= SPECKLE_SQRT_N, (one, eight)
