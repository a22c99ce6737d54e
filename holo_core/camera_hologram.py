"""Camera holograms: the object wave recorded on a virtual plate at the camera's entrance pupil,
and the image the camera forms from it (Sect. VII: any wave field can be evaluated on the
aperture of an arbitrarily placed camera).

A camera uses only the light that reaches its pupil, so the samples go there:

- Optics (:func:`choose_optics`). A pupil of diameter D resolves λ/D; λ = D·Δ/s makes that
  one *fine pixel* (Δ the pixel angle, s the supersampling). A lens keeps its real aperture
  (lens/f-stop) and focus, so the defocus is the camera's. Without one, the pupil is the
  largest whose defocus over the emitters' depth range stays within a fine pixel.
- Bins. The pupil fills its FFT window (h·dy = w·dx = D): its spectrum's bins lie b = Δ/s
  apart in direction cosine, each bin one direction of arrival, covering the field of view
  and a margin for blur.
- Emitters (:func:`rasterize`). The surfaces the camera sees, one emitter per bin: each bin's
  ray meets the nearest triangle (a depth buffer, perspective-correct attributes), which
  emits its colour from the hit point, at distance R, with a random phase per look (speckle
  is averaged over looks, Sect. VII-E). Bare points go to their nearest bin.
- Object wave (:func:`object_wave`). By depth layers: O = Σ_l exp(ik(√(ρ²+z_l²) − z_l))·
  F⁻¹[S_l], where S_l holds the layer's emitters as amp·exp(i(kR + φ)) at their bins. Each
  plane wave is exact; each layer's curvature is that of its distance (the Fresnel
  approximation per layer, spaced so that the error stays within a quarter wave at the pupil's
  rim: Rayleigh's depth of focus).
- Image (:func:`render_camera`). The pupil cut by the iris (a raised-cosine rim against
  ringing, Fig. 9), the thin lens of Eq. 24, and the angular spectrum read at each pixel's
  direction cosines (Eq. 22) by the ES kernel of a non-uniform FFT: no interpolation blur.
  Radiance |A|² / (N·Σw²) shows a surface's own colour whatever the aperture or the
  resolution. Depth: the two-wavelength phase difference (Eq. 26–30) of the colour image and
  the depth partner's (λ2 = ε·λ1, unit emitters), whose intensity is also each pixel's
  coverage (alpha).
- The paper's route (:func:`intensity_hologram`, :func:`reconstruct_object_wave`): the object
  wave is recorded as H = |O + R|² with an off-axis plane reference on a grid 4× finer in x,
  and reconstructed as R'·H with the DC and twin terms filtered off (Sect. V–VI). Rendering
  the object wave directly is that reconstruction's ideal filter.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import numpy as np

from . import jobs, memory, validate
from .camera import Camera
from .depth import from_cross_spectrum, partner_wavelength
from .emitters import Mesh, _colour
from .opencl import get_runtime
from .opencl.arrays import empty
from .propagation import grid
from .propagation.tilt import _cached, _es_table, es_transform
from .render import BACKGROUND_DEPTH, RenderResult
from .speckle import box_mean, downsample
from .validate import InputError

log = logging.getLogger(__name__)
SUPERSAMPLE = 2        # fine pixels per pixel (per axis): the pupil resolves one fine pixel
LAYER_PHASE = math.pi / 2  # a layer's largest curvature error at the pupil's rim [rad]: a
                           # quarter wave, Rayleigh's depth of focus
MAX_LAYERS = 512
IRIS_TAPER = 0.1       # the iris's raised-cosine rim, a fraction of its radius
DEPTH_MARGIN = 1.25    # the depth pair's unambiguous range over the scene's depth extent
COVERAGE_EDGE = (0.25, 0.75)  # coverage mapped to alpha 0 … 1 (0.5: the geometric edge)
COVERAGE_FLOOR = 0.05  # the colour is radiance / coverage where coverage exceeds this
TAPS, ES_TABLE = 6, 4096


@dataclass(frozen=True, slots=True, kw_only=True)
class PupilOptics:
    """The camera hologram's optics.

    wavelength, depth_wavelength : λ1 of the colour channels and λ2 = ε·λ1 of the depth partner [m]
    diameter : the pupil D [m]
    focus : the planar distance in focus [m] (a thin lens, Eq. 24): the camera's, or for a
        camera without depth of field the middle of the emitters' depth range in 1/z
    supersample : s, fine pixels per pixel per axis
    bin : direction-cosine spacing of the spectrum's bins (b = Δ/s)
    shape : (h, w) pupil samples = spectrum bins
    layers : planar distances z_l [m] of the depth layers, nearest first
    depth_range : (near, far) planar depths [m] of the emitters
    centre : the ray distance [m] the depth pair's phase is unwrapped around (Eq. 30)
    """

    wavelength: float
    depth_wavelength: float
    diameter: float
    focus: float | None
    supersample: int
    bin: float
    shape: tuple
    layers: tuple
    depth_range: tuple
    centre: float

    def pitch(self, wavelength=None) -> tuple[float, float]:
        """(dy, dx) [m] of the pupil's samples at ``wavelength`` (default λ1): the bins stay
        in the same directions, so the pupil scales with λ."""
        lam = wavelength or self.wavelength
        h, w = self.shape
        return lam / (h * self.bin), lam / (w * self.bin)

    def layer_of(self, depth) -> np.ndarray:
        """Index of the layer each planar ``depth`` [m] belongs to (nearest in 1/z)."""
        inv = 1 / np.asarray(self.layers)
        return np.argmin(np.abs(1 / np.asarray(depth)[:, None] - inv[None, :]), axis=1)

    def describe(self) -> str:
        h, w = self.shape
        lens = f"focus {self.focus:.4g} m" if self.focus else "no lens"
        return (f"camera hologram {w}x{h} on a {self.diameter * 1e3:.3g} mm pupil ({lens}), "
                f"λ = {self.wavelength:.4g} m (depth λ2 = {self.depth_wavelength:.6g} m), "
                f"{len(self.layers)} depth layers, {self.supersample}x supersampling")


def choose_optics(camera: Camera, depth_range, *, supersample=SUPERSAMPLE,
                  aperture: float | None = None) -> PupilOptics:
    """Optics for ``camera`` and emitters at planar depths ``depth_range`` (near, far) [m]
    (module docstring). ``aperture`` [m] overrides the pupil's diameter."""
    s = int(validate.at_least("supersample", supersample, 1))
    near, far = (validate.positive("depth_range", d, "m") for d in depth_range)
    near, far = min(near, far), max(near, far)
    b = camera.pixel_angle() / s
    if camera.fstop is not None:
        focus, diameter = camera.focus_distance, camera.aperture_diameter
    else:  # focused on the middle in 1/z; the largest pupil defocused by one fine pixel
        focus = 2 / (1 / near + 1 / far)
        defocus = max(1 / near - 1 / focus, 1 / focus - 1 / far, 1e-12)
        diameter = min(b / defocus, camera.lens * 1e-3)  # at most f/1
    if aperture is not None:
        diameter = validate.positive("aperture", aperture, "m")
    lam = diameter * b
    blur = diameter * max(abs(1 / near - 1 / focus), abs(1 / far - 1 / focus))
    margin = math.ceil(blur / b) + TAPS + 2
    alpha, beta, gamma = replace(camera, resolution=tuple(r * s for r in camera.resolution)
                                 ).direction_cosines()
    shape = tuple(grid.next_fast_len(2 * (math.ceil(np.abs(a).max() / b) + margin))
                  for a in (beta, alpha))
    step = 16 * LAYER_PHASE * lam / (2 * math.pi * diameter**2)  # layer spacing in 1/z
    n = max(1, math.ceil((1 / near - 1 / far) / step))
    if n > MAX_LAYERS:
        validate.warn_sampling(f"the emitters' depth range needs {n} layers at this aperture; "
                               f"using {MAX_LAYERS} (defocus phase error up to "
                               f"{LAYER_PHASE * n / MAX_LAYERS:.2g} rad)")
        n = MAX_LAYERS
    inv = 1 / far + (np.arange(n) + 0.5) * (1 / near - 1 / far) / n
    farthest = far / float(gamma.min())  # the longest ray to the far depth
    depth_half = DEPTH_MARGIN * max(farthest - near, lam) / 2
    optics = PupilOptics(wavelength=lam, depth_wavelength=partner_wavelength(lam, depth_half),
                         diameter=diameter, focus=focus,
                         supersample=s, bin=b, shape=shape, layers=tuple(sorted(1 / inv)),
                         depth_range=(near, far), centre=(near + farthest) / 2)
    log.info("optics: %s", optics.describe())
    return optics


