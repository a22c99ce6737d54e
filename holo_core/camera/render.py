"""The camera hologram's image: colour, coverage (alpha) and depth.

- Image (:func:`render_camera`). The pupil cut by the iris (a raised-cosine rim against
  ringing, Fig. 9), the thin lens of Eq. 24, and the angular spectrum read at each pixel's
  direction cosines (Eq. 22) by the ES kernel of a non-uniform FFT: no interpolation blur.
  Radiance |A|² / (N·Σw²) shows a surface's own colour whatever the aperture or the
  resolution. Depth: the two-wavelength phase difference (Eq. 26–30) of the colour image and
  the depth partner's (λ2 = ε·λ1, unit emitters), whose intensity is also each pixel's
  coverage (alpha).
"""

from __future__ import annotations

import logging
import math

import numpy as np

from .. import jobs, memory, validate
from ..opencl import get_runtime
from ..opencl.arrays import read, write
from ..optics.imaging import COVERAGE_FLOOR, assemble
from ..optics.speckle import downsample
from ..scene.camera import Camera
from ..scene.mesh import Mesh
from ..validate import MAX_SAMPLES, MAX_SUPERSAMPLE, InputError
from ..view import RenderResult
from .incoherent import IncoherentImages, grid_bytes
from .optics import SUPERSAMPLE, PupilOptics
from .raster import camera_emitters, raster_bytes
from .recording import PupilFields, intensity_hologram, reconstruct_object_wave

log = logging.getLogger(__name__)


# --- emitters ---------------------------------------------------------------------------------


# --- the object wave on the pupil, and the image ------------------------------------------------


# --- rendering -------------------------------------------------------------------------------

FINE_PIXEL_BYTES = 64  # per fine pixel: the four looks' images, coverage, depth, accumulators
DEVICE_FIELDS = 6  # complex pupil-sized buffers on the device: the layers' sum, FFTs, iris


def render_camera(
    meshes=(),
    camera: Camera = None,
    *,
    points=None,
    samples=16,
    supersample=SUPERSAMPLE,
    pupil_diameter=None,
    exposure=1.0,
    seed=0,
    via="object_wave",
    progress: jobs.Progress = None,
    on_sample=None,
):
    """Render meshes (and bare points) as a camera sees them through its camera hologram.

    The camera hologram is the module docstring's; meshes that move (``Mesh.motion``) are
    averaged over the shutter (motion blur, :func:`.raster.across_shutter`).

    Parameters
    ----------
    meshes : sequence of Mesh
        The scene, in world metres.
    camera : Camera
        The camera; its lens and f-stop set the pupil.
    points : (positions (N, 3) [m], colours (N, 3)), optional
        Bare point emitters.
    samples : int
        Looks with independent random emitter phases, averaged progressively (speckle; the
        'object_wave' and 'hologram' routes).
    supersample : int
        Fine pixels per pixel per axis (the pupil resolves one fine pixel).
    pupil_diameter : float, optional
        [m], default the camera's (lens/f-stop) or, without a lens, the widest whose defocus
        stays within a fine pixel.
    exposure : float
        Radiance to pixel value (1: a surface shows its own colour, as an emission shader of
        strength 1 in Cycles).
    seed : int
        Seeds the emitters' random phases.
    via : {'object_wave', 'incoherent', 'hologram'}
        'object_wave' (looks of the object wave with random phases, the ideal
        reconstruction), 'incoherent' (what those looks converge to, computed exactly by each
        layer's intensity PSF, :mod:`.incoherent`: no speckle, one pass) or 'hologram' (each
        look's object wave recorded as an intensity hologram with an off-axis reference and
        reconstructed).
    progress : callable, optional
        Given the fraction done in [0, 1] between units of work.
    on_sample : callable, optional
        ``on_sample(result, n)`` gets the running result after 1, 2, 4, 8 … looks (once,
        n = 1, for 'incoherent').

    Returns
    -------
    RenderResult
        The view: radiance, alpha and planar depth [m], with ``coverage`` and the optics used.

    Raises
    ------
    InputError
        Where a setting is out of range or the scene is empty, naming what.

    Notes
    -----
    Each emitter is a spherical wave (Eq. 3) through the camera's thin lens (Eq. 24) onto its
    sensor; the 'hologram' route records H = ``|O + R|²`` (Eq. 16) and reconstructs it
    (Eq. 18).

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import Camera, Mesh, look_at, render_camera
    >>> camera = Camera(matrix_world=look_at((0, 0, 0.3), (0, 0, -0.01), up=(0, 1, 0)),
    ...                 resolution=(32, 24), fstop=8.0, focus_distance=0.31)
    >>> triangle = Mesh(vertices=np.array([[-0.01, -0.01, -0.01], [0.01, -0.01, -0.01],
    ...                                    [0.0, 0.01, -0.01]]),
    ...                 triangles=np.array([[0, 1, 2]]), colours=np.ones((3, 3)))
    >>> view = render_camera([triangle], camera, samples=1)
    >>> view.rgb.shape, round(float(view.depth.min()), 2)
    ((24, 32, 3), 0.31)
    """
    if not isinstance(camera, Camera):
        raise InputError(
            f"camera must be a Camera (render_camera needs one); got {type(camera).__name__}"
        )
    validate.choice("via", via, ("incoherent", "object_wave", "hologram"))
    samples = validate.integer("samples", samples, 1, MAX_SAMPLES)
    supersample = validate.integer("supersample", supersample, 1, MAX_SUPERSAMPLE)
    seed = validate.seed(seed)
    exposure = validate.exposure(exposure)
    meshes, points = _meshes(meshes), None if points is None else _points(points)
    fine, (w, h) = camera.supersampled(supersample), camera.resolution
    view = FINE_PIXEL_BYTES * w * h * supersample**2
    # the host's memory before the meshes are projected (a 10^7-vertex mesh took 8 GB and more)
    memory.check_host(f"a {w}x{h} camera view at supersample {supersample}", view)
    if meshes:
        memory.check_host(
            f"rasterizing {sum(len(m.triangles) for m in meshes)} triangles", raster_bytes(meshes)
        )
    optics, em = camera_emitters(
        meshes, points, camera, supersample=supersample, pupil_diameter=pupil_diameter
    )
    rt, pupil = get_runtime(), 8.0 * math.prod(optics.shape)
    # the layers' padded images, else the pupil's fields
    what, held, largest = (
        ("padded images", grid_bytes(optics) + view, 4 * pupil)
        if via == "incoherent"
        else ("fields", DEVICE_FIELDS * pupil + view, pupil)
    )
    memory.check_device(
        rt, f"the {optics.shape[1]}x{optics.shape[0]} pupil's {what}", held, largest
    )
    acc = _Accumulator(camera, optics, exposure)
    if via == "incoherent":
        return _incoherent(rt, em, optics, fine, acc, progress, on_sample)
    fields = PupilFields(rt, em, optics, fine)
    rng = np.random.default_rng(seed)
    for n in range(1, samples + 1):
        phases = rt.to_device(rng.uniform(0, 2 * np.pi, len(em.index)), np.float32)
        images = []
        for f in range(4):
            wave = fields.object_wave(f, phases)
            if via == "hologram":
                write(
                    wave,
                    np.fft.ifftshift(
                        reconstruct_object_wave(intensity_hologram(np.fft.fftshift(read(wave))))
                    ),
                )
            images.append(fields.image(f))
            jobs.report(progress, (n - 1) * 4 + f + 1, samples * 4)
        acc.add(images)
        if on_sample is not None and not n & (n - 1):  # the result costs a few looks' time
            on_sample(acc.result(), n)
    result = acc.result()
    log.info(
        "camera hologram: %d samples, speckle contrast %.3f",
        samples,
        result.info["speckle_contrast"],
    )
    return result


