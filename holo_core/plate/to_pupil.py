"""A plate's field at a camera's entrance pupil: what the camera hologram's pupil → image stage
(:mod:`holo_core.optics.imaging`) turns into the view, so that a plate's view is the camera
hologram of the same camera within the plate's physical limits (its window, its band, its
emitters).

1. The window (:func:`plate_window`): only the part of the plate inside the cone from the
   pupil to the objects is read, rows and columns of its samples with a margin; beyond the
   plate's edge the field is zero (the plate's own aperture). A tiled plate is read tile by
   tile.
2. To the pupil's plane (:func:`field_at_pupil`): the window's field is carried by the angular
   spectrum with an offset to the plane parallel to the plate through the pupil's centre,
   centred there (Sect. IV-D), then its spectrum is rotated onto the camera's own plane
   (Sect. IV-C.1) and sampled finely enough for the directions it carries: the plate's band
   tilted by the camera's tilt, widened by the lens's own spread (D/2f).
3. The pupil's grid (:func:`pupil_grid`): n×n samples, n odd (the centre sample lies on the
   axis, so the field is in FFT order by a shift), spanning the pupil's diameter and a few
   samples more.
"""

from __future__ import annotations

import math

import numpy as np

from ..propagation import angular_spectrum, grid, tilt
from ..propagation.angular_spectrum import BAND_EDGE
from ..scene.hologram import Hologram
from ..scene.plate import box_corners

WINDOW_MARGIN = 0.1   # the window reaches this fraction of its size beyond the cone ...
WINDOW_SAMPLES = 8    # ... and at least this many samples
PUPIL_GUARD = 0.05    # direction cosines carried beyond the band, the tilt and the lens spread
PUPIL_EDGE = 4        # pupil samples beyond the iris on each side
PUPIL_PADDING = 1.25  # the pupil grid's padding in the rotation: the crop rotated onto it
                      # reaches little beyond it (1.25 against 2: 1e-4 of the field's norm)


def odd_fast_len(n: int) -> int:
    """The smallest odd 3^a·5^b·7^c >= n (a fast FFT size whose centre is a sample)."""
    return grid.smooth_len(n, (3, 5, 7))


def plate_window(h: Hologram, position, rotation, diameter, view=None
                 ) -> tuple[int, int, int, int]:
    """(row0, row1, col0, col1) of the plate's samples the camera's pupil (centre ``position``
    (3,) [m], axes ``rotation`` (3, 3), both in the plate's frame, diameter ``diameter`` [m])
    sees the objects through: the cone from the pupil to the objects' box, cut to the
    camera's field of view (``view``: the directions (N, 3) of the image's corners in the
    plate's frame, when given; a camera that sees a part of a large plate reads that part),
    a margin around it, and at least the pupil's own width around its foot. May reach beyond
    the plate."""
    r = diameter / 2
    rim = np.array([position + s * r * rotation[:, a] for a in (0, 1) for s in (-1, 1)]
                   + [position])
    cone_lo, cone_hi = cone_on_plate(h.bounds, rim)
    if view is not None:
        d = np.asarray(view, np.float64)
        t = -rim[:, None, 2:3] / np.minimum(d[None, :, 2:3], -1e-12)
        seen = (rim[:, None, :2] + t * d[None, :, :2]).reshape(-1, 2)
        cone_lo, cone_hi = np.maximum(cone_lo, seen.min(0)), np.minimum(cone_hi, seen.max(0))
        cone_hi = np.maximum(cone_hi, cone_lo)  # nothing in view: the pupil's foot alone
    size = cone_hi - cone_lo
    margin = np.maximum(WINDOW_MARGIN * size, WINDOW_SAMPLES * h.pitch)
    cone_lo, cone_hi = cone_lo - margin, cone_hi + margin
    # the parallel plane's window, of the same size, must hold the (tilted) pupil
    need = r / max(float(rotation[2, 2]), 1e-3) + WINDOW_SAMPLES * h.pitch
    half = np.maximum((cone_hi - cone_lo) / 2, need)
    mid = (cone_lo + cone_hi) / 2
    rows, cols = h.shape
    c0 = math.floor((mid[0] - half[0]) / h.pitch + (cols - 1) / 2)
    c1 = math.ceil((mid[0] + half[0]) / h.pitch + (cols - 1) / 2) + 1
    r0 = math.floor((mid[1] - half[1]) / h.pitch + (rows - 1) / 2)
    r1 = math.ceil((mid[1] + half[1]) / h.pitch + (rows - 1) / 2) + 1
    return r0, r1, c0, c1


