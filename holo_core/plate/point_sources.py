"""Object waves of point emitters on the hologram plane z = 0 (Eq. 3, Sect. V-B).

Two methods compute the same sum:

``direct``
    every point–pixel pair, by the segment-recurrence kernel ``point_sources.cl``;
``wrp``
    wavefront recording planes (Shimobaba et al. 2009): points are cut into depth slabs; each
    slab's points are summed directly onto a plane just in front of them, where their cones are
    small, and that plane is carried to the hologram by the angular spectrum (Eq. 14).

Each point lights only the cone its pitch samples alias-free: ρ ≤ |z|·tan θ with
sin θ = λ/(2·pitch) (the disc whose local spatial frequency stays below Nyquist).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy import int32

from .. import jobs, memory, validate
from ..opencl import associated, get_runtime
from ..opencl.arrays import cached, empty, fill, window
from ..opencl.kernel import BUFFER, REAL, kernel
from ..propagation import grid
from ..propagation.convolution import chirp_transfer, convolve
from ..validate import InputError, shown

PROGRAM = associated(__file__)

SEGMENTS = (32, 16, 8, 4)  # columns per recurrence segment, longest first (error ~ SEG³)
PHASE_TOLERANCE = 5e-5  # rad, the recurrence's largest phase error (see ``segment``) ...
WRP_PHASE_TOLERANCE = 2e-3  # ... and on recording planes, whose method errs by ~5e-3 anyway
CONE_FILL = 0.8  # a point's cone ends at this fraction of the Nyquist angle ...
CONE_RIM = 0.5  # ... and its outer fraction (of the radius) is a soft rim
WRP_WIDEN, WRP_RIM = 1.5, 0.17  # on a recording plane the cone reaches 1.5x the band (past
# Nyquist for the full band: aliases land beyond the cone)
CPU_LANES = 16  # rows per work item on CPU devices, as a cost-model figure (Runtime.lanes)
PAIRS_PER_LAUNCH = 2e9  # point-pixel pairs per kernel launch, between progress reports
MIN_CONE_PIXELS = 32  # a recording plane keeps this many pixels of cone radius to its points
# pairs/s of the direct kernel at 32-column segments (the cost model of the automatic choice;
# shorter segments are proportionally slower) ...
DIRECT_RATE = 3.3e9
TILE_CHECKS = 3e8  # ... plus its point-tile cone tests per second (it bins nothing)
BINNED_RATE = 6e8  # pairs/s on recording planes (small cones: setup-bound)
FFT_SECONDS_PER_SAMPLE = 3.5e-8  # one plane carried to the hologram, per plane sample


class Grid(NamedTuple):
    """A plane's sampling, ``shape`` (rows, cols), ``pitch`` [m], ``wavelength`` [m], and the
    cone its points light: ``fill`` of the Nyquist angle, the outer ``rim`` of it soft."""

    shape: tuple[int, int]
    pitch: float
    wavelength: float
    fill: float = CONE_FILL
    rim: float = CONE_RIM

    @property
    def cone(self) -> float:
        """tan θ of the cone's edge (inf when it reaches beyond 90°)."""
        s = self.fill * self.wavelength / (2 * self.pitch)
        return math.inf if s >= 1 else s / math.sqrt(1 - s * s)


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
            _wrp(rt, out, pos, amp, g, obliquity, progress)
        else:
            _sum(rt, out, pos, amp, g, obliquity, binned=False, progress=progress)
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


def _pixels_reached(pos, g: Grid, z) -> np.ndarray:
    """Pixels inside each point's cone (clipped to the hologram's area)."""
    radius = np.abs(z) * min(g.cone, 1e6) / g.pitch
    return np.minimum(np.pi * radius**2, g.shape[0] * g.shape[1])


