"""The camera hologram's images as the looks converge: the emitters as mutually incoherent
sources (Sect. VII-E), computed exactly instead of averaged over random phases.

A look's image is A(u) = Σ_e S_e·p_l(u − u_e): each emitter's weight S_e = a_e·exp(i(kR_e + φ_e))
times its layer's coherent point spread function p_l, the FFT of the pupil (iris, layer
curvature, thin lens). Averaged over independent uniform phases φ_e, the cross terms vanish:

    E|A|² = Σ_e a_e²·|p_l(u − u_e)|²,
    E[A₁·A₂*] = Σ_e a_e·b_e·e^{i(k₁−k₂)R_e}·p₁(u − u_e)·p₂*(u − u_e),

so the colour and coverage images are each layer's emitter map convolved with the intensity
PSF |p_l|² (Goodman's incoherent imaging), and the depth pair's cross image is the map of
e^{i(k₁−k₂)R} convolved with the cross PSF p₁·p₂*. Both are cyclic convolutions on the pupil's
2× padded spectrum grid, where the intensity (twice the coherent band) is sampled alias-free:
per layer, two PSFs, their two transfer functions and three emitter maps are transformed (the
colours packed as R + iG and B + i·coverage; a map fills only the even bins of the 2x grid, so
its transform there is that of the pupil-sized map, tiled), summed in the frequency domain,
and transformed back once: zero-padded 1.5x there and read at each fine pixel by the ES
kernel (6 taps, its β for 1.5x oversampling: a type-2 non-uniform FFT, ~1e-4), as the intensity
fills the 2x grid's band. The result is what infinitely many looks give: no speckle, no noise at the silhouettes,
and one pass.
"""

from __future__ import annotations

import math

import numpy as np
from numpy import int32

from .. import jobs
from ..opencl import associated
from ..opencl.arrays import by_rows, empty, fill, read
from ..opencl.kernel import BUFFER, kernel
from ..optics import imaging
from ..optics.imaging import ES_TABLE, IRIS_TAPER
from ..propagation.grid import embedded
from ..propagation.tilt import cached_array, es_table, es_transform
from ..scene.camera import Camera
from . import recording
from .optics import READ_PADDING, PupilOptics, read_shape
from .raster import Emitters

PROGRAM = associated(__file__)
# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
SCATTER_VALUES = kernel(PROGRAM, "scatter_values", M=BUFFER, idx=BUFFER, val=BUFFER,
                        first=int32)
# fmt: on
PSF_PRODUCTS = kernel(PROGRAM, "psf_products", p1=BUFFER, p2=BUFFER)
# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
MULTIPLY_TILED = kernel(PROGRAM, "multiply_tiled", acc=BUFFER, m=BUFFER, k=BUFFER, h=int32,
                        w=int32, first=int32)
EMBED_DEAPODIZED = kernel(PROGRAM, "embed_deapodized", Q=BUFFER, H=int32, W=int32, A=BUFFER,
                          h=int32, w=int32, ay=BUFFER, ax=BUFFER)
# fmt: on

# complex buffers of the padded grid on the device: 3 accumulators, 2 PSFs, and a map of a quarter
# of its size
BUFFERS = 5.25
# the read (its grid padded by READ_PADDING) with these taps and this β per tap (FINUFFT's for 1.5x)
READ_TAPS, READ_BETA = 6, 2.03


