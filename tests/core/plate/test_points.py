"""The point-sum recorder (holo_core.plate.points: point sources, textured triangles, the
reference wave) and the reconstruction, against analytic waves and float64 NumPy (Sect. V-VI)."""

import math

import numpy as np
import pytest
from accuracy import POINT_SUM, PRIMITIVE_VS_POINTS, WRP_VS_DIRECT, rel_err

from holo_core.io.hologram import read_hologram, write_hologram
from holo_core.plate.point_sources import Grid, cone_weight, point_wave
from holo_core.plate.points import record_points
from holo_core.plate.reconstruction import reconstruct
from holo_core.plate.record import record_hologram
from holo_core.plate.reference import Reference, reference_wave
from holo_core.plate.sampling import choose
from holo_core.plate.triangles import Primitive, primitive_wave, surface_field, surface_pitch
from holo_core.propagation import angular_spectrum, grid
from holo_core.scene.mesh import Mesh, sample_points
from holo_core.scene.plate import Plate
from holo_core.validate import InputError, SamplingWarning

LAM, PITCH = 633e-9, 8e-6


def numpy_point_wave(pos, amp, shape, obliquity=False, lam=LAM, pitch=PITCH):
    """Eq. 3 summed in float64, each point weighted by its sampling cone."""
    g = Grid(shape, pitch, lam)
    y, x = grid.coords(shape[0], pitch)[:, None], grid.coords(shape[1], pitch)[None, :]
    out = np.zeros(shape, np.complex128)
    for (px, py, pz), a in zip(pos, amp):
        rho2 = (x - px) ** 2 + (y - py) ** 2
        r = np.sqrt(rho2 + pz * pz)
        w = a * np.exp(2j * np.pi / lam * r) / r * cone_weight(rho2, (g.cone * pz) ** 2)
        out += w * (abs(pz) / r if obliquity else 1)
    return out


def max_rel(a, ref):
    return float(np.abs(a - ref).max() / np.abs(ref).max())


def test_one_point_is_the_spherical_wave():
    shape, z = (128, 160), -0.03
    o = point_wave([[1e-4, -5e-5, z]], [2.0], wavelength=LAM, pitch=PITCH, shape=shape)
    y, x = grid.coords(shape[0], PITCH)[:, None], grid.coords(shape[1], PITCH)[None, :]
    r = np.sqrt((x - 1e-4) ** 2 + (y + 5e-5) ** 2 + z * z)
    inner = (x - 1e-4) ** 2 + (y + 5e-5) ** 2 <= (0.5 * Grid(shape, PITCH, LAM).cone * z) ** 2
    analytic = 2.0 * np.exp(2j * np.pi / LAM * r) / r
    err = max_rel(o[inner], analytic[inner])
    assert err < POINT_SUM, f"point wave vs 2·exp(ikr)/r inside the cone: {err:.2e}"


@pytest.mark.parametrize("obliquity", [False, True])
def test_device_sum_equals_float64_numpy(rng, obliquity):
    shape = (96, 136)
    g = Grid(shape, PITCH, LAM)
    z = rng.uniform(-0.05, -0.004, 40)
    near_axis = np.c_[rng.normal(0, 2e-4, 20), rng.normal(0, 2e-4, 20)]
    edge = rng.uniform(-1, 1, (20, 2))  # at the rim of the cone over the hologram's centre
    edge = edge / np.linalg.norm(edge, axis=1)[:, None] * (0.95 * g.cone * np.abs(z[20:]))[:, None]
    pos = np.c_[np.r_[near_axis, edge], z]
    amp = rng.uniform(0.5, 1, 40) * np.exp(2j * np.pi * rng.random(40))
    o = point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=shape, obliquity=obliquity,
                   method="direct")
    err = max_rel(o, numpy_point_wave(pos, amp, shape, obliquity))
    assert err < POINT_SUM, f"OpenCL point sum vs float64 NumPy: max relative error {err:.2e}"