def _incoherent(
    rt, em, optics: PupilOptics, fine: Camera, acc: _Accumulator, progress, on_sample
) -> RenderResult:
    acc.add_expected(*IncoherentImages(rt, em, optics, fine).images(progress))
    result = acc.result()
    if on_sample is not None:
        on_sample(result, 1)
    log.info("camera hologram: the looks' limit (incoherent emitters)")
    return result


def _meshes(meshes) -> list:
    """``meshes`` (a Mesh or a sequence of them) as a list, else :class:`InputError`."""
    try:
        out = [meshes] if isinstance(meshes, Mesh) else list(meshes)
    except TypeError:
        out = [meshes]
    if not all(isinstance(m, Mesh) for m in out):
        raise InputError(
            f"meshes must be a Mesh or a sequence of Mesh; got {type(meshes).__name__}"
        )
    return out


def _points(points):
    """(positions (N, 3) [m], colours (N, 3)) of ``points``, finite, colours >= 0."""
    allowed = "(positions (N, 3) [m], colours (N, 3)), finite, colours >= 0"
    try:
        positions, colours = points
        pos = np.asarray(positions, np.float64).reshape(-1, 3)
        col = np.asarray(colours, np.float64).reshape(len(pos), 3)
    except (TypeError, ValueError):
        raise InputError(f"points must be {allowed}") from None
    if not (np.isfinite(pos).all() and np.isfinite(col).all()) or (col < 0).any():
        raise InputError(f"points must be {allowed}; they hold NaN, infinite or negative values")
    return pos, col


class _Accumulator:
    """The running average of the looks, and the speckle contrast of that average."""

    def __init__(self, camera: Camera, optics: PupilOptics, exposure):
        self.camera, self.optics, self.exposure, self.n = camera, optics, exposure, 0
        self.rgb = self.cross = self.coverage = 0
        self.lum = self.lum2 = 0
        self.exact = False

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

    def add_expected(self, rg, bz, cross):
        """The looks' expectation (:mod:`.incoherent`): no spread between looks is left."""
        self.rgb = np.maximum(np.stack([rg.real, rg.imag, bz.real], -1), 0)
        self.coverage = np.maximum(bz.imag, 0)
        self.cross, self.n, self.exact = cross, 1, True

    def result(self) -> RenderResult:
        o, n, s = self.optics, self.n, self.optics.supersample
        colour, alpha, depth, radiance, coverage = assemble(
            self.rgb / n,
            self.coverage / n,
            self.cross,
            camera=self.camera,
            supersample=s,
            wavelengths=(o.wavelength, o.depth_wavelength),
            centre=o.centre,
            exposure=self.exposure,
            soft=self.exact,
        )
        mean = self.lum / n
        spread = np.sqrt(np.maximum(self.lum2 / n - mean**2, 0) / max(n - 1, 1))
        solid = alpha >= 1
        contrast = (
            0.0
            if self.exact
            else float(np.median(spread[solid] / np.maximum(mean[solid], 1e-30)))
            if solid.any() and n > 1
            else float("nan")
        )
        info = {
            "samples": n,
            "speckle_contrast": contrast,
            "aperture_m": o.diameter,
            "focus_m": o.focus,
            "wavelengths_m": [o.wavelength, o.depth_wavelength],
            "layers": len(o.layers),
            "pupil_samples": list(o.shape),
            "resolution_limit_px": 1 / s,
            "exposure": self.exposure,
        }
        return RenderResult(
            rgb=colour, alpha=alpha, depth=depth, info=info, coverage=coverage, radiance=radiance
        )