def cone_on_plate(bounds, rim) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) (x, y) [m] on the plate (z = 0) of the lines from the points ``rim`` (N, 3)
    [m, z > 0] to the corners of the objects' box ``bounds`` (2, 3) [m], all in the plate's
    frame."""
    corners = box_corners(bounds)
    rim = np.asarray(rim, np.float64)
    t = rim[:, None, 2:3] / (rim[:, None, 2:3] - np.minimum(corners[None, :, 2:3], -1e-12))
    hits = (rim[:, None, :2] + t * (corners[None, :, :2] - rim[:, None, :2])).reshape(-1, 2)
    return hits.min(0), hits.max(0)


def overlaps(h: Hologram, window) -> bool:
    r0, r1, c0, c1 = window
    rows, cols = h.shape
    return r0 < rows and r1 > 0 and c0 < cols and c1 > 0


def window_of(plane, window, channel=None) -> np.ndarray:
    """``plane`` (H, W)'s samples in ``window`` (row0, row1, col0, col1), zero beyond its
    edges: complex64. With ``channel``, ``plane`` is (C, H, W) and only that channel's window
    is read: of a tiled plate, only the tiles the window overlaps."""
    r0, r1, c0, c1 = window
    rows, cols = plane.shape[-2:]
    out = np.zeros((r1 - r0, c1 - c0), np.complex64)
    a, b, c, d = max(r0, 0), min(r1, rows), max(c0, 0), min(c1, cols)
    if a < b and c < d:
        at = (slice(a, b), slice(c, d)) if channel is None else (channel, slice(a, b),
                                                                 slice(c, d))
        out[a - r0:b - r0, c - c0:d - c0] = plane[at]
    return out


def lit_diameter(h: Hologram, position, rotation, diameter) -> float:
    """The diameter [m] of the part of a pupil of ``diameter`` [m] (centre ``position`` (3,)
    [m], axes ``rotation``, the plate's frame) that the plate's light can reach: a pupil
    larger than the plate's light (a 10 m lens before a 6 cm plate) is read only where light
    arrives, since beyond it the field is zero (its iris still counts whole in the view's
    calibration). The light leaves every plate point within the object wave's cone (sin θ =
    band, else the pitch's Nyquist angle at the longest wavelength), so on the pupil's plane
    it lies within the plate widened by z·tan θ; seen on a tilted pupil, 1/cos(tilt) wider."""
    nyquist = min(1.0, max(h.wavelengths) / (2 * h.pitch))
    band = min(h.band, nyquist) if h.band else nyquist
    if band >= 1:
        return diameter
    spread = float(position[2]) * band / math.sqrt(1 - band * band)
    width, height = h.size
    reach = max(abs(float(position[0])) + width / 2, abs(float(position[1])) + height / 2) \
        + spread + WINDOW_SAMPLES * h.pitch
    return min(diameter, 2 * reach / max(float(rotation[2, 2]), 1e-3))


def pupil_grid(h: Hologram, rotation, diameter, focus, wavelength) -> tuple[int, float]:
    """(n, pitch [m]) of the pupil's n×n grid in the camera's plane for the shortest
    ``wavelength`` [m] of a view: its samples carry the plate's band tilted by the camera's
    tilt and widened by a lens focused at ``focus`` [m] (None: none). ``h``: the hologram, or
    the plan it will be recorded by (their ``pitch`` and ``band``)."""
    nyquist = min(1.0, wavelength / (2 * h.pitch))
    band = min(h.band, nyquist) if h.band else nyquist
    tilted = math.asin(min(1.0, band)) + math.acos(float(np.clip(rotation[2, 2], -1, 1)))
    spread = math.sin(min(tilted, math.pi / 2)) + (diameter / (2 * focus) if focus else 0.0)
    pitch = wavelength / (2 * min(1.0, spread + PUPIL_GUARD))
    n = odd_fast_len(math.ceil(diameter / pitch) + 2 * PUPIL_EDGE)
    return n, pitch


def neighbourhood(n: int, pitch: float, rotation, plate_pitch: float) -> int:
    """Samples (per side, of ``plate_pitch`` [m]) of the parallel plane around the pupil's foot
    that a view reads and rotates: the n×n pupil grid of ``pitch`` [m], tilted by
    ``rotation``, seen on that plane, and a few samples more."""
    return math.ceil(n * pitch / max(float(rotation[2, 2]), 1e-3) / plate_pitch) \
        + 2 * PUPIL_EDGE


def output_padding(shape, near: int) -> float:
    """The angular spectrum's padding when only ``near`` samples around the pupil's foot are
    read. A ray from the window (``shape``) to them moves at most (window + near)/2, and the
    band limit passes rays whole up to (1 − BAND_EDGE) of half the padded grid, so that grid
    need only span (window + near)/(1 − BAND_EDGE), not twice the window (measured on the
    plate scene: 1.77 instead of 2 changes the pupil's field by 2e-3 of its norm)."""
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
    parallel = angular_spectrum(u, wavelength=wavelength, pitch=h.pitch,
                                distance=float(position[2]),
                                offset=(float(position[0] - x_mid), float(position[1] - y_mid)),
                                padding=output_padding(u.shape, near), read=(near, near))
    crop = []
    for size in parallel.shape:
        m = min(size, near)
        m += (size - m) % 2  # the same centre: the pupil's
        crop.append(slice((size - m) // 2, (size - m) // 2 + m))
    at = tilt(np.ascontiguousarray(parallel[tuple(crop)]), wavelength=wavelength,
              pitch=h.pitch, rotation=rotation, out_shape=(n, n), out_pitch=pitch,
              out_padding=PUPIL_PADDING)
    return np.ascontiguousarray(np.fft.ifftshift(at))

