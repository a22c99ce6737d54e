"""Camera holograms (holo_core/camera/) against geometric optics and a float64 spherical-wave
sum: where points land, the thin lens's circle of confusion, exposure across f-stops, the
object wave on the pupil, the intensity-hologram route, silhouettes and depth of meshes."""

import math

import numpy as np
import pytest
from huge import huge_mesh, never

from holo_core.camera.optics import choose_optics
from holo_core.camera.raster import depth_range, grid_indices, point_emitters, rasterize
from holo_core.camera.recording import (
    intensity_hologram,
    object_wave,
    random_phases,
    reconstruct_object_wave,
)
from holo_core.camera.render import render_camera
from holo_core.optics.raster import bin_rays
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.mesh import Mesh
from holo_core.validate import InputError

EYE = np.array([0.0, -3.5, 0.0])


def cam(resolution=(160, 120), **kw):
    return Camera(matrix_world=look_at(EYE, (0, 0, 0)), resolution=resolution, **kw)


def on_ray(camera, col, row, depth):
    """The world point at planar ``depth`` [m] on the ray of pixel position (col, row)."""
    tx, ty = camera.pixel_tangents(np.array([row]), np.array([col]))
    local = np.array([tx[0] * depth, ty[0] * depth, -depth])
    return camera.position + camera.rotation @ local


def plane(corners, colour=(0.5, 0.5, 0.5), texture=None):
    v = np.asarray(corners, float)
    return Mesh(
        vertices=v,
        triangles=np.array([[0, 1, 2], [0, 2, 3]]),
        colours=None if texture is not None else np.tile(colour, (4, 1)),
        uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]) if texture is not None else None,
        texture=texture,
    )


def uv_sphere(centre, radius, n=72):
    """A UV sphere of 2·n·(n-1) triangles."""
    th, ph = np.meshgrid(
        np.linspace(0, np.pi, n), np.linspace(0, 2 * np.pi, 2 * n + 1)[:-1], indexing="ij"
    )
    v = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)
    idx = np.arange(v.shape[0] * v.shape[1]).reshape(v.shape[:2])
    a, b = idx[:-1], np.roll(idx, -1, 1)[:-1]
    c, d = idx[1:], np.roll(idx, -1, 1)[1:]
    tri = np.concatenate(
        [np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)]
    )
    return Mesh(
        vertices=v.reshape(-1, 3) * radius + centre,
        triangles=tri,
        colours=np.full((v.shape[0] * v.shape[1], 3), 0.6),
    )


def centroid(img, col, row, r=4):
    """Intensity-weighted centre (col, row) [px from the top-left corner] near (col, row)."""
    c0, r0 = int(col), int(row)
    win = img[r0 - r : r0 + r + 1, c0 - r : c0 + r + 1]
    yy, xx = np.mgrid[r0 - r : r0 + r + 1, c0 - r : c0 + r + 1] + 0.5
    return (win * xx).sum() / win.sum(), (win * yy).sum() / win.sum()


def test_points_land_on_blenders_projection_at_1920x1080():
    """Points across a 1920×1080 frame, corners included, image where Camera.project (Blender's
    world_to_camera_view) puts them, within 0.5 px."""
    camera = cam((1920, 1080))
    where = [(960.3, 540.2), (100.7, 80.1), (1820.2, 1000.6), (1500.5, 200.4), (300.1, 900.9)]
    pts = np.array([on_ray(camera, c, r, 3.5) for c, r in where])
    r = render_camera(camera=camera, points=(pts, np.ones((len(pts), 3))), samples=4)
    lum = r.radiance.mean(-1)
    proj, _ = camera.project(pts)
    err = [math.dist(centroid(lum, *p), p) for p in proj]
    print(f"points vs projection: {np.round(err, 3)} px")
    assert max(err) <= 0.5, err


