"""The pupil → image stage both renderers share (facts: a plate's view is the camera
hologram's image of the plate's field carried to the pupil).

- :class:`PupilImage`: a field sampled on the entrance pupil, in FFT order, through the iris (a
  raised-cosine rim against ringing, Fig. 9) and the thin lens of Eq. 24, deapodized and
  zero-padded 2×; its angular spectrum is read at each pixel's direction cosines (Eq. 22) by
  the ES kernel of a type-2 non-uniform FFT. A pixel whose direction lies beyond the pupil
  grid's band reads zero (no light of that direction was sampled).
- :func:`assemble`: the view from the colour, coverage and depth-pair images at the fine
  pixels: radiance and coverage box-filtered to pixels, alpha from the coverage, the colour as
  radiance over coverage (both share their speckle, which this divides out on surfaces of one
  colour), and the depth from the two-wavelength phase (Eq. 26–30).
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np
from numpy import float32, int32

from ..opencl import associated
from ..opencl.arrays import by_rows, empty, read
from ..opencl.kernel import BUFFER, REAL, kernel
from ..propagation import grid
from ..propagation.tilt import cached_array, es_profile, es_table
from ..scene.camera import Camera
from ..view import BACKGROUND_DEPTH
from .depth import from_cross_spectrum
from .speckle import box_mean, downsample

PROGRAM = associated(__file__)
# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
PUPIL_WINDOW = kernel(PROGRAM, "pupil_window", Q=BUFFER, P=BUFFER, h=int32, w=int32,
                      dy=float32, dx=float32, radius=float32, taper=float32, k=float32,
                      f=float32, dy_apod=BUFFER, dx_apod=BUFFER, plane=int32)
READ_PIXELS = kernel(PROGRAM, "read_pixels", out=BUFFER, A=BUFFER, h=int32, w=int32, u=BUFFER,
                     v=BUFFER, scale=float32, es=BUFFER)
READ_FOLDED = kernel(PROGRAM, "read_folded", power=BUFFER, cross=BUFFER, fine=BUFFER,
                     A=BUFFER, h=int32, w=int32, W=int32, H=int32, s=int32, t0=REAL, dt=REAL,
                     r0=REAL, dr=REAL, ca=REAL, cb=REAL, bin2=REAL, scale=BUFFER, es=BUFFER)
# fmt: on
TAPS, ES_TABLE = 4, 4096  # the image read: 4 taps at 2x padding agree with 6 to 100 dB PSNR
IRIS_TAPER = 0.1  # the iris's raised-cosine rim, a fraction of its radius
COVERAGE_EDGE = (0.25, 0.75)  # coverage mapped to alpha 0 … 1 (0.5: the geometric edge)
COVERAGE_FLOOR = 0.05  # the colour is radiance / coverage where coverage exceeds this
COVERAGE_RADIUS = 1  # a speckle minimum inside a surface: the (2r+1)² pixels' mean
SOFT_FLOOR = 1e-3  # soft alpha: coverage below this is clear, within this of 1 opaque
SPECTRA = "pupil-spectra"  # the workspace of a stack of padded spectra (P, 2h, 2w)


def iris_weights(shape, pitch, diameter, taper=IRIS_TAPER) -> np.ndarray:
    """The iris's transmission (h, w) on a pupil grid of ``shape`` in FFT order, samples
    ``pitch`` (dy, dx) [m] apart: 1 inside (1 − taper)·radius, a raised cosine to 0 at the
    radius ``diameter``/2 [m] (what the ``pupil_window`` kernel applies)."""
    (h, w), (dy, dx) = shape, pitch
    y, x = grid.signed_indices(h)[:, None] * dy, grid.signed_indices(w)[None, :] * dx
    rho, radius = np.hypot(x, y), diameter / 2
    inner = (1 - taper) * radius
    edge = 0.5 * (1 + np.cos(np.pi * np.clip(rho - inner, 0, None) / max(radius - inner, 1e-300)))
    return np.where(rho >= radius, 0.0, np.where(rho > inner, edge, 1.0))


@functools.lru_cache(maxsize=32)
def iris_power(shape, pitch, diameter, taper=IRIS_TAPER) -> float:
    """Σ w² of :func:`iris_weights` (the views' calibration), once for each pupil grid: a
    shot's frames share it."""
    return float(np.sum(iris_weights(shape, pitch, diameter, taper) ** 2))


class PupilImage:
    """The image a pupil field forms at a camera's (fine) pixels.

    rt : the OpenCL runtime
    shape : (h, w) pupil samples; the pupil field is passed in FFT order (sample (r, c) at the
        signed indices (r or r − h, c or c − w) from the optical axis)
    bin : the spectrum's bin spacing in direction cosine, λ/(w·dx) = λ/(h·dy)
    camera : the camera whose pixels are read (its resolution is the fine one)
    centre : (α, β) the direction cosines of the spectrum's centre bin (default the axis): a
        pupil field demodulated by exp(−ik(α·x + β·y)) holds the directions around it
    """

    def __init__(self, rt, shape, *, bin: float, camera: Camera, centre=(0.0, 0.0)):
        self.rt = rt
        h, w = self.shape = tuple(shape)
        self.apod = [es_profile(rt, n, TAPS, inverse=True) for n in (h, w)]
        self.es = cached_array(rt, "es-table", es_table, TAPS)
        self.camera, self.bin, self.centre = camera, bin, tuple(map(float, centre))
        self.options = rt.real_options + (f"-DTAPS={TAPS}", f"-DES_TABLE={ES_TABLE}")
        self._pixels = None

    def _directions(self):
        """(u, v, pixels): each fine pixel's bin (device float32) and its image's buffer, made
        on the first :meth:`image` (:meth:`fold` finds the bins in its kernel)."""
        if self._pixels is None:
            alpha, beta, _ = self.camera.direction_cosines()
            self._pixels = (
                self.rt.to_device(2 * (alpha - self.centre[0]) / self.bin, np.float32),
                self.rt.to_device(2 * (beta - self.centre[1]) / self.bin, np.float32),
                empty(self.rt, alpha.shape),
            )
        return self._pixels

    def image(
        self, pupil, *, pitch, diameter, focus=None, taper=IRIS_TAPER, lens_k=None, scale=1.0
    ) -> np.ndarray:
        """The complex image (H, W) of ``pupil`` (device, (h, w), FFT order, samples
        ``pitch`` = (dy, dx) [m] apart): the iris of ``diameter`` [m] with its rim ``taper``
        (0: a hard edge), the thin lens focused at ``focus`` [m] (None: none) whose wave number
        is ``lens_k`` [rad/m], and the spectrum read at the pixels times ``scale``."""
        rt = self.rt
        h, w = self.shape
        self._spectrum(
            pupil, pitch=pitch, diameter=diameter, focus=focus, taper=taper, lens_k=lens_k
        )
        u, v, pixels = self._directions()
        READ_PIXELS.launch(
            rt,
            (pixels.size,),
            options=self.options,
            out=pixels,
            A=self._padded(),
            h=2 * h,
            w=2 * w,
            u=u,
            v=v,
            scale=scale,
            es=self.es,
        )
        return read(pixels)

    def _padded(self):
        """The (2h, 2w) spectrum :meth:`image` reads (only it: :meth:`fold` has a stack)."""
        h, w = self.shape
        return self.rt.scratch("pupil-padded", (2 * h, 2 * w))

    def _spectrum(self, pupil, *, pitch, diameter, focus, taper, lens_k) -> None:
        """:meth:`_padded`: the spectrum of ``pupil`` through the iris and the lens
        (:meth:`image`)."""
        h, w = self.shape
        padded = self._padded()
        corners = (grid.embedded(h, 2 * h), grid.embedded(w, 2 * w))
        self.rt.fft.clear(padded, corners)
        window(
            self.rt,
            padded,
            pupil,
            (h, w),
            pitch=pitch,
            radius=diameter / 2,
            taper=taper,
            k=lens_k or 0.0,
            focus=focus or 0.0,
            apodization=self.apod,
            options=self.options,
        )
        self.rt.fft.forward(padded, nonzero=corners)

    def fold(
        self,
        pupils,
        channels,
        *,
        same,
        partner,
        supersample,
        diameter,
        focus=None,
        taper=IRIS_TAPER,
        keep_fine=False,
    ) -> list:
        """Each look's images folded to the camera's pixels as they are read (speckle
        reduction, Sect. VII-E): a list of :class:`Folded`, one per look. What a view composes
        is linear in the fine pixels' intensities and the depth pair's cross image, so one
        kernel reads every look's spectra at each fine pixel (its bins and ES weights found
        once for them all) and keeps only the pixels' means: no fine image is stored unless
        ``keep_fine`` asks for them (a composition by maximum, a depth by the brightest look).

        pupils : device (P, h, w), FFT order: the looks' channels, look after look
        channels : {channel: (pitch (dy, dx) [m], lens wave number [rad/m], scale)}, a look's
            planes in order
        same, partner : the colour channels at the depth pair's first wavelength (their sum is
            u1) and the depth channel (u2; None: none)
        diameter, focus, taper : the iris [m], the lens's focus [m] (None: none), its rim
        """
        rt, (h, w), s = self.rt, self.shape, supersample
        names = list(channels)
        planes = pupils.shape[0]
        looks = planes // len(names)
        cols, rows = (n // s for n in self.camera.resolution)
        spectra = rt.workspace(SPECTRA, (planes, 2 * h, 2 * w))
        scales = rt.to_device(
            np.array([channels[names[p % len(names)]][2] for p in range(planes)]), np.float32
        )
        corners = (grid.embedded(h, 2 * h), grid.embedded(w, 2 * w))
        rt.fft.clear(spectra, corners)
        for p in range(planes):  # each plane windowed into its spectrum's corners ...
            pitch, lens_k, _ = channels[names[p % len(names)]]
            window(
                rt,
                spectra,
                pupils,
                (h, w),
                pitch=pitch,
                radius=diameter / 2,
                taper=taper,
                k=lens_k,
                focus=focus or 0.0,
                apodization=self.apod,
                options=self.options,
                plane=p,
            )
        rt.fft.forward(spectra, nonzero=corners)  # ... and every plane transformed in place
        pair = (
            (sum(1 << names.index(c) for c in same), names.index(partner))
            if partner is not None
            else (0, -1)
        )
        options = self.options + (
            f"-DPLANES={planes}",
            f"-DLOOK_PLANES={len(names)}",
            f"-DSAME={pair[0]}",
            f"-DPARTNER={pair[1]}",
            f"-DKEEP_FINE={int(keep_fine)}",
        )
        power = rt.scratch("pixel-power", (planes, rows, cols), np.float32)
        cross = rt.scratch("pixel-cross", (looks, rows, cols))
        # without KEEP_FINE the kernel never writes ``fine``: any buffer fills the argument
        fine = rt.scratch("pixel-fine", (planes, rows * s, cols * s)) if keep_fine else cross
        t0, dt, r0, dr = self.camera.tangent_steps()
        ca, cb = self.centre
        READ_FOLDED.launch(
            rt,
            (cols, rows),
            options=options,
            power=power,
            cross=cross,
            fine=fine,
            A=spectra,
            h=2 * h,
            w=2 * w,
            W=cols,
            H=rows,
            s=s,
            t0=t0,
            dt=dt,
            r0=r0,
            dr=dr,
            ca=ca,
            cb=cb,
            bin2=2 / self.bin,
            scale=scales,
            es=self.es,
        )
        power, cross = read(power), read(cross)
        fine = read(fine) if keep_fine else None
        return [
            Folded(
                {c: power[look * len(names) + m] for m, c in enumerate(names)},
                cross[look] if partner is not None else None,
                {c: fine[look * len(names) + m] for m, c in enumerate(names)}
                if keep_fine
                else None,
            )
            for look in range(looks)
        ]


class Folded(NamedTuple):
    """One look's images at the camera's pixels (:meth:`PupilImage.fold`).

    power : channel → (H, W) float32, the mean |A|² over each pixel's s×s fine pixels
    cross : (H, W) complex64, the mean of u1·conj(u2) of the depth pair (u1 the sum of the
        colours at its first wavelength), or None without the partner
    fine : channel → (H·s, W·s) complex64, the fine images themselves where asked for, or None
    """

    power: dict
    cross: np.ndarray | None
    fine: dict | None


def fold_images(images, *, same, partner, supersample, keep_fine=False) -> Folded:
    """One look's fine images (channel → (H·s, W·s) complex NumPy arrays) at the camera's
    pixels, as :meth:`PupilImage.fold` folds them on the device: for images read one by one
    (a full-band plate's channels, each on its own wavelength's bins)."""
    s = supersample
    cross = (
        None
        if partner is None
        else downsample(sum(images[c] for c in same) * np.conj(images[partner]), s).astype(
            np.complex64
        )
    )
    return Folded(
        {c: downsample(np.abs(a) ** 2, s).astype(np.float32) for c, a in images.items()},
        cross,
        dict(images) if keep_fine else None,
    )


def window(
    rt, padded, pupil, shape, *, pitch, radius, taper, k, focus, apodization, options, plane=0
) -> None:
    """``pupil`` (device, ``shape`` (h, w), FFT order) through the iris (``radius`` [m], its rim
    ``taper``), the thin lens (wave number ``k`` [rad/m], focused at ``focus`` [m], 0: none)
    and the ``apodization`` (per row, per column; device float32) into the corners of
    ``padded`` (2h, 2w), FFT order; ``pitch`` (dy, dx) [m]. The rest of ``padded`` is left
    as it is (``rt.fft.clear`` with the corners first). ``plane``: of stacks (P, h, w) and
    (P, 2h, 2w) given as ``pupil`` and ``padded``."""
    (h, w), (dy, dx) = shape, pitch
    PUPIL_WINDOW.launch(
        rt,
        by_rows(shape),
        options=options,
        Q=padded,
        P=pupil,
        h=h,
        w=w,
        dy=dy,
        dx=dx,
        radius=radius,
        taper=taper,
        k=k,
        f=focus,
        dy_apod=apodization[0],
        dx_apod=apodization[1],
        plane=plane,
    )


def assemble(
    radiance,
    coverage,
    cross,
    *,
    camera: Camera,
    supersample: int,
    wavelengths,
    centre: float,
    exposure: float,
    soft: bool = False,
):
    """The view from the fine pixels' images: ``radiance`` (H·s, W·s, C), ``coverage``
    (H·s, W·s) (1 where surfaces cover a fine pixel), ``cross`` (H·s, W·s) the depth pair's
    u1·conj(u2) at ``wavelengths`` (λ1, λ2) [m] unwrapped around ``centre`` [m], ``exposure``
    radiance to pixel value. Returns (colour, alpha, planar depth [m], radiance, coverage) at
    the camera's pixels (radiance times the exposure).

    ``soft`` (images without speckle: the looks' limit): alpha is the coverage itself (0
    below ``SOFT_FLOOR``, 1 within it of 1, where a uniform surface's coverage ripples by
    3e-5), which the pupil has blurred as it blurs the colour, so a defocused or moving edge
    fades over the width Blender's raster gives it and the pass premultiplied is the
    radiance (within 0.2 %). Else
    (speckled looks) alpha ramps from coverage 0.25 to 0.75, and a speckle minimum inside a
    surface leaves no hole."""
    s, f32 = supersample, np.float32
    radiance = downsample(radiance, s)
    coverage = downsample(coverage, s)
    # each step in place on an image of the pixels' own: a 1280×720 view's composition is
    # passes over a few MB, which the memory's speed, not the arithmetic, sets
    if soft:
        alpha = np.clip((coverage - SOFT_FLOOR) / (1 - 2 * SOFT_FLOOR), 0, 1).astype(f32)
        floor = SOFT_FLOOR
    else:
        lo, hi = COVERAGE_EDGE
        # a pixel's coverage, or its neighbourhood's mean where higher: a speckle minimum
        # inside a surface leaves no hole, while a straight edge keeps its half-way crossing
        solid = box_mean(coverage, COVERAGE_RADIUS)
        np.maximum(solid, coverage, out=solid)
        solid -= lo
        solid *= 1 / (hi - lo)
        alpha = np.clip(solid, 0, 1, out=solid).astype(f32, copy=False)
        floor = COVERAGE_FLOOR
    # the surfaces' own colour: radiance over coverage (what the pass stores premultiplied
    # by alpha); the colour and the partner share their speckle, which this divides out
    per_cover = np.maximum(coverage, floor)
    np.divide(per_cover.dtype.type(exposure), per_cover, out=per_cover)
    colour = np.empty(radiance.shape, np.result_type(radiance, per_cover))
    for c in range(radiance.shape[-1]):  # a channel at a time: broadcast over the last axis,
        np.multiply(radiance[..., c], per_cover, out=colour[..., c])  # numpy loops by 3
    depth = from_cross_spectrum(
        downsample(cross, s), wavelengths=tuple(wavelengths), centre=centre
    ).astype(f32, copy=False)
    depth /= _ray_per_depth(camera)  # planar: along the view axis, as Blender's Depth pass
    np.copyto(depth, f32(BACKGROUND_DEPTH), where=alpha <= 0)
    return (
        colour.astype(f32, copy=False),
        alpha,
        depth,
        (radiance * f32(exposure)).astype(f32, copy=False),
        coverage.astype(f32, copy=False),
    )


def _ray_per_depth(camera: Camera) -> np.ndarray:
    """(H, W) float32: a pixel's distance along its ray per unit of planar depth,
    √(1 + t_x² + t_y²) of its centre's view tangents."""
    w, h = camera.resolution  # the tangents by row and by column, broadcast
    tx, ty = camera.pixel_tangents(
        rows=np.arange(h)[:, None] + 0.5, cols=np.arange(w)[None, :] + 0.5
    )
    ratio = (1 + tx * tx).astype(np.float32) + (ty * ty).astype(np.float32)
    return np.sqrt(ratio, out=ratio)
