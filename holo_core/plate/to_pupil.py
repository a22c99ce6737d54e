"""A plate's field at a camera's entrance pupil: what the camera hologram's pupil → image stage
(:mod:`holo_core.optics.imaging`) turns into the view, so that a plate's view is the camera
hologram of the same camera within the plate's physical limits (its window, its band, its
emitters). The window and the pupil's grid are :mod:`.window`'s.

- A full-band plate (:func:`field_at_pupil`): the window's field is carried by the angular
  spectrum with an offset to the plane parallel to the plate through the pupil's centre,
  centred there (Sect. IV-D), then its spectrum is rotated onto the camera's own plane
  (Sect. IV-C.1) and sampled finely enough for the directions it carries: the plate's band
  tilted by the camera's tilt, widened by the lens's own spread (D/2f).
- A plate stored against its zone's carrier (:class:`CarrierPupil`): demodulated onto the
  pupil's carrier, decimated to the light that enters the pupil, and summed onto the pupil's
  plane waves by a non-uniform FFT.
"""

from __future__ import annotations

import math

import numpy as np
from numpy import float32, int32, int64

from .. import jobs
from ..opencl.arrays import resident, upload_window, write
from ..opencl.kernel import BUFFER, REAL, kernel
from ..opencl.runtime import associated
from ..propagation import angular_spectrum, tilt
from ..propagation.angular_spectrum import BAND_EDGE
from ..scene.hologram import Hologram
from ..validate import InputError
from .gather import Gather
from .window import PUPIL_EDGE

PROGRAM = associated(__file__)

# the pupil grid's padding in the rotation: the crop rotated onto it reaches little beyond it (1.25
# against 2: 1e-4 of the field's norm)
PUPIL_PADDING = 1.25


def neighbourhood(n: int, pitch: float, rotation, plate_pitch: float) -> int:
    """Samples (per side, of ``plate_pitch`` [m]) of the parallel plane around the pupil's foot
    that a view reads and rotates: the n×n pupil grid of ``pitch`` [m], tilted by
    ``rotation``, seen on that plane, and a few samples more."""
    return math.ceil(n * pitch / max(float(rotation[2, 2]), 1e-3) / plate_pitch) + 2 * PUPIL_EDGE


def output_padding(shape, near: int) -> float:
    """The angular spectrum's padding when only ``near`` samples around the pupil's foot are
    read. A ray from the window (``shape``) to them moves at most (window + near)/2, and the
    band limit passes rays whole up to (1 − BAND_EDGE) of half the padded grid, so that grid
    need only span (window + near)/(1 − BAND_EDGE), not twice the window (the pupil's field
    changes by about 2e-3 of its norm: the Performance page's figures behind the constants)."""
    need = max((size + near) / (size * (1 - BAND_EDGE)) for size in shape)
    return float(min(2.0, need))


