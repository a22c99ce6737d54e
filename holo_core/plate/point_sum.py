"""The direct point sum on the device: every point–pixel pair inside each point's cone
(Eq. 3), by the segment-recurrence kernel ``point_sum.cl``.

Each point lights only the cone its pitch samples alias-free: ρ ≤ |z|·tan θ with
sin θ = λ/(2·pitch) (the disc whose local spatial frequency stays below Nyquist), its outer
rim soft (:func:`cone_weight`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy import int32

from .. import jobs
from ..opencl import associated
from ..opencl.kernel import BUFFER, REAL, kernel

PROGRAM = associated(__file__)

SEGMENTS = (32, 16, 8, 4)  # columns per recurrence segment, longest first (error ~ SEG³)
PHASE_TOLERANCE = 5e-5  # rad, the recurrence's largest phase error (see ``segment``) ...
WRP_PHASE_TOLERANCE = 2e-3  # ... and on recording planes, whose method errs by ~5e-3 anyway
CONE_FILL = 0.8  # a point's cone ends at this fraction of the Nyquist angle ...
CONE_RIM = 0.5  # ... and its outer fraction (of the radius) is a soft rim
CPU_LANES = 16  # rows per work item on CPU devices, as a cost-model figure (Runtime.lanes)
PAIRS_PER_LAUNCH = 2e9  # point-pixel pairs per kernel launch, between progress reports


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


def pixels_reached(pos, g: Grid, z) -> np.ndarray:
    """Pixels inside each point's cone (clipped to the hologram's area)."""
    radius = np.abs(z) * min(g.cone, 1e6) / g.pitch
    return np.minimum(np.pi * radius**2, g.shape[0] * g.shape[1])


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


def add_points(rt, out, pos, amp, g: Grid, obliquity, *, binned, progress=None):
    """Add the points' waves to ``out`` (device array of ``g.shape``), by segment class."""
    seg = segment(pos[:, 2], g, WRP_PHASE_TOLERANCE if binned else PHASE_TOLERANCE)
    pairs = pixels_reached(pos, g, pos[:, 2])
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