def direct_seconds(pos, g: Grid) -> float:
    seg = segment(pos[:, 2], g)
    pairs = _pixels_reached(pos, g, pos[:, 2]) * (SEGMENTS[0] / seg)
    tiles = -(-g.shape[0] // CPU_LANES) * (-(-g.shape[1] // seg))
    return float(pairs.sum() / DIRECT_RATE + tiles.sum() / TILE_CHECKS)


def wrp_seconds(pos, g: Grid) -> float:
    if not math.isfinite(g.cone) or len(pos) == 0:
        return math.inf
    return _slab_plan(pos, g)[1]


# --- the point sum on the device -------------------------------------------------------------


def cone_weight(rho2, rho_max2, rim=CONE_RIM):
    """The cone's weight at squared lateral distance ``rho2`` [m²] from a point whose cone
    reaches ``rho_max2`` [m²]: 1 inside, 1 - smoothstep over the rim, 0 outside. A hard rim
    would diffract as strongly as the wave itself (like a Poisson spot); the soft rim maps onto
    itself between planes (it depends on tan θ only), so direct and WRP sums agree."""
    inner2 = (1 - rim) ** 2 * rho_max2
    u = np.clip((rho2 - inner2) / (rho_max2 - inner2), 0, 1)
    return 1 - u * u * (3 - 2 * u)


def segment(z, g: Grid, tolerance=None) -> np.ndarray:
    """Per point, the longest recurrence segment whose phase error k·sinθ·h³/(2z²) (the cubic
    Taylor term over half a segment h, θ up to the cone's edge) stays below
    ``PHASE_TOLERANCE``."""
    k = 2 * np.pi / g.wavelength
    sin_max = min(1.0, g.fill * g.wavelength / (2 * g.pitch))
    seg = np.full(len(z), SEGMENTS[-1])
    for n in reversed(SEGMENTS[:-1]):
        h = n / 2 * g.pitch
        sin_path = np.minimum(1.0, sin_max + n * g.pitch / np.abs(z))
        ok = k * sin_path * h**3 / (2 * z * z) <= (tolerance or PHASE_TOLERANCE)
        seg = np.where(ok, n, seg)
    return seg


def _sum(rt, out, pos, amp, g: Grid, obliquity, *, binned, progress=None):
    """Add the points' waves to ``out`` (device array of ``g.shape``), by segment class."""
    seg = segment(pos[:, 2], g, WRP_PHASE_TOLERANCE if binned else PHASE_TOLERANCE)
    pairs = _pixels_reached(pos, g, pos[:, 2])
    done, total = 0.0, pairs.sum()
    for n in SEGMENTS:
        sel = seg == n
        if not sel.any():
            continue
        if binned:
            order, starts, reach = _bins(rt, pos[sel], g, n)
            dpos, damp = _upload(rt, pos[sel][order], amp[sel][order], g.wavelength)
            _launch(
                rt, out, dpos, damp, g, obliquity, n, bins=(rt.to_device(starts, np.int32), reach)
            )
            continue
        dpos, damp = _upload(rt, pos[sel], amp[sel], g.wavelength)
        per_launch = max(1, int(PAIRS_PER_LAUNCH / (g.shape[0] * g.shape[1])))
        cum = np.cumsum(pairs[sel])
        for first in range(0, int(sel.sum()), per_launch):
            last = min(int(sel.sum()), first + per_launch)
            _launch(rt, out, dpos, damp, g, obliquity, n, first=first, last=last)
            rt.queue.finish()
            jobs.report(progress, done + cum[last - 1], total)
        done += cum[-1]


# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
POINT_WAVE = kernel(PROGRAM, "point_wave", out=BUFFER, h=int32, w=int32, pitch=REAL, x0=REAL,
                    y0=REAL, k=REAL, cone2=REAL, inner2=REAL, px=BUFFER, py=BUFFER,
                    pz=BUFFER, amp=BUFFER, first=int32, last=int32, binned=int32,
                    bin_start=BUFFER, reach_x=int32, reach_y=int32)
# fmt: on


def _launch(rt, out, pos, amp, g: Grid, obliquity, seg, *, first=0, last=None, bins=None):
    lanes = rt.lanes
    channels = amp.shape[1]
    options = (
        (f"-DVEC={lanes}", f"-DSEG={seg}", f"-DCHANNELS={channels}", "-cl-fast-relaxed-math")
        + rt.real_options
        + (("-DOBLIQUITY",) if obliquity else ())
    )
    h, w = g.shape
    x0, y0 = -(w - 1) / 2 * g.pitch, -(h - 1) / 2 * g.pitch
    cone2 = min(g.cone, 1e15) ** 2
    k = 2 * np.pi / g.wavelength
    binned = bins is not None
    starts, (reach_x, reach_y) = bins if binned else (_dummy(rt), (0, 0))
    last = len(pos.x) if last is None else last
    POINT_WAVE.launch(
        rt,
        (-(-h // lanes), -(-w // seg)),
        rt.series_group,
        options=options,
        out=out,
        h=h,
        w=w,
        pitch=g.pitch,
        x0=x0,
        y0=y0,
        k=k,
        cone2=cone2,
        inner2=(1 - g.rim) ** 2,
        px=pos.x,
        py=pos.y,
        pz=pos.z,
        amp=amp,
        first=first,
        last=last,
        binned=binned,
        bin_start=starts,
        reach_x=reach_x,
        reach_y=reach_y,
    )


def _dummy(rt):
    if "point-dummy" not in rt.cache:
        rt.cache["point-dummy"] = rt.to_device(np.zeros(1, np.int32))
    return rt.cache["point-dummy"]


class _DevicePoints(NamedTuple):
    x: object
    y: object
    z: object


def _upload(rt, pos, amp, wavelength):
    """Points as separate arrays; the carrier exp(ik|z|) folded into the amplitude in float64."""
    carrier = np.exp(1j * np.remainder(2 * np.pi / wavelength * np.abs(pos[:, 2]), 2 * np.pi))
    dev = _DevicePoints(*(rt.to_device(pos[:, i], rt.real) for i in range(3)))
    return dev, rt.to_device(amp * carrier[:, None], np.complex64)


# --- wavefront recording planes ---------------------------------------------------------------


def _slab_plan(pos, g: Grid):
    """Slab edges (far to near, [m]) and the modelled seconds, for the cheapest slab thickness."""
    z = np.sort(pos[:, 2])
    depth = z[-1] - z[0]
    best = (None, math.inf)
    for slabs in (1, 2, 4, 8, 16, 32, 64, 128, 256):
        edges = np.linspace(z[0], z[-1], slabs + 1)
        edges[-1] = np.nextafter(edges[-1], 0)
        plane = np.minimum(edges[_slab_of(z, edges) + 1] + _gap(g), 0)
        pairs = _pixels_reached(pos, _on_plane(g, g.shape), plane - z).sum()
        h, w = _plane_shape(g, plane.min())
        fft = slabs * h * w * FFT_SECONDS_PER_SAMPLE
        seconds = pairs / BINNED_RATE + fft
        if seconds < best[1]:
            best = (edges, seconds)
        if depth == 0:
            break
    return best


def _wrp(rt, out, pos, amp, g: Grid, obliquity, progress):
    edges, _ = _slab_plan(pos, g)
    gap, slabs = _gap(g), len(edges) - 1
    which = _slab_of(pos[:, 2], edges)
    w_shape = _plane_shape(g, min(edges[1] + gap, 0.0))  # one grid for all: one FFT plan
    for s in range(slabs):
        sel = which == s
        if sel.any():
            plane = min(pos[sel, 2].max() + gap, 0.0)
            _slab(rt, out, pos[sel], amp[sel], plane, g, w_shape, obliquity)
        jobs.report(progress, s + 1, slabs)


def _gap(g: Grid) -> float:
    """How far [m] a recording plane stays in front of its nearest point."""
    return MIN_CONE_PIXELS * g.pitch / g.cone


def _slab_of(z, edges) -> np.ndarray:
    """The slab index of each depth ``z`` [m] between ascending ``edges`` [m]."""
    return np.clip(np.searchsorted(edges, z, side="right") - 1, 0, len(edges) - 2)


def _on_plane(g: Grid, shape) -> Grid:
    """A recording plane's grid: its points light a cone wider than the hologram's band (the
    transfer function cuts the band with its own soft rim), not the plane's whole Nyquist cone,
    which would cost (Nyquist / band)² more pairs for a narrow band."""
    return g._replace(shape=shape, fill=WRP_WIDEN * g.fill, rim=WRP_RIM)


def _plane_shape(g: Grid, plane):
    """A recording plane at z = ``plane`` [m]: the hologram plus the margin its light crosses."""
    margin = math.ceil(abs(plane) * g.cone / g.pitch)
    return g.shape[0] + 2 * margin, g.shape[1] + 2 * margin


def _slab(rt, out, pos, amp, plane, g: Grid, w_shape, obliquity):
    """Add one slab's wave: summed on the plane z = ``plane`` [m], carried to z = 0."""
    local = pos - (0.0, 0.0, plane)
    if plane == 0:  # the slab touches the hologram: sum directly, its cones are small
        _sum(rt, out, local, amp, g, obliquity, binned=True)
        return
    wrp = empty(rt, out.shape[:1] + w_shape)
    fill(rt, wrp, 0)
    _sum(rt, wrp, local, amp, _on_plane(g, w_shape), obliquity, binned=True)
    padded = tuple(grid.next_fast_len(n) for n in w_shape)  # no wrap: the margin holds it

    wg, _ = cached(rt, ("wrp-chirp", padded, g), lambda: (_chirp(padded, g), ()))
    carrier = math.remainder(-2 * math.pi * plane / g.wavelength, 2 * math.pi)
    r0, c0 = (w_shape[0] - g.shape[0]) // 2, (w_shape[1] - g.shape[1]) // 2
    for c in range(len(out)):
        at_hologram = convolve(rt, wrp[c], chirp_transfer(rt, wg, carrier, -plane))
        out[c] += window(rt, at_hologram, g.shape, r0, c0)


def _chirp(shape, g: Grid) -> np.ndarray:
    """(w, g) packed as complex: the transfer function from a recording plane at distance d is
    w·exp(ikd - i·d·g) (the stable form of exp(i2πd·fz)), w the hologram's cone as angles and
    the inverse FFT's 1/N; evanescent waves have w = 0."""
    w, f2, fz = _cone_in_angle(shape, g)
    return w + 1j * (2 * np.pi * f2 / (1 / g.wavelength + fz))


def _cone_in_angle(shape, g: Grid):
    """(w, f², fz) on the FFT grid of ``shape``: w the cone's weight at each direction (the
    soft rim of :func:`cone_weight` in tan θ) over the inverse FFT's N, 0 for evanescent waves."""
    fy, fx = grid.freqs(shape[0], g.pitch)[:, None], grid.freqs(shape[1], g.pitch)[None, :]
    f2 = fx * fx + fy * fy
    fz2 = 1 / g.wavelength**2 - f2
    w = np.where(fz2 > 0, cone_weight(f2 / np.maximum(fz2, 1e-300), g.cone**2, g.rim), 0)
    return w / (shape[0] * shape[1]), f2, np.sqrt(np.maximum(fz2, 0))


def cone_filter(field, *, wavelength, pitch, band=None):
    """``field`` (H, W) on the hologram (``pitch`` [m], ``wavelength`` [m]) limited to the
    directions the points' cones light (``band`` as for :func:`point_wave`), with the same soft
    rim in angle: for waves of other emitters (textured primitives) recorded with the points.
    Returns a complex64 NumPy array."""
    rt = get_runtime()
    dev = rt.to_device(np.asarray(field), np.complex64)
    g = sampling_grid(dev.shape, wavelength, pitch, band)
    padded = grid.padded_shape(dev.shape, 2)
    w, _ = cached(rt, ("cone-filter", padded, g), lambda: (_cone_in_angle(padded, g)[0], ()))
    return convolve(rt, dev, w).get()


def _bins(rt, pos, g: Grid, seg):
    """The points binned by the kernel tile that holds them (clipped to the grid): their sort
    order, each bin's first point in it (one entry per tile, and the end), and how many tiles
    (cols, rows) the widest cone reaches beyond its own."""
    lanes = rt.lanes
    h, w = g.shape
    ty_n, tx_n = -(-h // lanes), -(-w // seg)
    tx = np.clip(np.floor((pos[:, 0] / g.pitch + (w - 1) / 2) / seg), 0, tx_n - 1)
    ty = np.clip(np.floor((pos[:, 1] / g.pitch + (h - 1) / 2) / lanes), 0, ty_n - 1)
    tile = ty.astype(np.int64) * tx_n + tx.astype(np.int64)
    order = np.argsort(tile, kind="stable")
    starts = np.concatenate([[0], np.cumsum(np.bincount(tile, minlength=ty_n * tx_n))])
    reach = min(np.abs(pos[:, 2]).max() * min(g.cone, 1e6) / g.pitch + 1, max(h, w))
    return order, starts, (math.ceil(reach / seg) + 1, math.ceil(reach / lanes) + 1)