def field_at_pupil(u, window, h: Hologram, *, wavelength, position, rotation, n, pitch):
    """The window's field ``u`` (:func:`window_of`) carried to the camera's pupil: n×n
    samples ``pitch`` [m] apart in the camera's plane, centred on ``position`` (3,) [m], axes
    ``rotation`` (both in the plate's frame); a complex64 NumPy array in FFT order."""
    r0, r1, c0, c1 = window
    rows, cols = h.shape
    x_mid = ((c0 + c1 - 1) / 2 - (cols - 1) / 2) * h.pitch
    y_mid = ((r0 + r1 - 1) / 2 - (rows - 1) / 2) * h.pitch
    near = neighbourhood(n, pitch, rotation, h.pitch)
    parallel = angular_spectrum(
        u,
        wavelength=wavelength,
        pitch=h.pitch,
        distance=float(position[2]),
        offset=(float(position[0] - x_mid), float(position[1] - y_mid)),
        padding=output_padding(u.shape, near),
        read=(near, near),
    )
    crop = []
    for size in parallel.shape:
        m = min(size, near)
        m += (size - m) % 2  # the same centre: the pupil's
        crop.append(slice((size - m) // 2, (size - m) // 2 + m))
    at = tilt(
        np.ascontiguousarray(parallel[tuple(crop)]),
        wavelength=wavelength,
        pitch=h.pitch,
        rotation=rotation,
        out_shape=(n, n),
        out_pitch=pitch,
        out_padding=PUPIL_PADDING,
    )
    return np.ascontiguousarray(np.fft.ifftshift(at))


# --- plates stored against a carrier converging on their zone ---------------------------------

# [dB] the decimation filter's stop band: light towards the rest of the zone, as strong as the
# pupil's own, kept out of the pupil
DECIMATION_STOP = 50.0
PASS_MARGIN = 1.1  # the filter passes this much beyond the pupil's own band ...
TRANSITION = 0.35  # ... and falls to its stop band over this fraction of the pass band
BAND_ROWS = 512  # samples read and filtered per band of rows
DEMODULATE_SEGMENT = 32  # columns per exact phase (to_pupil.cl's SEGMENT)
# outputs of a row decimated by one work group: the largest whose inputs fit the device's local
# memory (the larger, the faster: docs, Performance)
DECIMATE_GROUPS = (256, 64, 16)

# the kernels of to_pupil.cl, their arguments in its order
_GEOMETRY = dict(pitch=REAL, row_pitch=REAL, x0=REAL, y0=REAL)  # of a band's first sample
_POINTS = dict(px=REAL, py=REAL, pz=REAL, zx=REAL, zy=REAL, zz=REAL)  # pupil's, zone's centre
# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
DEMODULATE_CENTRES = kernel(PROGRAM, "demodulate_centres", table=BUFFER, rows=int32,
                            segments=int32, **_GEOMETRY, k=REAL, **_POINTS)
DEMODULATE_DECIMATE = kernel(
    PROGRAM, "demodulate_decimate", out=BUFFER, samples=BUFFER, first=int64, plane=int64,
    stride=int32, rows=int32, cols=int32, out_cols=int32, out_row0=int32, out_height=int32,
    lead=int32, h=BUFFER, **_GEOMETRY, k=float32, **_POINTS, table=BUFFER, segments=int32)
DECIMATE = kernel(PROGRAM, "decimate", out=BUFFER, rowpass=BUFFER, rows=int32, cols=int32,
                  out_rows=int32, slot=BUFFER, stride=int32, plane0=int32, q=int32,
                  first=int32, h=BUFFER)
# fmt: on


def kaiser_lowpass(cutoff: float, transition: float, taps_len=None) -> np.ndarray:
    """A linear-phase low-pass FIR (odd taps, unit DC gain) with its −6 dB point at ``cutoff``
    and ``transition`` wide (both in cycles per sample), its stop band DECIMATION_STOP below
    (Kaiser's window and formulas). ``taps_len``: the taps made from the count the
    transition needs (odd; more taps narrow the transition, the stop band the same)."""
    a = DECIMATION_STOP
    beta = 0.1102 * (a - 8.7)
    taps = int(math.ceil((a - 8) / (2.285 * 2 * math.pi * transition))) | 1
    if taps_len is not None:
        taps = taps_len(taps) | 1
    n = np.arange(taps) - (taps - 1) / 2
    h = 2 * cutoff * np.sinc(2 * cutoff * n) * np.kaiser(taps, beta)
    return (h / h.sum()).astype(np.float32)


class CarrierPupil:
    """One camera's pupil field from a plate stored against its zone's carrier.

    Per channel: the window the pupil sees the objects through is read band by band, turned
    onto the carrier converging on the pupil's centre P (``demodulate``: exact, float64), low-
    passed to the light that enters the pupil and thinned to what that light needs
    (``decimate``, :func:`kaiser_lowpass`: the rest of the zone's light is filtered off), and
    its samples, each a point source of the plate (Rayleigh–Sommerfeld, Eq. 7: weight
    (q·pitch)²·cos θ/(λR)), summed into the pupil's plane waves by a type-1 non-uniform FFT
    onto the camera's spectrum bins, with the curvature of their distance (depth layers as the
    camera hologram's). The Riemann sum is exact for band-limited samples whose band plus the
    pupil's stays below their rate; the decimation keeps to that.

    rt : the OpenCL runtime
    h : the hologram (carrier plate; only its metadata is read here)
    position, rotation : the pupil's centre (3,) [m] and the camera's axes (3, 3) in the
        plate's frame
    diameter : the pupil's diameter [m]
    bin : the spectrum's bin spacing in direction cosine; shape : (h, w) pupil samples
    centre : (α, β) the direction cosines of the spectrum's centre bin: the pupil fields come
        demodulated by exp(−ik(α·x + β·y)) (the spectrum holds the directions the samples'
        light arrives from, not the whole field of view)
    window : (row0, row1, col0, col1) of the plate's samples that can reach the pupil
    taps_len : callable(n) -> int >= n, optional: the decimation's taps made from the count
        it needs (a moving camera's views share the kernels built for a few counts)
    """

    def __init__(
        self,
        rt,
        h,
        *,
        position,
        rotation,
        diameter,
        bin,
        shape,
        window,
        centre=(0.0, 0.0),
        taps_len=None,
    ):
        self.rt, self.h, self.centre, self.taps_len = rt, h, centre, taps_len
        self._designs, self._taps = {}, {}
        self._gathers = {}
        self.position = np.asarray(position, np.float64)
        self.rotation = np.asarray(rotation, np.float64)
        self.diameter, self.bin, self.shape = diameter, bin, tuple(shape)
        self.window = window

    def _design(self, wavelength):
        """((q, taps) along rows, (q, taps) along columns) of the decimation at
        ``wavelength`` [m]: the pass band the pupil's light needs (its width seen from the
        window's nearest point, PASS_MARGIN beyond), the stop band TRANSITION beyond it, and
        every q-th sample while the stop band's edge plus the pupil's own band stay below the
        rate (the Riemann sum onto the pupil then has no alias). Made once a wavelength."""
        key = round(wavelength, 15)
        if key not in self._designs:
            self._designs[key] = self._designed(wavelength)
        return self._designs[key]

    def _designed(self, wavelength):
        h = self.h
        r0, r1, c0, c1 = self.window
        x, y = h.carrier.coords(h.pitch, [r0, r1], [c0, c1])
        corners = np.array([[xx, yy, 0.0] for xx in x for yy in y])
        nearest = float(np.min(np.linalg.norm(corners - self.position, axis=1)))
        nearest = min(nearest, float(self.position[2]))
        band = PASS_MARGIN * self.diameter / (2 * wavelength * nearest)  # [1/m]
        out = []
        for pitch in (h.carrier.row_pitch, h.pitch):
            q = max(1, int(1 / (pitch * band * (1 + TRANSITION + 1 / PASS_MARGIN))))
            out.append(
                (1, np.ones(1, np.float32))
                if q == 1
                else (
                    q,
                    kaiser_lowpass(
                        (1 + TRANSITION / 2) * band * pitch,
                        TRANSITION * band * pitch,
                        self.taps_len,
                    ),
                )
            )
        return out

    def fields(self, parts, *, amplitude=1.0, progress=None):
        """The pupil fields (device (planes, h, w) complex64, FFT order) of ``parts``, each
        (samples, channels, wavelength [m]): ``channels`` (neighbours, all at ``wavelength``)
        of one look's ``samples`` (C, H, W), a NumPy array or any array sliced as [c0:c1,
        r0:r1, c0:c1] (a store's); the planes in the parts' order, ``amplitude`` scaling them
        (the emitters' density). The parts that thin out alike share one gather onto the
        bins: every look and channel is spread in one pass, which finds each sample's bins
        once for all of them, not once a plane."""
        designs = [self._design(wavelength) for _, _, wavelength in parts]
        planes = sum(len(channels) for _, channels, _ in parts)
        out = self.rt.workspace("carrier-pupils", (planes,) + self.shape)
        out.fill(0)
        firsts = np.cumsum([0] + [len(channels) for _, channels, _ in parts])
        done = 0
        for key in dict.fromkeys((rows[0], cols[0]) for rows, cols in designs):
            if key not in self._gathers:  # one per decimation
                self._gathers[key] = Gather(self, *key)
            mine = [i for i, (rows, cols) in enumerate(designs) if (rows[0], cols[0]) == key]
            gather = self._gathers[key]
            stack = self.rt.workspace(
                "plate-decimated", (gather.count, sum(len(parts[i][1]) for i in mine))
            )
            runs, at = [], 0
            for i in mine:
                samples, channels, wavelength = parts[i]
                self._decimated(
                    samples, channels, wavelength, *designs[i], out=stack, at=at, slot=gather.slot
                )
                runs.append((at, int(firsts[i]), len(channels), wavelength))
                at += len(channels)
                done += 1
                jobs.report(progress, done, len(parts))
            gather.pupil(stack, runs, out, amplitude)
        return out

    def _device_taps(self, taps: np.ndarray):
        """``taps`` on the device, copied there once."""
        key = taps.tobytes()
        if key not in self._taps:
            self._taps[key] = self.rt.to_device(taps)
        return self._taps[key]

    def _decimated(self, samples, channels, wavelength, along_rows, along_cols, *, out, at, slot):
        """The window's samples turned onto the pupil's carrier, filtered and thinned to every
        q-th along each axis (``along_rows``, ``along_cols``: (q, taps)): the rows r0 + q·i
        and columns c0 + q·j of the plate, into planes ``at`` … of the device array ``out``
        (samples, P), sample (i, j) at row ``slot`` [i·cols + j] (device int32)."""
        rt, h = self.rt, self.h
        ph, pw = h.shape
        r0, r1, c0, c1 = self.window
        (qy, taps_y), (qx, taps_x) = along_rows, along_cols
        pad_y, pad_x = (len(taps_y) - 1) // 2, (len(taps_x) - 1) // 2
        rr0, rr1 = max(r0 - pad_y, 0), min(r1 + pad_y, ph)
        cc0, cc1 = max(c0 - pad_x, 0), min(c1 + pad_x, pw)
        out_cols, out_rows = -(-(c1 - c0) // qx), -(-(r1 - r0) // qy)
        planes = len(channels)
        rowpass = rt.workspace("plate-rowpass", (planes, rr1 - rr0, out_cols))
        k = 2 * math.pi / wavelength
        taps = [self._device_taps(t) for t in (taps_x, taps_y)]
        group = _decimate_group(rt, planes, qx, len(taps_x))
        options = rt.real_options + (
            f"-DTAPS={len(taps_x)}",
            f"-DQ={qx}",
            f"-DPLANES={planes}",
            f"-DGROUP={group}",
        )
        # a CPU reads the host's samples where they are, a GPU its copy of them, kept between
        # views
        in_place = (
            resident(rt, samples) if getattr(samples, "dtype", None) == np.complex64 else None
        )
        for b0 in range(rr0, rr1, BAND_ROWS):
            b1 = min(b0 + BAND_ROWS, rr1)
            if in_place is not None:
                source = in_place
                first, plane, stride = (channels[0] * ph + b0) * pw + cc0, ph * pw, pw
            else:
                # one buffer for every band (a fresh one would cost the first touch of its
                # pages): the window's rectangle of an array, or a store's tiles, read
                band = rt.workspace("plate-band", (planes, b1 - b0, cc1 - cc0))
                if (
                    isinstance(samples, np.ndarray)
                    and samples.flags.c_contiguous
                    and samples.dtype == np.complex64
                ):
                    upload_window(band, samples, channels, b0, cc0)
                else:
                    write(band, samples[channels[0] : channels[-1] + 1, b0:b1, cc0:cc1])
                source = band.data
                first, plane, stride = 0, (b1 - b0) * (cc1 - cc0), cc1 - cc0
            x0, y0 = h.carrier.coords(h.pitch, [b0], [cc0])
            segments = -(-(cc1 - cc0) // DEMODULATE_SEGMENT)
            table = rt.workspace("plate-demodulate", (b1 - b0, segments), np.float32)
            geometry = dict(pitch=h.pitch, row_pitch=h.carrier.row_pitch, x0=x0[0], y0=y0[0])
            points = dict(
                zip(("px", "py", "pz", "zx", "zy", "zz"), (*self.position, *h.carrier.centre))
            )
            DEMODULATE_CENTRES.launch(
                rt,
                (segments, b1 - b0),
                options=rt.real_options,
                table=table,
                rows=b1 - b0,
                segments=segments,
                **geometry,
                k=k,
                **points,
            )
            groups = -(-out_cols // group)
            DEMODULATE_DECIMATE.launch(
                rt,
                (groups * group, b1 - b0),
                (group, 1),
                options=options,
                out=rowpass,
                samples=source,
                first=first,
                plane=plane,
                stride=stride,
                rows=b1 - b0,
                cols=cc1 - cc0,
                out_cols=out_cols,
                out_row0=b0 - rr0,
                out_height=rr1 - rr0,
                lead=c0 - cc0 - pad_x,
                h=taps[0],
                **geometry,
                k=k,
                **points,
                table=table,
                segments=segments,
            )
        DECIMATE.launch(
            rt,
            (out_cols, out_rows, planes),
            options=(f"-DTAPS={len(taps_y)}",),
            out=out,
            rowpass=rowpass,
            rows=rr1 - rr0,
            cols=out_cols,
            out_rows=out_rows,
            slot=slot,
            stride=out.shape[1],
            plane0=at,
            q=qy,
            first=r0 - rr0 - pad_y,
            h=taps[1],
        )


def _decimate_group(rt, planes: int, q: int, taps: int) -> int:
    """The work group of demodulate_decimate: its outputs' inputs (planes × (group·q + taps)
    complex64, to_pupil.cl's span) within the device's local memory and work-group size."""
    device = rt.device
    for group in DECIMATE_GROUPS:
        need = 8 * planes * q * (group + (taps + q - 1) // q + 1)
        if need <= device.local_mem_size and group <= device.max_work_group_size:
            return group
    raise InputError(
        f"a view's decimation needs {8 * planes * (16 * q + taps)} bytes of "
        f"local memory; the device {device.name} has {device.local_mem_size}"
    )