# --- emitters ---------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Emitters:
    """One emitter per covered bin: ``index`` into the (h, w) spectrum in FFT order, planar
    ``depth`` and ray ``distance`` R [m], ``colour`` (n, 3) linear, ``coverage`` (n,) in [0, 1]
    (the partner's amplitude²), sorted by ``layer``; ``starts`` the first emitter of each."""

    index: np.ndarray
    depth: np.ndarray
    distance: np.ndarray
    colour: np.ndarray
    coverage: np.ndarray
    layer: np.ndarray
    starts: np.ndarray


def camera_space(camera: Camera, points) -> np.ndarray:
    """World points (N, 3) [m] in the camera's axes, relative to its pupil."""
    return (np.asarray(points, np.float64) - camera.position) @ camera.rotation


def _bin_rays(kx, ky, b):
    """View tangents (t_x, t_y) of the rays of bins (kx, ky) (signed indices)."""
    alpha, beta = kx * b, ky * b
    gamma = np.sqrt(np.clip(1 - alpha * alpha - beta * beta, 1e-12, None))
    return -alpha / gamma, -beta / gamma


def rasterize(meshes, camera: Camera, optics: PupilOptics, *, chunk=4_000_000) -> Emitters:
    """The surfaces of ``meshes`` (world metres) the camera sees, one emitter per bin."""
    h, w = optics.shape
    b = optics.bin
    zbuf = np.full(h * w, np.inf)
    owner = np.full(h * w, -1, np.int64)  # (mesh, triangle) packed
    bary = np.zeros((h * w, 2), np.float32)
    meshes = list(meshes)
    for m, mesh in enumerate(meshes):
        v = camera_space(camera, mesh.vertices)
        tri = np.asarray(mesh.triangles)
        d = -v[:, 2]
        t = v[:, :2] / np.where(d > 1e-9, d, 1)[:, None]
        p0, p1, p2 = (t[tri[:, i]] for i in range(3))
        area = (p1[:, 0] - p0[:, 0]) * (p2[:, 1] - p0[:, 1]) - \
            (p2[:, 0] - p0[:, 0]) * (p1[:, 1] - p0[:, 1])
        # triangles reaching behind the pupil, or seen edge-on (or degenerate), are not seen
        tri_ids = np.nonzero((d[tri] > 1e-9).all(1) & (area != 0))[0]
        if not len(tri_ids):
            continue
        box = _bin_boxes(t[tri[tri_ids]], b, h, w)
        keep = (box[:, 1] >= box[:, 0]) & (box[:, 3] >= box[:, 2])
        tri_ids, box = tri_ids[keep], box[keep]
        sizes = (box[:, 1] - box[:, 0] + 1) * (box[:, 3] - box[:, 2] + 1)
        ends = np.cumsum(sizes)
        lo = 0
        while lo < len(tri_ids):
            hi = max(lo + 1, int(np.searchsorted(ends, (ends[lo - 1] if lo else 0) + chunk)))
            _raster_chunk(tri_ids[lo:hi], box[lo:hi], sizes[lo:hi], tri, t, d, b, h, w,
                          m, zbuf, owner, bary)
            lo = hi
    covered = np.nonzero(owner >= 0)[0]
    return _emitters(meshes, covered, owner[covered], bary[covered], zbuf[covered], optics)


