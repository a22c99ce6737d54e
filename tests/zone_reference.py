"""A float64 NumPy reference of the zone sum (holo_core/plate/zone_sum.py), independent of its
kernel, and small carrier plates of bare emitters made with it.

``reference`` is the stored samples' definition evaluated exactly, one emitter at a time:
every emitter's spherical wave (Eq. 3) through its window towards the zone (the zone's box, a
soft rim, the parallax of its depth) and its visibility from the zone point its ray reaches,
times the conjugate carrier converging on the zone's centre. ``object_wave`` is the same sum
without the carrier: the physical field of the light the zone sees, on any grid."""

import math

import numpy as np

from holo_core.plate.zone_light import RIM, window_on_plate, zone_band
from holo_core.plate.zone_sum import ZoneEmitters, ZoneWindow, zone_sum
from holo_core.scene.hologram import Hologram
from holo_core.scene.plate import Carrier


def rim(u, inner, width):
    t = np.clip((np.abs(u) - inner) / width, 0, 1)
    return (1 - t) ** 2 * (1 + 2 * t)


def reference(em: ZoneEmitters, win: ZoneWindow, wavelength) -> np.ndarray:
    """B(x) = exp(ik|x − Z|)·Σ a_j·w_j(x)·exp(ik·r_j)/r_j in float64, one emitter at a time."""
    k = 2 * np.pi / wavelength
    x = win.origin[0] + np.arange(win.shape[1]) * win.pitch
    y = win.origin[1] + np.arange(win.shape[0]) * win.row_pitch
    X, Y = np.meshgrid(x, y)
    Z, e = np.asarray(win.centre), np.asarray(win.half_extents)
    (g0x, gsx), (g0y, gsy) = em.grid
    out = np.zeros((em.amplitude.shape[1],) + win.shape, complex)
    for j, p in enumerate(em.position):
        s = (Z[2] - p[2]) / -p[2]  # the ray through x reaches the zone's plane at xi
        xi, eta = p[0] - Z[0] + s * (X - p[0]), p[1] - Z[1] + s * (Y - p[1])
        w = rim(xi, e[0] + e[2] * np.abs(X - p[0]) / -p[2], win.rim * e[0]) * rim(
            eta, e[1] + e[2] * np.abs(Y - p[1]) / -p[2], win.rim * e[1]
        )
        if em.visibility[j] >= 0:
            v = em.table[em.visibility[j]] / 255.0
            gy, gx = v.shape
            fx = np.clip((xi - g0x) / gsx, 0, gx - 1.0001)
            fy = np.clip((eta - g0y) / gsy, 0, gy - 1.0001)
            ix, iy = fx.astype(int), fy.astype(int)
            ax, ay = fx - ix, fy - iy
            top = v[iy, ix] * (1 - ax) + v[iy, ix + 1] * ax
            bottom = v[iy + 1, ix] * (1 - ax) + v[iy + 1, ix + 1] * ax
            w = w * (top * (1 - ay) + bottom * ay)
        r = np.sqrt((X - p[0]) ** 2 + (Y - p[1]) ** 2 + p[2] ** 2)
        out += em.amplitude[j][:, None, None] * (w * np.exp(1j * k * r) / r)[None]
    rz = np.sqrt((X - Z[0]) ** 2 + (Y - Z[1]) ** 2 + Z[2] ** 2)
    return out * np.exp(1j * k * rz)[None]


def object_wave(em: ZoneEmitters, zone, wavelength, xs, ys) -> np.ndarray:
    """O (C, len(ys), len(xs)) complex128 at the grid of columns ``xs`` and rows ``ys`` [m]
    (evenly spaced): the same sum with no carrier."""
    win = ZoneWindow(
        origin=(xs[0], ys[0]),
        pitch=xs[1] - xs[0],
        row_pitch=ys[1] - ys[0],
        shape=(len(ys), len(xs)),
        centre=zone.centre,
        half_extents=zone.half_extents,
        rim=RIM,
    )
    cx, cy, cz = zone.centre
    r = np.sqrt((xs[None] - cx) ** 2 + (ys[:, None] - cy) ** 2 + cz**2)
    return reference(em, win, wavelength) * np.exp(-2j * np.pi / wavelength * r)[None]


def carrier_plate(em: ZoneEmitters, zone, wavelength, finer=1) -> Hologram:
    """The complex plate of ``em`` against the carrier converging on ``zone``'s centre, as
    record_plate samples one (the window the light to the zone crosses, B's band there at its
    Nyquist pitch), or ``finer`` times more finely along each axis."""
    box = np.array([em.position.min(0), em.position.max(0)])
    lo, hi = window_on_plate(box, zone, math.inf, math.inf)
    pitch, row_pitch = (wavelength / (2 * b * finer) for b in zone_band(lo, hi, zone))
    shape = (math.ceil((hi[1] - lo[1]) / row_pitch) + 1, math.ceil((hi[0] - lo[0]) / pitch) + 1)
    win = ZoneWindow(
        origin=tuple(lo),
        pitch=pitch,
        row_pitch=row_pitch,
        shape=shape,
        centre=zone.centre,
        half_extents=zone.half_extents,
        rim=RIM,
    )
    return Hologram(
        object_wave=zone_sum(em, win, wavelength),
        encoding="complex",
        wavelengths=(wavelength,) * em.amplitude.shape[1],
        pitch=pitch,
        zone=zone,
        bounds=box,
        carrier=Carrier(centre=zone.centre, origin=tuple(lo), row_pitch=row_pitch),
    )