def test_recording_planes_match_the_direct_sum(rng):
    shape, n = (256, 256), 3000
    half = shape[0] * PITCH / 2
    pos = np.c_[rng.uniform(-half, half, (n, 2)), rng.uniform(-0.2, -0.1, n)]
    amp = np.exp(2j * np.pi * rng.random(n))
    direct = point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=shape, method="direct")
    wrp = point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=shape, method="wrp")
    err = rel_err(wrp, direct)
    assert err < WRP_VS_DIRECT, f"wavefront recording planes vs direct sum: {err:.2e}"


@pytest.mark.parametrize("method", ["direct", "wrp"])
def test_colours_in_one_pass_equal_separate_passes(rng, method):
    """(N, C) amplitudes share the geometry; each colour must still be its own wave (float32
    rounding apart: the amplitude is applied per pixel instead of folded into the recurrence)."""
    shape, n = (96, 128), 400
    pos = np.c_[rng.uniform(-3e-4, 3e-4, (n, 2)), rng.uniform(-0.03, -0.01, n)]
    amp = rng.uniform(0, 1, (n, 3)) * np.exp(2j * np.pi * rng.random((n, 1)))
    amp[:, 1] = 0  # a colour absent from the scene
    together = point_wave(pos, amp, wavelength=LAM, pitch=PITCH, shape=shape, method=method)
    assert together.shape == (3,) + shape
    for c in (0, 2):
        alone = point_wave(pos, amp[:, c], wavelength=LAM, pitch=PITCH, shape=shape,
                           method=method)
        err = max_rel(together[c], alone)
        assert err < 1e-5, f"colour {c} in one pass vs alone ({method}): {err:.2e}"
    assert not together[1].any()


def test_points_behind_the_hologram_are_refused():
    with pytest.raises(ValueError, match="z must be < 0"):
        point_wave([[0, 0, 0.01]], [1], wavelength=LAM, pitch=PITCH, shape=(8, 8))


def _cloud(rng, z):
    """Six points on a 3x2 lattice 20 pixels apart, jittered by up to a pixel."""
    lattice = np.array([(i, j) for i in (-1, 0, 1) for j in (-0.5, 0.5)]) * 20 * PITCH
    return np.c_[lattice + rng.uniform(-PITCH, PITCH, (6, 2)), np.full(6, z)]


def test_reconstruction_focuses_every_point(rng):
    shape, z = (256, 256), -0.15
    pts = _cloud(rng, z)
    holo = record_points(pts, np.ones((6, 1)), shape=shape, pitch=PITCH, wavelengths=(LAM,),
                         reference=Reference(angle=0.03), seed=3)
    image = np.abs(angular_spectrum(reconstruct(holo), wavelength=LAM, pitch=PITCH,
                                    distance=z)) ** 2
    for x, y, _ in pts:
        col, row = x / PITCH + (shape[1] - 1) / 2, y / PITCH + (shape[0] - 1) / 2
        r0, c0 = int(round(row)) - 6, int(round(col)) - 6
        win = image[r0:r0 + 13, c0:c0 + 13]
        pr, pc = np.unravel_index(win.argmax(), win.shape)
        off = math.hypot(r0 + pr - row, c0 + pc - col)
        assert off <= 1.0, f"point at ({x:.2e}, {y:.2e}) focuses {off:.2f} px away"


def test_dc_suppression_removes_the_reference_term(rng):
    """Fig. 7: the reference term R(|O|² + |R|²) is the reconstruction's component along R."""
    shape, z = (256, 256), -0.05
    ref = Reference(angle=0.03, beam_ratio=4.0)
    holo = record_points(_cloud(rng, z), np.ones((6, 1)), shape=shape, pitch=PITCH,
                         wavelengths=(LAM,), reference=ref)
    r = reference_wave(shape, wavelength=LAM, pitch=PITCH, reference=ref)

    def reference_energy(u):  # energy in the 3x3 spectral bins around R's carrier
        s = np.fft.fft2(u * np.conj(r))
        s = np.fft.fftshift(s)
        c = np.array(shape) // 2
        return float((np.abs(s[c[0] - 1:c[0] + 2, c[1] - 1:c[1] + 2]) ** 2).sum())

    plain = reference_energy(reconstruct(holo, dc_suppression=False))
    suppressed = reference_energy(reconstruct(holo, dc_suppression=True))
    db = 10 * math.log10(plain / suppressed)
    assert db >= 20, f"DC suppression lowers the reference term by only {db:.1f} dB"


