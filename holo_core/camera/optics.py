"""The camera hologram's optics: the pupil's wavelength, its sampling and its depth layers.

- Optics (:func:`choose_optics`). A pupil of diameter D resolves λ/D; λ = D·Δ/s makes that
  one *fine pixel* (Δ the pixel angle, s the supersampling). A lens keeps its real aperture
  (lens/f-stop) and focus, so the defocus is the camera's. Without one, the pupil is the
  largest whose defocus over the emitters' depth range stays within a fine pixel.
- Bins. The pupil fills its FFT window (h·dy = w·dx = D): its spectrum's bins lie b = Δ/s
  apart in direction cosine, each bin one direction of arrival, covering the field of view
  and a margin for blur.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from .. import validate
from ..optics.depth import DEPTH_MARGIN, partner_wavelength
from ..optics.pupil import Pupil, defocus_limited_diameter
from ..propagation import grid
from ..scene.camera import Camera

log = logging.getLogger(__name__)
SUPERSAMPLE = 2  # fine pixels per pixel (per axis): the pupil resolves one fine pixel
# a layer's largest curvature error at the pupil's rim [rad]: a quarter wave, Rayleigh's depth of
# focus
LAYER_PHASE = math.pi / 2
MAX_LAYERS = 512
EDGE_BINS = 8  # bins beyond the field of view and its blur: the read's taps and a guard
# the incoherent route's images' grid (twice the pupil's) is padded by this much for the ES read
READ_PADDING = 1.5


@dataclass(frozen=True, slots=True, kw_only=True)
class PupilOptics:
    """The camera hologram's optics.

    wavelength, depth_wavelength : λ1 of the colour channels and λ2 = ε·λ1 of the depth partner [m]
    pupil : the entrance pupil: its diameter D [m] and the planar distance in focus [m] (a thin
        lens, Eq. 24): the camera's, or for a camera without depth of field the middle of the
        emitters' depth range in 1/z
    supersample : s, fine pixels per pixel per axis
    bin : direction-cosine spacing of the spectrum's bins (b = Δ/s)
    shape : (h, w) pupil samples = spectrum bins
    layers : planar distances z_l [m] of the depth layers, nearest first
    depth_range : (near, far) planar depths [m] of the emitters
    centre : the ray distance [m] the depth pair's phase is unwrapped around (Eq. 30)
    """

    wavelength: float
    depth_wavelength: float
    pupil: Pupil
    supersample: int
    bin: float
    shape: tuple
    layers: tuple
    depth_range: tuple
    centre: float

    @property
    def diameter(self) -> float:
        """The pupil's diameter D [m]."""
        return self.pupil.diameter

    @property
    def focus(self) -> float | None:
        """The planar distance in focus [m]."""
        return self.pupil.focus

    def pitch(self, wavelength=None) -> tuple[float, float]:
        """(dy, dx) [m] of the pupil's samples at ``wavelength`` (default λ1): the bins stay
        in the same directions, so the pupil scales with λ."""
        lam = wavelength or self.wavelength
        h, w = self.shape
        return lam / (h * self.bin), lam / (w * self.bin)

    def describe(self) -> str:
        h, w = self.shape
        lens = f"focus {self.focus:.4g} m" if self.focus else "no lens"
        return (
            f"camera hologram {w}x{h} on a {self.diameter * 1e3:.3g} mm pupil ({lens}), "
            f"λ = {self.wavelength:.4g} m (depth λ2 = {self.depth_wavelength:.6g} m), "
            f"{len(self.layers)} depth layers, {self.supersample}x supersampling"
        )


def choose_optics(
    camera: Camera, depth_range, *, supersample=SUPERSAMPLE, pupil_diameter: float | None = None
) -> PupilOptics:
    """Optics for ``camera`` and emitters at planar depths ``depth_range`` (near, far) [m]
    (module docstring). ``pupil_diameter`` [m] overrides the pupil's diameter."""
    s = validate.integer("supersample", supersample, 1)
    near, far = (validate.positive("depth_range", d, "m") for d in depth_range)
    near, far = min(near, far), max(near, far)
    b = camera.pixel_angle() / s
    alpha, beta, gamma = camera.supersampled(s).direction_cosines()
    if camera.fstop is not None:
        focus, diameter = camera.focus_distance, camera.aperture_diameter
    else:  # a pinhole: the largest pupil defocused by one fine pixel, at most f/1
        diameter, focus = defocus_limited_diameter(b, near, far)
        diameter = min(diameter, camera.lens * 1e-3)
    if pupil_diameter is not None:
        diameter = validate.positive("pupil_diameter", pupil_diameter, "m")
    lam = diameter * b
    blur = diameter * max(abs(1 / near - 1 / focus), abs(1 / far - 1 / focus))
    margin = math.ceil(blur / b) + EDGE_BINS
    shape = tuple(
        grid.next_fast_len(2 * (math.ceil(np.abs(a).max() / b) + margin)) for a in (beta, alpha)
    )
    step = 16 * LAYER_PHASE * lam / (2 * math.pi * diameter**2)  # layer spacing in 1/z
    n = max(1, math.ceil((1 / near - 1 / far) / step))
    if n > MAX_LAYERS:
        validate.warn_sampling(
            f"the emitters' depth range needs {n} layers at this aperture; "
            f"using {MAX_LAYERS} (defocus phase error up to "
            f"{LAYER_PHASE * n / MAX_LAYERS:.2g} rad)"
        )
        n = MAX_LAYERS
    inv = 1 / far + (np.arange(n) + 0.5) * (1 / near - 1 / far) / n
    farthest = far / float(gamma.min())  # the longest ray to the far depth
    depth_half = DEPTH_MARGIN * max(farthest - near, lam) / 2
    optics = PupilOptics(
        wavelength=lam,
        depth_wavelength=partner_wavelength(lam, depth_half),
        pupil=Pupil(diameter=diameter, focus=focus),
        supersample=s,
        bin=b,
        shape=shape,
        layers=tuple(sorted(1 / inv)),
        depth_range=(near, far),
        centre=(near + farthest) / 2,
    )
    log.info("optics: %s", optics.describe())
    return optics


def read_shape(shape) -> tuple[int, int]:
    """The incoherent route's read grid (rows, cols) [samples]: its images' grid ``shape``
    (rows, cols) [samples] padded by READ_PADDING to fast FFT sizes."""
    return tuple(grid.next_fast_len(math.ceil(READ_PADDING * n)) for n in shape)


def transform_lengths(optics: PupilOptics, speckle: str = "EXACT") -> tuple[int, ...]:
    """The lengths [samples] of the FFTs a camera pass with ``optics`` transforms, each once (what its
    FFT plans are measured for the first time: :mod:`holo_core.estimate`): the pupil's grid
    (h, w) and its images' twice as fine; with ``speckle`` 'EXACT' (the incoherent route)
    the images' read grid too."""
    h, w = optics.shape
    shapes = [(h, w), (2 * h, 2 * w)]
    if speckle == "EXACT":
        shapes.append(read_shape((2 * h, 2 * w)))
    return tuple(dict.fromkeys(n for shape in shapes for n in shape))
