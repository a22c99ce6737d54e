"""The camera hologram's object wave on the pupil, and the paper's intensity hologram of it.

- Object wave (:func:`object_wave`). By depth layers: O = Σ_l exp(ik(√(ρ²+z_l²) − z_l))·
  F⁻¹[S_l], where S_l holds the layer's emitters as amp·exp(i(kR + φ)) at their bins. Each
  plane wave is exact; each layer's curvature is that of its distance (the Fresnel
  approximation per layer, spaced so that the error stays within a quarter wave at the pupil's
  rim: Rayleigh's depth of focus).
- The paper's route (:func:`intensity_hologram`, :func:`reconstruct_object_wave`): the object
  wave is recorded as H = |O + R|² with an off-axis plane reference on a grid 4× finer in x,
  and reconstructed as R'·H with the DC and twin terms filtered off (Sect. V–VI). Rendering
  the object wave directly is that reconstruction's ideal filter.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy import float32, int32

from ..opencl import associated, get_runtime
from ..opencl.arrays import by_rows, empty, fill
from ..opencl.kernel import BUFFER, kernel
from ..optics.imaging import ES_TABLE, TAPS, PupilImage, iris_weights
from ..scene.camera import Camera
from .optics import PupilOptics
from .raster import Emitters

PROGRAM = associated(__file__)
# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
SCATTER = kernel(PROGRAM, "scatter", S=BUFFER, idx=BUFFER, amp=BUFFER, phase0=BUFFER,
                 phi=BUFFER, first=int32)
ADD_LAYER = kernel(PROGRAM, "add_layer", P=BUFFER, u=BUFFER, h=int32, w=int32, dy=float32,
                   dx=float32, k=float32, z=float32)
# fmt: on


class PupilFields:
    """Device state of one render: the emitters' bins, amplitudes and phases, work arrays."""

    def __init__(self, rt, em: Emitters, optics: PupilOptics, camera_fine: Camera):
        self.rt, self.em, self.optics = rt, em, optics
        h, w = optics.shape
        self.index = rt.to_device(em.index.astype(np.int32))
        self.wavelengths = (optics.wavelength, optics.depth_wavelength)
        self.pitches = [optics.pitch(lam) for lam in self.wavelengths]  # (dy, dx) [m] each
        self.phase0 = [
            rt.to_device(np.remainder(2 * np.pi / lam * em.distance, 2 * np.pi), np.float32)
            for lam in self.wavelengths
        ]
        self.amps = [rt.to_device(np.sqrt(em.colour[:, c]), np.float32) for c in range(3)]
        self.amps.append(rt.to_device(np.sqrt(em.coverage), np.float32))
        self.spectrum, self.pupil = empty(rt, (h, w)), empty(rt, (h, w))
        self.imager = PupilImage(rt, (h, w), bin=optics.bin, camera=camera_fine)
        # |A|² / (N·Σw²) is the emitters' intensity (Parseval), w the iris on the samples
        iris = iris_weights((h, w), self.pitches[0], optics.diameter)
        self.scale = 1 / math.sqrt(h * w * float(np.sum(iris**2)))
        self.options = rt.real_options + (f"-DTAPS={TAPS}", f"-DES_TABLE={ES_TABLE}")

    def object_wave(self, field: int, phases):
        """The pupil's object wave (device, (h, w) FFT order) of colour channel ``field``
        (0-2) or the depth partner (3), emitter phases ``phases`` (device float32)."""
        rt, em, optics = self.rt, self.em, self.optics
        lam, (dy, dx) = self.wavelengths[field == 3], self.pitches[field == 3]
        h, w = optics.shape
        fill(rt, self.pupil, 0)
        for layer, z in enumerate(optics.layers):
            first, last = int(em.starts[layer]), int(em.starts[layer + 1])
            if first == last:
                continue
            fill(rt, self.spectrum, 0)
            SCATTER.launch(
                rt,
                (last - first,),
                options=self.options,
                S=self.spectrum,
                idx=self.index,
                amp=self.amps[field],
                phase0=self.phase0[field == 3],
                phi=phases,
                first=first,
            )
            rt.fft.backward(self.spectrum)
            ADD_LAYER.launch(
                rt,
                by_rows((h, w)),
                options=self.options,
                P=self.pupil,
                u=self.spectrum,
                h=h,
                w=w,
                dy=dy,
                dx=dx,
                k=2 * np.pi / lam,
                z=z,
            )
        return self.pupil

    def image(self, field: int) -> np.ndarray:
        """The image of the pupil's current wave (fine pixels, complex), normalised so that
        E|A|² is the emitters' intensity."""
        optics = self.optics
        lam = self.wavelengths[field == 3]
        return self.imager.image(
            self.pupil,
            pitch=self.pitches[field == 3],
            diameter=optics.diameter * lam / optics.wavelength,
            focus=optics.focus,
            lens_k=2 * np.pi / lam,
            scale=self.scale,
        )


def object_wave(
    em: Emitters, optics: PupilOptics, camera: Camera, *, field=0, seed=0
) -> np.ndarray:
    """The camera hologram: the object wave of colour channel ``field`` (0-2) or the depth
    partner (3) on the pupil (h, w) [field units], centred (row, col of the optical axis at
    (h//2, w//2)), pitch ``optics.pitch(λ)``, emitter phases drawn from ``seed``."""
    rt = get_runtime()
    fields = PupilFields(rt, em, optics, replace(camera, resolution=(1, 1)))
    phases = rt.to_device(random_phases(len(em.index), seed), np.float32)
    return np.fft.fftshift(fields.object_wave(field, phases).get())


def random_phases(n, seed) -> np.ndarray:
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
    big[:, 3 * w // 2 : 3 * w // 2 + w] = spec
    fine = np.fft.fftshift(np.fft.ifft2(np.fft.ifftshift(big))) * 4
    amplitude = math.sqrt(beam_ratio * float(np.mean(np.abs(o) ** 2)))
    carrier = 1.5 * w / (4 * w)
    ref = _reference(amplitude, carrier, 4 * w)
    return HologramRecording(
        intensity=np.abs(fine + ref).astype(np.float32) ** 2, carrier=carrier, amplitude=amplitude
    )


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
    o = spec[:, 3 * w // 2 : 3 * w // 2 + w]
    return np.fft.fftshift(np.fft.ifft2(np.fft.ifftshift(o))) / 4