def _bin_boxes(tris, b, h, w):
    """Bin ranges (kx0, kx1, ky0, ky1) that may hold each projected triangle (T, 3, 2) of view
    tangents: its edges sampled, as direction cosines bend them, plus one bin."""
    s = np.linspace(0, 1, 9)[:, None]
    pts = np.concatenate([tris[:, i:i + 1] * (1 - s) + tris[:, (i + 1) % 3:(i + 1) % 3 + 1] * s
                          for i in range(3)], 1)
    n = np.sqrt(1 + (pts ** 2).sum(-1))
    kx, ky = -pts[..., 0] / n / b, -pts[..., 1] / n / b
    box = np.stack([np.floor(kx.min(1)) - 1, np.ceil(kx.max(1)) + 1,
                    np.floor(ky.min(1)) - 1, np.ceil(ky.max(1)) + 1], 1)
    lim = np.array([-(w // 2), (w - 1) // 2, -(h // 2), (h - 1) // 2])
    box[:, 0::2] = np.maximum(box[:, 0::2], lim[0::2])
    box[:, 1::2] = np.minimum(box[:, 1::2], lim[1::2])
    return box.astype(np.int64)


def _raster_chunk(ids, box, sizes, tri, t, d, b, h, w, m, zbuf, owner, bary):
    total = int(sizes.sum())
    which = np.repeat(np.arange(len(ids)), sizes)
    q = np.arange(total) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    width = (box[:, 1] - box[:, 0] + 1)[which]
    kx = box[which, 0] + q % width
    ky = box[which, 2] + q // width
    tx, ty = _bin_rays(kx, ky, b)
    corners = tri[ids][which]
    p0, p1, p2 = (t[corners[:, i]] for i in range(3))
    area = (p1[:, 0] - p0[:, 0]) * (p2[:, 1] - p0[:, 1]) - (p2[:, 0] - p0[:, 0]) * (p1[:, 1] - p0[:, 1])
    l1 = ((tx - p0[:, 0]) * (p2[:, 1] - p0[:, 1]) - (p2[:, 0] - p0[:, 0]) * (ty - p0[:, 1]))
    l2 = ((p1[:, 0] - p0[:, 0]) * (ty - p0[:, 1]) - (tx - p0[:, 0]) * (p1[:, 1] - p0[:, 1]))
    l1, l2 = l1 / area, l2 / area
    inside = (l1 >= 0) & (l2 >= 0) & (l1 + l2 <= 1)
    if not inside.any():
        return
    l1, l2, corners, which = l1[inside], l2[inside], corners[inside], which[inside]
    inv = (1 - l1 - l2) / d[corners[:, 0]] + l1 / d[corners[:, 1]] + l2 / d[corners[:, 2]]
    depth = 1 / inv
    flat = (ky[inside] % h) * w + kx[inside] % w
    order = np.lexsort((depth, flat))  # nearest first within each bin
    flat, depth = flat[order], depth[order]
    first = np.ones(len(flat), bool)
    first[1:] = flat[1:] != flat[:-1]
    sel = order[first]
    flat, depth = flat[first], depth[first]
    nearer = depth < zbuf[flat]
    flat, sel = flat[nearer], sel[nearer]
    zbuf[flat] = depth[nearer]
    owner[flat] = (m << 40) | ids[which[sel]]
    # perspective-correct barycentrics: λ_i/d_i over Σ λ_j/d_j
    c = corners[sel]
    w1 = l1[sel] / d[c[:, 1]] / inv[sel]
    w2 = l2[sel] / d[c[:, 2]] / inv[sel]
    bary[flat] = np.stack([w1, w2], -1)


def _emitters(meshes, covered, owner, bary, depth, optics: PupilOptics) -> Emitters:
    h, w = optics.shape
    colour = np.ones((len(covered), 3))
    mesh_of, tri_of = owner >> 40, owner & ((1 << 40) - 1)
    for m, mesh in enumerate(meshes):
        sel = mesh_of == m
        if not sel.any():
            continue
        corners = np.asarray(mesh.triangles)[tri_of[sel]]
        lam = bary[sel].astype(np.float64)
        weights = np.stack([1 - lam.sum(1), lam[:, 0], lam[:, 1]], -1)
        c = _colour(mesh, corners, weights, 3)
        colour[sel] = c if c.shape[1] == 3 else np.repeat(c.mean(1, keepdims=True), 3, 1)
    ky, kx = grid_indices(covered, optics.shape)
    tx, ty = _bin_rays(kx, ky, optics.bin)
    distance = depth * np.sqrt(1 + tx * tx + ty * ty)
    return _sorted_emitters(covered, depth, distance, colour, np.ones(len(covered)), optics)


def grid_indices(flat, shape):
    """Signed (row, col) bin indices of flat FFT-order indices."""
    h, w = shape
    r, c = np.divmod(np.asarray(flat), w)
    return np.where(r > (h - 1) // 2, r - h, r), np.where(c > (w - 1) // 2, c - w, c)


def _sorted_emitters(index, depth, distance, colour, coverage, optics):
    layer = optics.layer_of(depth) if len(depth) else np.zeros(0, np.int64)
    order = np.argsort(layer, kind="stable")
    starts = np.searchsorted(layer[order], np.arange(len(optics.layers) + 1))
    return Emitters(index=index[order], depth=depth[order], distance=distance[order],
                    colour=np.clip(colour[order], 0, None), coverage=coverage[order],
                    layer=layer[order], starts=starts)


def point_emitters(positions, colours, camera: Camera, optics: PupilOptics) -> Emitters:
    """Bare points (N, 3) [m] with linear colours (N, 3), each at its nearest bin: within half
    a bin b/2 = Δ/(2s) of its direction (points that share a bin add their intensities; its
    depth is their intensity-weighted mean)."""
    local = camera_space(camera, positions)
    front = local[:, 2] < 0
    local, col = local[front], np.asarray(colours, np.float64).reshape(-1, 3)[front]
    r = np.linalg.norm(local, axis=1)
    kx = np.rint(-local[:, 0] / r / optics.bin).astype(np.int64)
    ky = np.rint(-local[:, 1] / r / optics.bin).astype(np.int64)
    h, w = optics.shape
    inside = (np.abs(kx) <= (w - 1) // 2) & (np.abs(ky) <= (h - 1) // 2)
    kx, ky, col, depth = kx[inside], ky[inside], col[inside], -local[inside, 2]
    tx, ty = _bin_rays(kx, ky, optics.bin)
    dist = depth * np.sqrt(1 + tx * tx + ty * ty)
    index, inverse = np.unique((ky % h) * w + kx % w, return_inverse=True)
    weight = col.sum(1) + 1e-30
    summed = np.stack([np.bincount(inverse, col[:, c]) for c in range(3)], -1)
    mean = lambda a: np.bincount(inverse, a * weight) / np.bincount(inverse, weight)  # noqa: E731
    return _sorted_emitters(index, mean(depth), mean(dist), summed, np.ones(len(index)),
                            optics)


def depth_range(meshes, camera: Camera, points=None) -> tuple[float, float]:
    """(near, far) planar depths [m] of the emitters in front of ``camera``."""
    zs = [-camera_space(camera, m.vertices)[:, 2] for m in meshes]
    if points is not None and len(points):
        zs.append(-camera_space(camera, points)[:, 2])
    z = np.concatenate(zs) if zs else np.zeros(0)
    z = z[z > 0]
    if not len(z):
        raise InputError("no emitter lies in front of the camera")
    return float(z.min()), float(z.max())


# --- the object wave on the pupil, and the image ------------------------------------------------

class _Fields:
    """Device state of one render: the emitters' bins, amplitudes and phases, work arrays."""

    def __init__(self, rt, em: Emitters, optics: PupilOptics, camera_fine: Camera):
        self.rt, self.em, self.optics = rt, em, optics
        h, w = optics.shape
        self.index = rt.to_device(em.index.astype(np.int32))
        self.lambdas = (optics.wavelength, optics.depth_wavelength)
        self.phase0 = [rt.to_device(np.remainder(2 * np.pi / lam * em.distance, 2 * np.pi),
                                    np.float32) for lam in self.lambdas]
        self.amps = [rt.to_device(np.sqrt(em.colour[:, c]), np.float32) for c in range(3)]
        self.amps.append(rt.to_device(np.sqrt(em.coverage), np.float32))
        self.spectrum, self.pupil = empty(rt, (h, w)), empty(rt, (h, w))
        self.padded = empty(rt, (2 * h, 2 * w))
        self.apod = [rt.to_device(1 / es_transform(grid.signed_indices(n) / (2 * n)), np.float32)
                     for n in (h, w)]
        self.es = _cached(rt, "es-table", _es_table)  # the table tilt.py reads too
        alpha, beta, _ = camera_fine.direction_cosines()
        self.u = rt.to_device(2 * alpha / optics.bin, np.float32)
        self.v = rt.to_device(2 * beta / optics.bin, np.float32)
        self.pixels = empty(rt, alpha.shape)
        # |A|² / (N·Σw²) is the emitters' intensity (Parseval), w the iris on the samples
        self.scale = 1 / math.sqrt(h * w * float(np.sum(_iris(optics, h, w) ** 2)))
        self.options = rt.real_options + (f"-DTAPS={TAPS}", f"-DES_TABLE={ES_TABLE}")

    def kernel(self, name):
        return self.rt.kernel("pupil", name, self.options)

    def object_wave(self, field: int, phases):
        """The pupil's object wave (device, (h, w) FFT order) of colour channel ``field``
        (0-2) or the depth partner (3), emitter phases ``phases`` (device float32)."""
        rt, em, optics = self.rt, self.em, self.optics
        lam = self.lambdas[field == 3]
        dy, dx = optics.pitch(lam)
        h, w = optics.shape
        self.pupil.fill(0)
        for layer, z in enumerate(optics.layers):
            first, last = int(em.starts[layer]), int(em.starts[layer + 1])
            if first == last:
                continue
            self.spectrum.fill(0)
            self.kernel("scatter")(rt.queue, (last - first,), None, self.spectrum.data,
                                   self.index.data, self.amps[field].data,
                                   self.phase0[field == 3].data, phases.data, np.int32(first))
            rt.fft.backward(self.spectrum)
            self.kernel("add_layer")(rt.queue, (h, w), None, self.pupil.data,
                                     self.spectrum.data, np.float32(dy), np.float32(dx),
                                     np.float32(2 * np.pi / lam), np.float32(z))
        return self.pupil

    def image(self, field: int) -> np.ndarray:
        """The image of the pupil's current wave (fine pixels, complex), normalised so that
        E|A|² is the emitters' intensity."""
        rt, optics = self.rt, self.optics
        lam = self.lambdas[field == 3]
        dy, dx = optics.pitch(lam)
        h, w = optics.shape
        self.padded.fill(0)
        self.kernel("pupil_window")(
            rt.queue, (h, w), None, self.padded.data, self.pupil.data, np.float32(dy),
            np.float32(dx), np.float32(optics.diameter / 2 * lam / optics.wavelength),
            np.float32(IRIS_TAPER), np.float32(2 * np.pi / lam), np.float32(optics.focus or 0),
            self.apod[0].data, self.apod[1].data)
        rt.fft.forward(self.padded)
        self.kernel("read_pixels")(rt.queue, (self.pixels.size,), None, self.pixels.data,
                                   self.padded.data, np.int32(2 * h), np.int32(2 * w),
                                   self.u.data, self.v.data, np.float32(self.scale), self.es.data)
        return self.pixels.get()


def _iris(optics: PupilOptics, h, w) -> np.ndarray:
    """The iris's transmission on the pupil's samples (what pupil_window applies)."""
    dy, dx = optics.pitch()
    y, x = grid.signed_indices(h)[:, None] * dy, grid.signed_indices(w)[None, :] * dx
    rho, radius = np.hypot(x, y), optics.diameter / 2
    inner = (1 - IRIS_TAPER) * radius
    edge = 0.5 * (1 + np.cos(np.pi * np.clip(rho - inner, 0, None) / (radius - inner)))
    return np.where(rho >= radius, 0.0, np.where(rho > inner, edge, 1.0))


def object_wave(em: Emitters, optics: PupilOptics, camera: Camera, *, field=0,
                seed=0) -> np.ndarray:
    """The camera hologram: the object wave of colour channel ``field`` (0-2) or the depth
    partner (3) on the pupil (h, w) [field units], centred (row, col of the optical axis at
    (h//2, w//2)), pitch ``optics.pitch(λ)``, emitter phases drawn from ``seed``."""
    rt = get_runtime()
    fields = _Fields(rt, em, optics, replace(camera, resolution=(1, 1)))
    phases = rt.to_device(_phases(len(em.index), seed), np.float32)
    return np.fft.fftshift(fields.object_wave(field, phases).get())


def _phases(n, seed) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0, 2 * np.pi, n)


@dataclass(frozen=True, slots=True, kw_only=True)
class HologramRecording:
    """An intensity hologram of a pupil's object wave: ``intensity`` (h, 4w) float32 [field
    units²], the reference's ``carrier`` [cycles per sample of the fine grid] and its
    ``amplitude`` [field units]."""

    intensity: np.ndarray
    carrier: float
    amplitude: float


def intensity_hologram(o: np.ndarray, *, beam_ratio=4.0) -> HologramRecording:
    """H = |O + R|² (Eq. 5) of a centred pupil wave ``o`` (h, w), on a grid 4× finer in x so
    that a plane reference of carrier 1.5·w bins (sin ϑ = 3λ/(4dx)) separates the virtual
    image, the twin and the |O|² term (Sect. V-B); |R|² = ``beam_ratio``·mean|O|²."""
    h, w = o.shape
    spec = np.fft.fftshift(np.fft.fft2(np.fft.ifftshift(o)))
    big = np.zeros((h, 4 * w), complex)
    big[:, 3 * w // 2: 3 * w // 2 + w] = spec
    fine = np.fft.fftshift(np.fft.ifft2(np.fft.ifftshift(big))) * 4
    amplitude = math.sqrt(beam_ratio * float(np.mean(np.abs(o) ** 2)))
    carrier = 1.5 * w / (4 * w)
    ref = _reference(amplitude, carrier, 4 * w)
    return HologramRecording(intensity=np.abs(fine + ref).astype(np.float32) ** 2,
                             carrier=carrier, amplitude=amplitude)


def _reference(amplitude, carrier, n) -> np.ndarray:
    """The plane reference wave R along a row of ``n`` samples (Eq. 4)."""
    return amplitude * np.exp(2j * np.pi * carrier * np.arange(n))[None, :]


def reconstruct_object_wave(rec: HologramRecording) -> np.ndarray:
    """R'·H with the DC term suppressed (its mean removed) and the twin and |O|² terms filtered
    off (Sect. VI): the centred pupil wave (h, w) again."""
    ww = rec.intensity.shape[1]
    w = ww // 4
    ref = _reference(rec.amplitude, rec.carrier, ww)
    u = (rec.intensity - rec.intensity.mean()) * ref / rec.amplitude**2  # O·R*·R = O|R|²
    spec = np.fft.fftshift(np.fft.fft2(np.fft.ifftshift(u)))
    o = spec[:, 3 * w // 2: 3 * w // 2 + w]
    return np.fft.fftshift(np.fft.ifft2(np.fft.ifftshift(o))) / 4


# --- rendering -------------------------------------------------------------------------------

FINE_PIXEL_BYTES = 64  # per fine pixel: the four looks' images, coverage, depth, accumulators
DEVICE_FIELDS = 6      # complex pupil-sized buffers on the device: the layers' sum, FFTs, iris


def render_camera(meshes=(), camera: Camera = None, *, points=None, samples=16,
                  supersample=SUPERSAMPLE, aperture=None, exposure=1.0, seed=0,
                  via="object_wave", progress: jobs.Progress = None, on_sample=None):
    """Render ``meshes`` (and bare ``points``: (positions (N, 3) [m], colours (N, 3))) as
    ``camera`` sees them through its camera hologram (module docstring).

    samples : looks with independent random emitter phases, averaged progressively
        (speckle); ``on_sample(result, n)`` gets the running result after each.
    supersample : fine pixels per pixel per axis (the pupil resolves one fine pixel).
    aperture : pupil diameter [m], default the camera's (lens/f-stop) or, without a lens, the
        widest whose defocus stays within a fine pixel.
    exposure : radiance to pixel value (1: a surface shows its own colour, as an emission
        shader of strength 1 in Cycles).
    via : 'object_wave' (the ideal reconstruction) or 'hologram' (each look's object wave
        recorded as an intensity hologram with an off-axis reference and reconstructed).
    """
    if camera is None:
        raise InputError("render_camera needs a camera")
    if via not in ("object_wave", "hologram"):
        raise InputError(f"via must be 'object_wave' or 'hologram'; got {via!r}")
    samples = int(validate.at_least("samples", samples, 1))
    supersample = int(validate.at_least("supersample", supersample, 1))
    w, h = camera.resolution
    memory.check_host(f"a {w}x{h} camera view at supersample {supersample}",
                      FINE_PIXEL_BYTES * w * h * supersample**2)
    meshes = [meshes] if isinstance(meshes, Mesh) else list(meshes)
    pos = None if points is None else np.asarray(points[0], np.float64).reshape(-1, 3)
    optics = choose_optics(camera, depth_range(meshes, camera, pos), supersample=supersample,
                           aperture=aperture)
    em = rasterize(meshes, camera, optics) if meshes else None
    if pos is not None:
        em = _merged(em, point_emitters(pos, points[1], camera, optics), optics)
    if em is None or not len(em.index):
        raise InputError("no emitter is visible to the camera")
    fine = replace(camera, resolution=tuple(r * supersample for r in camera.resolution))
    rt = get_runtime()
    pupil = 8.0 * math.prod(optics.shape)
    memory.check_device(rt, f"the {optics.shape[1]}x{optics.shape[0]} pupil's fields",
                        DEVICE_FIELDS * pupil + FINE_PIXEL_BYTES * w * h * supersample**2, pupil)
    fields = _Fields(rt, em, optics, fine)
    acc = _Accumulator(camera, optics, exposure)
    rng = np.random.default_rng(seed)
    for n in range(1, samples + 1):
        phases = rt.to_device(rng.uniform(0, 2 * np.pi, len(em.index)), np.float32)
        images = []
        for f in range(4):
            wave = fields.object_wave(f, phases)
            if via == "hologram":
                wave.set(np.ascontiguousarray(np.fft.ifftshift(reconstruct_object_wave(
                    intensity_hologram(np.fft.fftshift(wave.get())))), np.complex64))
            images.append(fields.image(f))
            jobs.report(progress, (n - 1) * 4 + f + 1, samples * 4)
        acc.add(images)
        if on_sample is not None:
            on_sample(acc.result(), n)
    result = acc.result()
    log.info("camera hologram: %d samples, speckle contrast %.3f", samples,
             result.info["speckle_contrast"])
    return result


def _merged(a: Emitters | None, b: Emitters, optics) -> Emitters:
    if a is None:
        return b
    cat = [np.concatenate([getattr(a, k), getattr(b, k)])
           for k in ("index", "depth", "distance", "colour", "coverage")]
    return _sorted_emitters(*cat, optics)


class _Accumulator:
    """The running average of the looks, and the speckle contrast of that average."""

    def __init__(self, camera: Camera, optics: PupilOptics, exposure):
        self.camera, self.optics, self.exposure, self.n = camera, optics, exposure, 0
        self.rgb = self.cross = self.coverage = 0
        self.lum = self.lum2 = 0

    def add(self, images):
        s = self.optics.supersample
        rgb = np.stack([np.abs(a) ** 2 for a in images[:3]], -1)
        cov = np.abs(images[3]) ** 2
        self.rgb = self.rgb + rgb
        self.coverage = self.coverage + cov
        self.cross = self.cross + (images[0] + images[1] + images[2]) * np.conj(images[3])
        # the colour this look alone would give, for the spread between looks
        look = downsample(rgb.mean(-1), s) / np.maximum(downsample(cov, s), COVERAGE_FLOOR)
        self.lum, self.lum2 = self.lum + look, self.lum2 + look * look
        self.n += 1

    def result(self) -> RenderResult:
        o, n, s = self.optics, self.n, self.optics.supersample
        radiance = downsample(self.rgb / n, s)
        coverage = downsample(self.coverage / n, s)
        lo, hi = COVERAGE_EDGE
        # a pixel's coverage, or its 3×3 neighbourhood's where higher: a speckle minimum
        # inside a surface leaves no hole, while a straight edge keeps its half-way crossing
        solid = np.maximum(coverage, box_mean(coverage, 1))
        alpha = np.clip((solid - lo) / (hi - lo), 0, 1).astype(np.float32)
        # the surfaces' own colour: radiance over coverage (what the pass stores premultiplied
        # by alpha); the colour and the partner share their speckle, which this divides out
        colour = radiance / np.maximum(coverage, COVERAGE_FLOOR)[..., None] * self.exposure
        ray = from_cross_spectrum(downsample(self.cross, s), wavelengths=(
            o.wavelength, o.depth_wavelength), centre=o.centre)
        tx, ty = self.camera.pixel_tangents()
        planar = ray / np.sqrt(1 + tx * tx + ty * ty)
        depth = np.where(alpha > 0, planar, BACKGROUND_DEPTH).astype(np.float32)
        mean = self.lum / n
        spread = np.sqrt(np.maximum(self.lum2 / n - mean**2, 0) / max(n - 1, 1))
        solid = alpha >= 1
        contrast = float(np.median(spread[solid] / np.maximum(mean[solid], 1e-30))) \
            if solid.any() and n > 1 else float("nan")
        info = {"samples": n, "speckle_contrast": contrast, "aperture_m": o.diameter,
                "focus_m": o.focus, "wavelengths_m": [o.wavelength, o.depth_wavelength],
                "layers": len(o.layers), "pupil_samples": list(o.shape),
                "resolution_limit_px": 1 / s, "exposure": self.exposure}
        return RenderResult(rgb=colour.astype(np.float32), alpha=alpha, depth=depth, info=info,
                            coverage=coverage.astype(np.float32),
                            radiance=(radiance * self.exposure).astype(np.float32))