class IncoherentImages:
    """Device state of the incoherent route for one render (module docstring)."""

    def __init__(self, rt, em: Emitters, optics: PupilOptics, camera_fine: Camera):
        self.rt, self.em, self.optics = rt, em, optics
        h, w = optics.shape
        self.shape = (2 * h, 2 * w)
        self.options = rt.real_options + (f"-DTAPS={READ_TAPS}", f"-DES_TABLE={ES_TABLE}")
        self.index = rt.to_device(em.index, np.int32)
        self.maps = [rt.to_device(m, np.complex64) for m in _emitter_maps(em, optics)]
        self.acc = [empty(rt, self.shape) for _ in self.maps]
        self.psf = [empty(rt, self.shape) for _ in range(2)]
        self.map = empty(rt, (h, w))
        self.pupil, self.ones = empty(rt, (h, w)), empty(rt, (h, w))
        self.flat = [rt.to_device(np.ones(n), np.float32) for n in (h, w)]
        self.read_shape = read_shape(self.shape)
        self.read = empty(rt, self.read_shape)
        self.deapodize = [
            rt.to_device(1 / es_transform(_signed(n) / m, READ_TAPS, READ_BETA), np.float32)
            for n, m in zip(self.shape, self.read_shape)
        ]
        self.es = cached_array(rt, "es-table", es_table, READ_TAPS, READ_BETA)
        alpha, beta, _ = camera_fine.direction_cosines()
        # each fine pixel's direction in samples of the read grid (2·α/b on the padded one)
        self.u = rt.to_device(
            2 * alpha / optics.bin * self.read_shape[1] / self.shape[1], np.float32
        )
        self.v = rt.to_device(
            2 * beta / optics.bin * self.read_shape[0] / self.shape[0], np.float32
        )
        self.pixels = empty(rt, alpha.shape)
        # E|A|² in the looks' normalisation (|A|² / (N·Σw²), recording.py), and the 1/N of
        # the unnormalised inverse FFT
        iris = imaging.iris_weights((h, w), optics.pitch(), optics.diameter)
        self.scale = 1 / (h * w * float(np.sum(iris**2)) * math.prod(self.shape))

    def images(self, progress: jobs.Progress = None) -> list[np.ndarray]:
        """(R + iG, B + i·coverage, cross) at the fine pixels: complex64 (H, W) each."""
        rt, em = self.rt, self.em
        h, w = self.optics.shape
        layers = [
            (z, int(em.starts[i]), int(em.starts[i + 1]))
            for i, z in enumerate(self.optics.layers)
            if em.starts[i] < em.starts[i + 1]
        ]
        if not layers:
            for acc in self.acc:
                fill(rt, acc, 0)
        for done, (z, first, last) in enumerate(layers):
            self._transfer_functions(z)
            for values, acc, k in zip(self.maps, self.acc, (0, 0, 1)):
                # the map on the (h, w) grid: on the 2x grid it fills the even bins only, and
                # its transform there is this one tiled (multiply_tiled)
                fill(rt, self.map, 0)
                SCATTER_VALUES.launch(
                    rt,
                    (last - first,),
                    options=self.options,
                    M=self.map,
                    idx=self.index,
                    val=values,
                    first=first,
                )
                rt.fft.forward(self.map)
                MULTIPLY_TILED.launch(
                    rt,
                    by_rows(self.shape),
                    options=self.options,
                    acc=acc,
                    m=self.map,
                    k=self.psf[k],
                    h=h,
                    w=w,
                    first=done == 0,
                )
            jobs.report(progress, done + 1, len(layers) + 1)
        out = []
        corners = tuple(embedded(n, m) for n, m in zip(self.shape, self.read_shape))
        (read_h, read_w), (acc_h, acc_w) = self.read_shape, self.shape
        for acc in self.acc:
            rt.fft.clear(self.read, corners)
            EMBED_DEAPODIZED.launch(
                rt,
                by_rows(self.shape),
                options=self.options,
                Q=self.read,
                H=read_h,
                W=read_w,
                A=acc,
                h=acc_h,
                w=acc_w,
                ay=self.deapodize[0],
                ax=self.deapodize[1],
            )
            rt.fft.backward(self.read, nonzero=corners)
            imaging.READ_PIXELS.launch(
                rt,
                (self.pixels.size,),
                options=self.options,
                out=self.pixels,
                A=self.read,
                h=read_h,
                w=read_w,
                u=self.u,
                v=self.v,
                scale=self.scale,
                es=self.es,
            )
            out.append(read(self.pixels))
        jobs.report(progress, 1, 1)
        return out

    def _transfer_functions(self, z: float) -> None:
        """psf[0] ← F[|p₁|²] and psf[1] ← F[p₁·p₂*] of the layer at planar distance z [m]."""
        rt, o = self.rt, self.optics
        h, w = o.shape
        corners = (embedded(h, 2 * h), embedded(w, 2 * w))
        fill(rt, self.ones, 1)
        for psf, lam in zip(self.psf, (o.wavelength, o.depth_wavelength)):
            dy, dx = o.pitch(lam)
            k = 2 * np.pi / lam
            fill(rt, self.pupil, 0)
            recording.ADD_LAYER.launch(
                rt,
                by_rows((h, w)),
                options=self.options,
                P=self.pupil,
                u=self.ones,
                h=h,
                w=w,
                dy=dy,
                dx=dx,
                k=k,
                z=z,
            )
            rt.fft.clear(psf, corners)
            imaging.window(
                rt,
                psf,
                self.pupil,
                (h, w),
                pitch=(dy, dx),
                radius=o.diameter / 2 * lam / o.wavelength,
                taper=IRIS_TAPER,
                k=k,
                focus=o.focus or 0.0,
                apodization=self.flat,
                options=self.options,
            )
            rt.fft.forward(psf, nonzero=corners)
        PSF_PRODUCTS.launch(
            rt, (self.psf[0].size,), options=self.options, p1=self.psf[0], p2=self.psf[1]
        )
        for psf in self.psf:
            rt.fft.forward(psf)


def _signed(n: int) -> np.ndarray:
    """Signed indices 0, 1, …, −1 of an n-sample FFT-order axis."""
    return np.fft.fftfreq(n) * n


def _emitter_maps(em: Emitters, optics: PupilOptics) -> list[np.ndarray]:
    """The emitters' weights in the three images: intensities R + iG and B + i·coverage, and
    the cross pair's a·b·e^{i(k₁−k₂)R} (the phase folded in float64, as kR is ~10⁶ rad)."""
    col = np.asarray(em.colour, np.float64)
    cov = np.asarray(em.coverage, np.float64)
    dk = 2 * np.pi * (1 / optics.wavelength - 1 / optics.depth_wavelength)
    cross = (
        np.sqrt(col).sum(1) * np.sqrt(cov) * np.exp(1j * np.remainder(dk * em.distance, 2 * np.pi))
    )
    return [col[:, 0] + 1j * col[:, 1], col[:, 2] + 1j * cov, cross]


def grid_bytes(optics: PupilOptics) -> float:
    """Device bytes of the route's buffers for ``optics``."""
    return (BUFFERS + READ_PADDING**2) * 8.0 * 4 * math.prod(optics.shape)
