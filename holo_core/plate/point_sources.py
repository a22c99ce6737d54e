"""Object waves of point emitters on the hologram plane z = 0 (Eq. 3, Sect. V-B): the one
entry, its checks and the choice between two methods of the same sum by their modelled cost:

``direct``
    every point–pixel pair (:mod:`.point_sum`);
``wrp``
    wavefront recording planes (:mod:`.recording_planes`), cheaper where the points lie far
    from the plate.

Each point lights only the cone its pitch samples alias-free: ρ ≤ |z|·tan θ with
sin θ = λ/(2·pitch) (the disc whose local spatial frequency stays below Nyquist).
"""

from __future__ import annotations

import math

import numpy as np

from .. import jobs, memory, validate
from ..opencl import get_runtime
from ..opencl.arrays import cached, empty, fill
from ..propagation import grid
from ..propagation.convolution import convolve
from ..validate import InputError, shown
from .point_sum import CONE_FILL, CPU_LANES, SEGMENTS, Grid, add_points, pixels_reached, segment
from .recording_planes import cone_in_angle, record_on_planes, slab_plan

# pairs/s of the direct kernel at 32-column segments (the cost model of the automatic choice;
# shorter segments are proportionally slower) ...
DIRECT_RATE = 3.3e9
TILE_CHECKS = 3e8  # ... plus its point-tile cone tests per second (it bins nothing)


POINT_BYTES = 200  # host bytes per point emitter while recording, plus ...
# ... per point and channel: the recording planes' peak, above what one to four channels hold (docs,
# Performance)
POINT_CHANNEL_BYTES = 96


def point_bytes(points: int, channels: int) -> float:
    """Host bytes the point sum of ``points`` emitters of ``channels`` channels takes beyond
    its grid: the points' amplitudes, carriers, segments and planes."""
    return (POINT_BYTES + POINT_CHANNEL_BYTES * channels) * points


def point_wave(
    positions,
    amplitudes,
    *,
    wavelength,
    pitch,
    shape,
    obliquity=False,
    band=None,
    method="auto",
    progress: jobs.Progress = None,
    as_device=False,
):
    """The object wave O on the plane z = 0 from point emitters (Eq. 3).

    Parameters
    ----------
    positions : (N, 3) float array
        Point positions (x, y, z) [m] in the hologram's frame; every z must be < 0 (light
        travels towards +z, through the hologram).
    amplitudes : (N,) or (N, C) complex array
        Complex amplitude A0·exp(iφ0) of each point [field units · m]; C columns give C waves
        of the same points and wavelength (colours) in one pass, which shares the geometry.
    wavelength : float
        λ [m].
    pitch : float
        Hologram sample spacing [m].
    shape : (int, int)
        Hologram (rows, cols), pixel centres as in :mod:`holo_core.propagation.grid`.
    obliquity : bool
        False: the spherical wave A0·exp(ikr)/r of Eq. 3. True: times the obliquity factor
        cos θ = |z|/r of the Rayleigh-Sommerfeld integral.
    band : float, optional
        sin θ of each point's cone edge; default ``CONE_FILL`` of the grid's Nyquist angle
        λ/(2·pitch), which is also its largest allowed value. An off-axis hologram narrows it
        to leave room for the reference's carrier (Sect. VI).
    method : {'auto', 'direct', 'wrp'}
        'auto' takes the faster by a cost model (see the module docstring).
    progress : callable, optional
        Called with the fraction done; may raise :class:`holo_core.jobs.Cancelled`.
    as_device : bool
        Return the OpenCL device array instead of a NumPy array.

    Returns
    -------
    Complex64 (rows, cols) field, or (C, rows, cols) for (N, C) amplitudes.
    """
    g = sampling_grid(validate.shape2d("shape", shape), wavelength, pitch, band)
    pos, amp = _points(positions, amplitudes)
    check_distance(pos, g)
    validate.choice("method", method, ("auto", "direct", "wrp"))
    if method == "auto":
        method = "wrp" if wrp_seconds(pos, g) < direct_seconds(pos, g) else "direct"
    memory.check_host(
        f"{len(pos)} point emitters of {amp.shape[1]} channels", point_bytes(len(pos), amp.shape[1])
    )
    rt = get_runtime()
    nbytes = 8.0 * amp.shape[1] * math.prod(g.shape)
    memory.check_device(rt, f"the {g.shape[1]}x{g.shape[0]} object wave", nbytes, nbytes)
    out = empty(rt, (amp.shape[1],) + g.shape)
    fill(rt, out, 0)
    if len(pos):
        if method == "wrp":
            record_on_planes(rt, out, pos, amp, g, obliquity, progress)
        else:
            add_points(rt, out, pos, amp, g, obliquity, binned=False, progress=progress)
    if np.ndim(amplitudes) == 1:
        out = out.reshape(g.shape)
    return out if as_device else out.get()