def test_off_axis_reference_separates_the_twin_image(rng):
    """The object's band is |f| <= D/(λ|z|)-ish; the twin sits at 2 sin ϑ/λ."""
    shape, z = (256, 256), -0.3
    pts = np.c_[rng.uniform(-5e-5, 5e-5, (4, 2)), np.full(4, z)]
    aperture = shape[0] * PITCH
    f_obj = (aperture / 2 + 1e-4) / (LAM * abs(z))
    fy, fx = grid.freqs(shape[0], PITCH)[:, None], grid.freqs(shape[1], PITCH)[None, :]
    band = np.hypot(fx, fy) <= f_obj

    def twin_in_band(angle):
        holo = record_points(pts, np.ones((4, 1)), shape=shape, pitch=PITCH, wavelengths=(LAM,),
                             reference=Reference(angle=angle, beam_ratio=25.0))
        err = np.fft.fft2(reconstruct(holo) - holo.object_wave[0]) * band
        return float(np.linalg.norm(err) / np.linalg.norm(np.fft.fft2(holo.object_wave[0])))

    on_axis = twin_in_band(0.0)
    separated = twin_in_band(math.asin(3.2 * f_obj * LAM))
    assert on_axis > 0.5, f"on axis the twin should overlap the virtual image: {on_axis:.2e}"
    assert separated < 0.05, f"off axis the twin still overlaps: {separated:.2e}"


def test_reference_angle_sampling_condition():
    safe = math.asin(LAM / (2 * PITCH))
    with pytest.raises(ValueError, match=f"largest safe angle is {safe:.4g}"):
        Reference(angle=2 * safe).check(LAM, PITCH)
    with pytest.warns(SamplingWarning):
        Reference(angle=2 * safe, allow_aliasing=True).check(LAM, PITCH)
    Reference(angle=0.9 * safe).check(LAM, PITCH)
    with pytest.raises(ValueError, match=r"reference angle must be in \[0, π/2\)"):
        Reference(angle=2.0)


