"""The part of a plate a camera's pupil sees the objects through, and the pupil's grid: the
geometry a view reads before any light is carried (:mod:`.to_pupil`).

- The camera in the plate's frame (:func:`camera_in_plate`), and where its pixels' rays meet
  a plane (:func:`plane_depth`).
- The window (:func:`plate_window`, a carrier plate's :func:`carrier_window`): only the part
  of the plate inside the cone from the pupil to the objects (:func:`seen_on_plate`), cut to
  the camera's field of view (:func:`image_corners`), is read, rows and columns of its
  samples with a margin; beyond the plate's edge the field is zero (the plate's own
  aperture). A tiled plate is read tile by tile (:func:`window_of`).
- The pupil's grid (:func:`pupil_grid`): n×n samples, n odd (the centre sample lies on the
  axis, so the field is in FFT order by a shift), spanning the pupil's diameter (the part the
  plate's light reaches, :func:`lit_diameter`) and a few samples more.
- A pinhole camera's pupil on a carrier plate (:func:`pinhole_view_pupil`), the smallest
  that makes the view sharp, and the supersampling at which a view samples its intensity at
  the Nyquist rate (:func:`nyquist_supersample`).
"""

from __future__ import annotations

import math

import numpy as np

from ..optics.pupil import Pupil, intensity_supersample
from ..propagation import grid
from ..scene.camera import Camera
from ..scene.hologram import Hologram
from ..scene.plate import box_corners
from ..validate import InputError
from ..view import BACKGROUND_DEPTH
from .plan import SUPERSAMPLE, pinhole_pupil

WINDOW_MARGIN = 0.1  # the window reaches this fraction of its size beyond the cone ...
WINDOW_SAMPLES = 8  # ... and at least this many samples
VIEW_MARGIN = 0.1  # ... and the field of view this fraction of the image beyond its corners
PUPIL_GUARD = 0.05  # direction cosines carried beyond the band, the tilt and the lens spread
PUPIL_EDGE = 4  # pupil samples beyond the iris on each side