@pytest.mark.parametrize("fstop", [2.8, 16.0])
def test_defocused_point_is_the_thin_lens_circle_of_confusion(fstop):
    """A point off the focal plane images as a disc of the thin lens's diameter
    D·|1/z − 1/f| / (pixel angle) (Cycles' depth of field), within 10 %. The disc's edge is
    where its intensity falls to a quarter of the plateau: a straight edge's value at the
    geometric shadow in Fresnel diffraction (the half-maximum lies inside it, by about a
    Fresnel zone: 9 % here)."""
    focus = 2.0
    blur_px = 24.0
    camera = cam((160, 120), fstop=fstop, focus_distance=focus)
    diameter = camera.aperture_diameter
    z = 1 / (1 / focus + blur_px * camera.pixel_angle() / diameter)
    p = on_ray(camera, 80.0, 60.0, z)
    r = render_camera(camera=camera, points=(p[None], np.ones((1, 3))), samples=1, supersample=2)
    lum = r.radiance.mean(-1)
    plateau = np.median(lum[lum > 0.2 * lum.max()])
    measured = 2 * math.sqrt((lum > plateau / 4).sum() / math.pi)
    print(f"f/{fstop}: disc {measured:.2f} px, thin lens {blur_px} px")
    assert abs(measured / blur_px - 1) <= 0.10, (measured, blur_px)


def test_brightness_is_the_same_at_every_fstop():
    """A grey plane (linear 0.5, as an emission shader in Cycles) shows 0.5 at f/1.4, f/2.8,
    f/16 and without depth of field, within 10 %, and never NaN."""
    wall = plane([[-1, 0, -0.8], [1, 0, -0.8], [1, 0, 0.8], [-1, 0, 0.8]])
    means = {}
    for fstop in (1.4, 2.8, 16.0, None):
        camera = cam((64, 48), fstop=fstop, focus_distance=3.5 if fstop else None)
        r = render_camera(wall, camera, samples=4)
        assert np.isfinite(r.rgb).all() and np.isfinite(r.depth).all()
        means[fstop] = float(r.rgb[16:32, 20:44].mean())
    print(f"grey 0.5 by f-stop: {means}")
    assert all(abs(m / 0.5 - 1) <= 0.10 for m in means.values()), means