def sampling_grid(shape, wavelength, pitch, band) -> Grid:
    """The hologram's Grid, its cone narrowed to sin θ = ``band`` when given (checked)."""
    g = Grid(shape, *reversed(grid.wave(wavelength, pitch)))
    if band is None:
        return g
    most = CONE_FILL * g.wavelength / (2 * g.pitch)
    band = validate.finite("band", band)
    if not 0 < band <= most * (1 + 1e-9) or band >= 1:  # sin θ: no direction lies past 90°
        limit = f"(0, {most:.4g}]" if most < 1 else "(0, 1)"
        raise InputError(
            f"band must be in {limit} (sin θ of the cone the pitch samples); got {shown(band)}"
        )
    return g._replace(fill=band * 2 * g.pitch / g.wavelength)


def _points(positions, amplitudes):
    pos = np.asarray(positions, np.float64)
    amp = np.asarray(amplitudes, np.complex128)
    if pos.ndim != 2 or pos.shape[1] != 3:
        raise InputError(f"positions must be an (N, 3) array [m]; got shape {pos.shape}")
    if amp.ndim not in (1, 2) or len(amp) != len(pos) or (amp.ndim == 2 and not amp.shape[1]):
        raise InputError(
            f"amplitudes must be (N,) or (N, C) with N = {len(pos)} points; got shape {amp.shape}"
        )
    amp = amp[:, None] if amp.ndim == 1 else amp
    if not (np.isfinite(pos).all() and np.isfinite(amp).all()):
        raise InputError("positions and amplitudes must be finite")
    if len(pos) and pos[:, 2].max() >= 0:
        raise InputError(
            f"positions: every z must be < 0 m (in front of the hologram, light "
            f"travelling +z); the largest is {pos[:, 2].max():.4g} m"
        )
    return pos, amp


MIN_CONE_PITCHES = 2  # a point's cone must reach this many samples across on the plate


def safe_distance(g: Grid) -> float:
    """The least distance [m] from the plate at which a point's cone (tan θ = ``g.cone``) still
    spans ``MIN_CONE_PITCHES`` samples: nearer, the plate cannot sample its wave (its spot is
    smaller than a sample and 1/r grows without bound), so the recording would be wrong."""
    return max(g.pitch, MIN_CONE_PITCHES * g.pitch / g.cone)


def check_distance(pos, g: Grid) -> None:
    """:class:`InputError` naming the safe distance when a point is nearer to the plate."""
    if not len(pos):
        return
    safe, nearest = safe_distance(g), float(np.abs(pos[:, 2]).min())
    if nearest < safe:
        count = int((np.abs(pos[:, 2]) < safe).sum())
        raise InputError(
            f"positions: {count} point(s) lie closer to the plate than it can "
            f"record ({nearest:.3g} m, the nearest); at pitch {g.pitch:.3g} m and "
            f"λ = {g.wavelength:.3g} m points need |z| >= {safe:.3g} m (move the "
            f"objects back or use a finer pitch)"
        )


def direct_seconds(pos, g: Grid) -> float:
    seg = segment(pos[:, 2], g)
    pairs = pixels_reached(pos, g, pos[:, 2]) * (SEGMENTS[0] / seg)
    tiles = -(-g.shape[0] // CPU_LANES) * (-(-g.shape[1] // seg))
    return float(pairs.sum() / DIRECT_RATE + tiles.sum() / TILE_CHECKS)


def wrp_seconds(pos, g: Grid) -> float:
    if not math.isfinite(g.cone) or len(pos) == 0:
        return math.inf
    return slab_plan(pos, g)[1]


def cone_filter(field, *, wavelength, pitch, band=None):
    """``field`` (H, W) on the hologram (``pitch`` [m], ``wavelength`` [m]) limited to the
    directions the points' cones light (``band`` as for :func:`point_wave`), with the same soft
    rim in angle: for waves of other emitters (textured primitives) recorded with the points.
    Returns a complex64 NumPy array."""
    rt = get_runtime()
    dev = rt.to_device(np.asarray(field), np.complex64)
    g = sampling_grid(dev.shape, wavelength, pitch, band)
    padded = grid.padded_shape(dev.shape, 2)
    w, _ = cached(rt, ("cone-filter", padded, g), lambda: (cone_in_angle(padded, g)[0], ()))
    return convolve(rt, dev, w).get()