def camera_in_plate(hologram: Hologram, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """The camera's axes (columns) and aperture centre [m] in the hologram's frame."""
    plate = np.asarray(hologram.plate, np.float64)
    axes = plate[:3, :3] / np.linalg.norm(plate[:3, :3], axis=0)
    rotation = axes.T @ camera.rotation
    u, _, vt = np.linalg.svd(rotation)  # re-orthonormalise what float round-off bent
    rotation = u @ vt
    position = axes.T @ (camera.position - plate[:3, 3])
    if position[2] <= 0:
        raise InputError(
            f"the camera must be in front of the hologram (z > 0 in the plate's "
            f"frame); it is at z = {position[2]:.4g} m"
        )
    if rotation[2, 2] <= 0:
        raise InputError(
            "the camera must look towards the hologram (its view axis has to "
            "point to −z of the plate)"
        )
    return rotation, position


def plane_depth(h: Hologram, camera: Camera, z: float) -> np.ndarray:
    """The planar depth [m] (along the view axis, as Blender's Depth pass) at which each
    pixel's ray meets the plane ``z`` [m] of the hologram's frame; the background's where it
    never does."""
    rotation, position = camera_in_plate(h, camera)
    tx, ty = camera.pixel_tangents()
    direction = np.stack([tx, ty, -np.ones_like(tx)], -1) @ np.asarray(rotation).T
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (z - position[2]) / direction[..., 2]
    return np.where(np.isfinite(t) & (t > 0), t, BACKGROUND_DEPTH)


def odd_fast_len(n: int) -> int:
    """The smallest odd 3^a·5^b·7^c >= n (a fast FFT size whose centre is a sample)."""
    return grid.smooth_len(n, (3, 5, 7))


def plate_window(h: Hologram, position, rotation, diameter, view=None) -> tuple[int, int, int, int]:
    """(row0, row1, col0, col1) of the plate's samples the camera's pupil (centre ``position``
    (3,) [m], axes ``rotation`` (3, 3), both in the plate's frame, diameter ``diameter`` [m])
    sees the objects through (:func:`seen_on_plate`; ``view``: the directions of the image's
    corners, when given: a camera that sees a part of a large plate reads that part), a
    margin around it, and at least the pupil's own width around its foot. May reach beyond
    the plate."""
    cone_lo, cone_hi = seen_on_plate(h.bounds, position, rotation, diameter, view)
    if view is not None:
        cone_hi = np.maximum(cone_hi, cone_lo)  # nothing in view: the pupil's foot alone
    size = cone_hi - cone_lo
    margin = np.maximum(WINDOW_MARGIN * size, WINDOW_SAMPLES * h.pitch)
    cone_lo, cone_hi = cone_lo - margin, cone_hi + margin
    # the parallel plane's window, of the same size, must hold the (tilted) pupil
    r = diameter / 2
    need = r / max(float(rotation[2, 2]), 1e-3) + WINDOW_SAMPLES * h.pitch
    half = np.maximum((cone_hi - cone_lo) / 2, need)
    mid = (cone_lo + cone_hi) / 2
    rows, cols = h.shape
    c0 = math.floor((mid[0] - half[0]) / h.pitch + (cols - 1) / 2)
    c1 = math.ceil((mid[0] + half[0]) / h.pitch + (cols - 1) / 2) + 1
    r0 = math.floor((mid[1] - half[1]) / h.pitch + (rows - 1) / 2)
    r1 = math.ceil((mid[1] + half[1]) / h.pitch + (rows - 1) / 2) + 1
    return r0, r1, c0, c1


def seen_on_plate(bounds, position, rotation, diameter, view=None) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) (x, y) [m] on the plate of the cone from the rim of a pupil (centre
    ``position`` (3,) [m], axes ``rotation`` (3, 3), diameter ``diameter`` [m]) to the
    objects' box ``bounds`` (2, 3) [m], cut to the camera's field of view where ``view`` (the
    directions (N, 3) of the image's corners, :func:`image_corners`) is given; all in the
    plate's frame. Where the cut leaves nothing, hi < lo."""
    r = diameter / 2
    rim = np.array(
        [position + s * r * rotation[:, a] for a in (0, 1) for s in (-1, 1)] + [position]
    )
    lo, hi = cone_on_plate(bounds, rim)
    if view is not None:
        d = np.asarray(view, np.float64)
        t = -rim[:, None, 2:3] / np.minimum(d[None, :, 2:3], -1e-12)
        seen = (rim[:, None, :2] + t * d[None, :, :2]).reshape(-1, 2)
        lo, hi = np.maximum(lo, seen.min(0)), np.minimum(hi, seen.max(0))
    return lo, hi


def carrier_window(h: Hologram, position, rotation, diameter, view):
    """(row0, row1, col0, col1) of a carrier plate's samples the pupil sees the objects
    through (:func:`seen_on_plate`, cut to the field of view ``view``), or None where that
    misses the samples."""
    lo, hi = seen_on_plate(h.bounds, position, rotation, diameter, view)
    o, step = np.asarray(h.carrier.origin), np.array([h.pitch, h.carrier.row_pitch])
    c0, r0 = np.floor((lo - o) / step).astype(int) - 1
    c1, r1 = np.ceil((hi - o) / step).astype(int) + 2
    rows, cols = h.shape
    r0, r1, c0, c1 = max(r0, 0), min(r1, rows), max(c0, 0), min(c1, cols)
    return None if r1 <= r0 or c1 <= c0 else (int(r0), int(r1), int(c0), int(c1))


def image_corners(camera: Camera, rotation, margin=VIEW_MARGIN) -> np.ndarray:
    """The directions (4, 3) [plate frame] of the image's corners, ``margin`` of its size
    beyond them (a defocused pixel gathers light from around its ray)."""
    w, h = camera.resolution
    rows, cols = np.array([-1, -1, 1, 1]) * margin * h, np.array([-1, 1, -1, 1]) * margin * w
    tx, ty = camera.pixel_tangents(
        rows=rows + np.array([0, 0, h, h]), cols=cols + np.array([0, w, 0, w])
    )
    return np.stack([tx, ty, -np.ones(4)], -1) @ np.asarray(rotation).T


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
        at = (slice(a, b), slice(c, d)) if channel is None else (channel, slice(a, b), slice(c, d))
        out[a - r0 : b - r0, c - c0 : d - c0] = plane[at]
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
    reach = (
        max(abs(float(position[0])) + width / 2, abs(float(position[1])) + height / 2)
        + spread
        + WINDOW_SAMPLES * h.pitch
    )
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


def pinhole_view_pupil(h: Hologram, camera: Camera, rotation, position, *, apodize=True) -> Pupil:
    """A pinhole camera's pupil on the carrier plate ``h``: the smallest that makes the view
    sharp, the plate's own resolution rule.

    A pupil of diameter D resolves the angle λ/D (Sect. VII-A); a sharp view resolves a fine
    pixel b = Δ/s of its pixels Δ [rad] (s = ``SUPERSAMPLE``, the plate's reference view and
    the emitters' spacing, :mod:`holo_core.plate.plan`), so D = λ/b = s·λ/Δ: with Δ = p/f a
    pixel's pitch p on the sensor over the focal length f, D = s·λ·f/p. A wider pupil resolves
    no more of the pixels but its spectrum needs bins of λ/D each (the pupil grid's samples
    grow as D², a billion and more where a flat object lets defocus allow any width), and a
    narrower one blurs. Focused in the middle of the objects' depths in 1/z, the pupil
    defocuses a depth z by D·|1/z − 1/focus| ≤ D·δ; where that outgrows b (deep objects, a
    long λ), D = √(λ/δ), which balances the two blurs (λ/D = D·δ, the least blur a pinhole
    has; the view then warns that it is soft). Within the zone, where the plate sends light;
    a camera at its edge keeps λ/Δ (the spot one pixel), the light beyond is not there.

    Parameters
    ----------
    h : Hologram
        A carrier plate (its ``bounds``, ``zone`` and first colour's wavelength λ [m]).
    camera : Camera
        The pinhole camera (its pixel angle Δ [rad]).
    rotation, position : ndarray
        The camera's axes (3, 3) and pupil centre (3,) [m] in the plate's frame
        (:func:`holo_core.plate.window.camera_in_plate`).
    apodize : bool
        The pupil's cosine window (Fig. 9).

    Returns
    -------
    Pupil
        Its diameter [m] and focus [m].
    """
    lam = h.wavelengths[h.colour_channels()[0]]
    fine = camera.pixel_angle() / SUPERSAMPLE
    wide, focus = pinhole_pupil(h.bounds, position, fine, rotation)  # widest within b
    defocus = fine / wide  # δ [1/m], the largest |1/z − 1/focus| over the objects' box
    diameter = min(lam / fine, math.sqrt(lam / defocus))
    if h.zone is not None:
        room = np.asarray(h.zone.half_extents[:2]) - np.abs(
            position[:2] - np.asarray(h.zone.centre[:2])
        )
        diameter = min(diameter, max(2 * float(room.min()), lam / camera.pixel_angle()))
    return Pupil(diameter=diameter, focus=focus, apodize=apodize)


def nyquist_supersample(h: Hologram, camera: Camera, pinhole: Pupil | None = None) -> int:
    """The supersampling at which a view of ``h`` through ``camera``'s pupil samples its
    intensity at the Nyquist rate (:func:`holo_core.optics.pupil.intensity_supersample`;
    below it the view is measurably softer: docs, Performance): the camera's lens, or a
    pinhole's on a carrier plate (``pinhole``, where the caller made it already, else
    :func:`pinhole_view_pupil`). A pinhole's on a full-band plate is sized to that already
    (λ/D is two fine pixels, :func:`camera_pupil`): 1."""
    if camera.fstop is not None:
        diameter = camera.aperture_diameter
    elif h.carrier is not None:
        diameter = (pinhole or pinhole_view_pupil(h, camera, *camera_in_plate(h, camera))).diameter
    else:
        return 1
    return intensity_supersample(diameter, camera.pixel_angle(), min(h.wavelengths))