def rs_point_sources(src, amp, normal, area, shape, pitch, lam):
    """First-kind Rayleigh-Sommerfeld (Eq. 7) of point sources ``src`` (N, 3) with field values
    ``amp`` on a surface of ``normal``, each standing for ``area`` [m²]: float64, on z = 0."""
    y, x = np.meshgrid(grid.coords(shape[0], pitch), grid.coords(shape[1], pitch), indexing="ij")
    x, y, k, out = x.ravel(), y.ravel(), 2 * np.pi / lam, np.zeros(x.size, complex)
    for s, a in zip(np.array_split(src, max(1, len(src) // 512)),
                    np.array_split(amp, max(1, len(src) // 512))):
        dx, dy, dz = x - s[:, :1], y - s[:, 1:2], -s[:, 2:]
        r = np.sqrt(dx * dx + dy * dy + dz * dz)
        cos = (dx * normal[0] + dy * normal[1] + dz * normal[2]) / r
        out += a @ (cos / r * (1 / r - 1j * k) * np.exp(1j * k * r))
    return (out * area / (2 * np.pi)).reshape(shape)


@pytest.mark.parametrize("tilt_deg, diffuse", [(0, False), (15, True)])
def test_triangle_equals_dense_point_sum(tilt_deg, diffuse):
    """A triangle 10 mm in front of the hologram: the primitive pipeline (spectrum rotation
    and resampling, then offset angular spectrum) against its surface samples summed as
    Rayleigh-Sommerfeld sources in float64. Tilted about x; diffuse = random phases."""
    lam, pitch, shape = 633e-9, 4e-6, (96, 96)
    t = np.radians(tilt_deg)
    flat = np.array([[-60e-6, -50e-6, 0], [60e-6, -50e-6, 0], [5e-6, 60e-6, 0]])
    tilt_x = np.array([[1, 0, 0], [0, np.cos(t), -np.sin(t)], [0, np.sin(t), np.cos(t)]])
    prim = Primitive(corners=flat @ tilt_x.T + [0, 0, -0.01],
                     uvs=np.array([[0, 0], [1, 0], [0.5, 1]]), texture=np.ones((2, 2, 3)))
    u = primitive_wave(prim, wavelength=lam, pitch=pitch, shape=shape, diffuse=diffuse)
    m, centre = prim.frame()
    q = surface_pitch(prim, wavelength=lam, pitch=pitch)
    f, mid = surface_field(prim, pitch=q, diffuse=diffuse)
    eta, xi = (grid.coords(n, q) + c for n, c in zip(f.shape, mid[::-1]))
    src = centre + eta[:, None, None] * m[:, 1] + xi[None, :, None] * m[:, 0]
    ref = rs_point_sources(src[f != 0], f[f != 0], m[:, 2], q * q, shape, pitch, lam)
    err = rel_err(u, ref)
    assert err < PRIMITIVE_VS_POINTS, f"triangle primitive vs dense point sum: {err:.2e}"


def square(size, z, tilt_deg=0.0):
    """A white square mesh (two triangles) of side ``size`` [m] at depth ``z`` [m], tilted
    about x."""
    t = np.radians(tilt_deg)
    corners = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float) * size / 2
    rot = np.array([[1, 0, 0], [0, np.cos(t), -np.sin(t)], [0, np.sin(t), np.cos(t)]])
    return Mesh(vertices=corners @ rot.T + [0, 0, z], triangles=np.array([[0, 1, 2], [0, 2, 3]]),
                colours=np.ones((4, 3)))


def test_mesh_points_radiate_as_independent_emitters():
    """A diffuse mesh's points have independent random phases: the object wave's mean power
    is Σ I·w²/r² over the points (w their cone weight), within the speckle's scatter. (Phases
    drawn from the sampling's own random numbers once made each triangle coherent: 2.8x.)"""
    plate = Plate(matrix_world=np.eye(4), width=0.1, height=0.1)
    holo = record_hologram(square(0.08, -0.3), plate=plate, resolution=128, depth=False,
                           method="auto")
    spacing = choose((0.1, 0.1), square(0.08, -0.3).vertices, resolution=128).spacing
    pos = sample_points(square(0.08, -0.3), spacing)[0]  # as record_hologram samples it
    g = Grid(holo.shape, holo.pitch, holo.wavelengths[0])._replace(
        fill=holo.band * 2 * holo.pitch / holo.wavelengths[0])
    y, x = grid.coords(holo.shape[0], holo.pitch), grid.coords(holo.shape[1], holo.pitch)
    expected = np.zeros(holo.shape)
    for px, py, pz in pos:
        rho2 = (x[None] - px) ** 2 + (y[:, None] - py) ** 2
        expected += cone_weight(rho2, (g.cone * pz) ** 2) ** 2 / (rho2 + pz * pz)
    ratio = np.mean(np.abs(holo.object_wave[0]) ** 2) / expected.mean()
    assert 0.8 <= ratio <= 1.25, f"mean power over its expectation: {ratio:.3f}"


@pytest.mark.parametrize("tilt_deg", [0, 40])
def test_triangles_radiate_as_the_points_of_the_same_surface(tilt_deg):
    """A square recorded as two textured triangles and as points sampled on it: the same mean
    object-wave power, within the speckle's scatter (measured 0.98 and 1.12)."""
    plate = Plate(matrix_world=np.eye(4), width=0.1, height=0.1)
    mesh = square(0.04, -0.3, tilt_deg)
    points = record_hologram(mesh, plate=plate, resolution=256, depth=False, method="auto")
    triangles = record_hologram((), triangles=[mesh], plate=plate, resolution=256, depth=False,
                                method="auto")
    ratio = np.mean(np.abs(triangles.object_wave[0]) ** 2) / \
        np.mean(np.abs(points.object_wave[0]) ** 2)
    assert 0.8 <= ratio <= 1.25, f"triangles' mean power over the points': {ratio:.3f}"


def test_triangle_recording_reports_progress_per_primitive():
    """Textured triangles (a rotation and a propagation each) report progress as they go: a
    fraction per primitive and wavelength, rising, where they once reported none."""
    plate = Plate(matrix_world=np.eye(4), width=0.1, height=0.1)
    seen = []
    record_hologram((), triangles=[square(0.04, -0.3)], plate=plate, resolution=128,
                    depth=False, method="auto", progress=seen.append)
    assert len(seen) >= 2 and seen == sorted(seen) and 0.1 <= seen[-1] <= 1.0, seen
    assert sum(0.1 <= f < 1.0 for f in seen) >= 2, "no report while the triangles ran"


def test_points_nearer_than_the_plate_samples_are_refused_with_the_safe_distance():
    with pytest.raises(InputError, match=r"points need \|z\| >= 0.000\d+ m"):
        record_points([[0, 0, -4e-6]], [[1.0]], shape=(64, 64), pitch=8e-6,
                      wavelengths=(633e-9,))


def test_no_points_are_refused():
    with pytest.raises(InputError, match="nothing to record"):
        record_points(np.zeros((0, 3)), np.zeros((0, 1)), shape=(8, 8), pitch=8e-6,
                      wavelengths=(633e-9,))


def test_math_of_the_safe_distance():
    """2 samples across the cone: |z| = 2p/tan θ, θ the cone's edge (CONE_FILL of Nyquist)."""
    from holo_core.plate.point_sources import CONE_FILL, Grid, safe_distance
    p, lam = 8e-6, 633e-9
    s = CONE_FILL * lam / (2 * p)
    assert math.isclose(safe_distance(Grid((8, 8), p, lam)), 2 * p * math.sqrt(1 - s * s) / s)


def test_a_long_wavelength_hologram_is_written_and_read_back(tmp_path):
    """Finding 2: λ long against the pitch chose a cone of sin θ >= 1, which the reader refuses
    (here λ = 1 mm on a 39 µm pitch: 0.95·λ2/8p = 1.69 before the cone was capped)."""
    plate = Plate(matrix_world=np.eye(4), width=0.0025, height=0.0025)
    h = record_hologram(([[0.0, 0.0, -0.05]], [[1.0, 1.0, 1.0]]), plate=plate, resolution=64,
                        wavelength=1e-3)
    assert 0 < h.band < 1, f"band sin θ = {h.band}"
    back = read_hologram(write_hologram(tmp_path / "h.exr", h))
    assert back.band == h.band and back.wavelengths == h.wavelengths


def test_a_mesh_whose_emitters_cannot_be_found_in_memory_is_refused_first(rng, monkeypatch):
    """Random triangles through each other cross every ray of the zone many times over (10⁷
    vertices held 4.75 GB and ran past 150 s after the memory estimate passed them): counted
    before the work, they are refused by their crossings; a cube in the same memory is
    not."""
    from holo_core.plate.recording import plate_plan
    from holo_core.scene.camera import Camera, look_at
    plate = Plate(matrix_world=np.eye(4), width=0.1, height=0.1)
    camera = Camera(matrix_world=look_at((0, 0, 0.3), (0, 0, -0.33)), resolution=(160, 90),
                    fstop=2.8, focus_distance=0.63)
    v = rng.uniform([-0.03, -0.03, -0.36], [0.03, 0.03, -0.3], (30_000, 3))
    noise = Mesh(vertices=v, triangles=rng.integers(0, len(v), (10_000, 3)))
    corners = np.array([[x, y, z] for x in (-0.03, 0.03) for y in (-0.03, 0.03)
                        for z in (-0.36, -0.3)])
    cube = Mesh(vertices=corners, triangles=[[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5],
                                             [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],
                                             [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "200M")  # a step may take memory.SHARE of it
    plate_plan(cube, plate=plate, camera=camera)
    with pytest.raises(InputError, match=r"finding the emitters of 10000 triangles \(1\.\d+e\+06 "
                                         r"crossings of the zone's rays.* needs 0\.\d+ GiB of "
                                         r"memory"):
        plate_plan(noise, plate=plate, camera=camera)