def test_object_wave_on_the_pupil_equals_the_spherical_waves():
    """The camera hologram of points near the axis against their float64 spherical waves
    on the pupil's samples, e^{ik|X−P|}·R/|X−P| (amplitude 1 at the pupil's centre): within
    the layers' curvature approximation, 1e-3 over the iris (measured 2.5e-4)."""
    camera = cam((64, 48), fstop=2.8, focus_distance=3.5)
    optics = choose_optics(camera, (3.0, 4.0))
    rng = np.random.default_rng(3)
    kx, ky = rng.integers(-4, 5, 6), rng.integers(-4, 5, 6)
    depth = rng.choice(optics.layers, 6)
    tx, ty = bin_rays(kx, ky, optics.bin)
    local = np.stack([tx * depth, ty * depth, -depth], -1)
    pts = camera.position + local @ camera.rotation.T
    em = point_emitters(pts, np.ones((6, 3)), camera, optics)
    o = object_wave(em, optics, camera, field=0, seed=5)
    h, w = optics.shape
    dy, dx = optics.pitch()
    y, x = np.meshgrid((np.arange(h) - h // 2) * dy, (np.arange(w) - w // 2) * dx, indexing="ij")
    k = 2 * np.pi / optics.wavelength
    phases = random_phases(len(em.index), 5)
    ref = np.zeros((h, w), complex)
    ey, ex = grid_indices(em.index, optics.shape)
    etx, ety = bin_rays(ex, ey, optics.bin)
    for j in range(len(em.index)):  # each emitter is one point: on its bin's ray, at its depth
        p = np.array([etx[j], ety[j], -1.0]) * em.depth[j]
        r = np.sqrt((x - p[0]) ** 2 + (y - p[1]) ** 2 + p[2] ** 2)
        ref += np.exp(1j * (k * r + phases[j])) * np.linalg.norm(p) / r
    iris = np.hypot(x, y) < optics.diameter / 2
    err = np.linalg.norm((o - ref)[iris]) / np.linalg.norm(ref[iris])
    print(f"pupil object wave vs spherical waves: {err:.2e}")
    assert err < 1e-3, err


@pytest.mark.parametrize("fstop", [None, 2.8])
def test_incoherent_route_is_one_look_of_a_single_emitter(fstop):
    """One emitter has no cross terms: its image through the intensity PSF (the incoherent
    route) is exactly one look's |A|², read by another non-uniform FFT (the intensity's
    spectrum padded 1.5x, against the coherent spectrum's 2x)."""
    camera = cam((96, 72), fstop=fstop, focus_distance=1.5 if fstop else None)  # 1.3 px blur
    p = on_ray(camera, 30.3, 21.7, 3.4)
    pts = (p[None], np.array([[0.9, 0.5, 0.2]]))
    a = render_camera(camera=camera, points=pts, via="incoherent")
    b = render_camera(camera=camera, points=pts, samples=1)
    err = np.abs(a.radiance - b.radiance).max() / b.radiance.max()
    cover = np.abs(a.coverage - b.coverage).max() / b.coverage.max()
    print(f"f/{fstop}: radiance {err:.2e}, coverage {cover:.2e} of the peak apart")
    assert err < 1e-3, err
    assert cover < 1e-3, cover


def test_looks_converge_on_the_incoherent_route():
    """Many emitters: the looks' mean approaches the incoherent route as 1/√N (its error
    halves from 4 to 16 looks) and is within 28 dB PSNR of it inside a textured wall."""
    camera = cam((64, 48), fstop=2.8, focus_distance=3.5)
    wall = plane(
        [[-0.5, 0, -0.4], [0.5, 0, -0.4], [0.5, 0.3, 0.4], [-0.5, 0.3, 0.4]],
        texture=np.random.default_rng(1).uniform(0.2, 1, (6, 6, 3)),
    )
    exact = render_camera(wall, camera, via="incoherent")
    looks = {}
    render_camera(wall, camera, samples=64, on_sample=lambda r, n: looks.__setitem__(n, r.radiance))
    inside = exact.alpha >= 1
    rms = {n: np.sqrt(np.mean((looks[n] - exact.radiance)[inside] ** 2)) for n in (4, 16, 64)}
    psnr = 20 * np.log10(exact.radiance[inside].max() / rms[64])
    print(f"rms against the incoherent route: {rms}; 64 looks at {psnr:.1f} dB")
    assert rms[4] / rms[16] > 1.5, rms
    assert psnr >= 28, psnr
    assert exact.info["speckle_contrast"] == 0.0


def test_intensity_hologram_route_gives_the_object_wave_back():
    """H = |O + R|² recorded off axis, then R'·H with DC suppression and the band filter:
    the object wave again (float32 intensities), and the same render either way."""
    camera = cam((48, 36), fstop=4.0, focus_distance=3.5)
    wall = plane(
        [[-0.5, 0, -0.4], [0.5, 0, -0.4], [0.5, 0.3, 0.4], [-0.5, 0.3, 0.4]],
        texture=np.random.default_rng(1).uniform(0.2, 1, (6, 6, 3)),
    )
    optics = choose_optics(camera, depth_range([wall], camera))
    o = object_wave(rasterize([wall], camera, optics), optics, camera, seed=2)
    back = reconstruct_object_wave(intensity_hologram(o))
    assert np.linalg.norm(back - o) / np.linalg.norm(o) < 1e-4
    a = render_camera(wall, camera, samples=2)
    b = render_camera(wall, camera, samples=2, via="hologram")
    assert np.abs(a.rgb - b.rgb).max() < 1e-3 * a.rgb.max()


def test_sphere_silhouette_and_depth_of_ten_thousand_triangles():
    """A 10,000-triangle sphere: its silhouette against the analytic one (IoU >= 0.97) and
    its planar depth against the ray–sphere intersection (median error <= 0.5 % of its depth
    extent)."""
    centre, radius = np.array([0.1, 0.0, 0.05]), 0.5
    mesh = uv_sphere(centre, radius, n=72)
    assert len(mesh.triangles) >= 10_000
    camera = cam((160, 120), fstop=2.8, focus_distance=3.5)
    r = render_camera(mesh, camera, samples=4)
    tx, ty = camera.pixel_tangents()
    d = np.stack([tx, ty, -np.ones_like(tx)], -1) @ camera.rotation.T
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    oc = camera.position - centre
    b = (d * oc).sum(-1)
    disc = b * b - (oc @ oc - radius**2)
    hit = disc > 0
    t = -b - np.sqrt(np.where(hit, disc, 0))
    planar = t / np.sqrt(1 + tx * tx + ty * ty)
    inside = r.alpha > 0.5
    iou = (inside & hit).sum() / (inside | hit).sum()
    both = inside & hit & (np.abs(planar - np.median(planar[hit])) < 2 * radius)
    err = np.median(np.abs(r.depth[both] - planar[both])) / (2 * radius)
    print(f"sphere: IoU {iou:.3f}, median depth error {err:.2%} of its extent")
    assert iou >= 0.97 and err <= 5e-3, (iou, err)


def test_camera_hologram_equals_the_plate_hologram_carried_to_the_pupil():
    """Points 0.5 m behind a plate, recorded on the plate (direct sum of Eq. 3) and carried by
    the angular spectrum to a camera 1 cm in front of it, against the camera hologram of the
    same points on that camera's pupil: 2 % over the iris (measured 1.3e-2, which is the plate
    route's own error from its finite plate and band: it is 1.3e-2 from the float64 spherical
    waves, where the camera hologram is 4e-4)."""
    from holo_core.plate.point_sources import point_wave
    from holo_core.propagation import angular_spectrum

    d_c = 0.01
    pose = np.eye(4)
    pose[2, 3] = d_c  # the plate is z = 0 of the world; the camera looks down −z at it
    camera = Camera(matrix_world=pose, resolution=(48, 48), fstop=8.0, focus_distance=0.5)
    optics = choose_optics(camera, (0.5, 0.5))
    kx, ky = np.array([0, 2, -3, 1, -1]), np.array([0, -2, 1, 3, -3])
    tx, ty = bin_rays(kx, ky, optics.bin)
    depth = optics.layers[0]
    pts = np.stack([tx * depth, ty * depth, np.full(5, d_c - depth)], -1)
    em = point_emitters(pts, np.ones((5, 3)), camera, optics)
    o = object_wave(em, optics, camera, seed=5)
    ey, ex = grid_indices(em.index, optics.shape)
    etx, ety = bin_rays(ex, ey, optics.bin)
    emitters = np.stack([etx * em.depth, ety * em.depth, d_c - em.depth], -1)
    amps = em.distance * np.exp(1j * random_phases(len(em.index), 5))  # amplitude 1 at the pupil
    lam, (dy, dx), (h, w) = optics.wavelength, optics.pitch(), optics.shape
    pitch = dx / 3  # every third plate sample lies on a pupil sample
    n = 2 * math.ceil(5 * optics.diameter / pitch / 2) + 1
    plate = point_wave(
        emitters, amps, wavelength=lam, pitch=pitch, shape=(n, n), method="direct", band=0.5
    )
    carried = angular_spectrum(plate, wavelength=lam, pitch=pitch, distance=d_c)
    c = (n - 1) // 2
    at = carried[c + 3 * (np.arange(h) - h // 2)][:, c + 3 * (np.arange(w) - w // 2)]
    y, x = np.meshgrid((np.arange(h) - h // 2) * dy, (np.arange(w) - w // 2) * dx, indexing="ij")
    iris = np.hypot(x, y) < optics.diameter / 2
    err = np.linalg.norm((at - o)[iris]) / np.linalg.norm(o[iris])
    print(f"camera hologram vs plate hologram carried to the pupil: {err:.2e}")
    assert err < 2e-2, err


def test_a_ten_million_vertex_mesh_is_refused_by_render_camera(monkeypatch):
    """The camera hologram counts its raster's memory before rasterizing: about 1000 bytes
    per triangle (measured 920 at 10^6), 18.6 GiB for 2·10^7 triangles, refused against an
    8 GiB budget with both sizes named."""
    import holo_core.camera.raster as raster

    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "8G")
    monkeypatch.setattr(raster, "across_shutter", never)
    cam = Camera(matrix_world=look_at((0, 0, 0.5), (0, 0, -1)), resolution=(64, 64))
    with pytest.raises(
        InputError,
        match=r"rasterizing 20000000 triangles needs 1\d\.\d GiB of "
        r"memory; 6.4 GiB is available",
    ):
        render_camera(huge_mesh(10**7), cam, via="incoherent", supersample=1)
