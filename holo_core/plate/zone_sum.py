"""The plate's samples as a sum over emitters, against the carrier converging on the zone.

What the plate stores is B(x) = O(x)·exp(+ik|x − Z|): the object wave O times the conjugate of
the spherical wave converging on the viewing zone's centre Z (:mod:`holo_core.plate.carrier`).
The light that reaches the zone from a plate point leaves it within the zone's angle around
the direction towards Z, so B is band-limited to that angle and sampled at its own Nyquist
pitch, however wide the angles between the plate's normal and the objects (facts §7).

B(x) = exp(ik|x − Z|) · Σ_j a_j·w_j(x)·exp(ik·r_j(x)) / r_j(x), r_j(x) = |x − p_j|, where w_j
keeps emitter j's light that leaves through x towards the zone (the box of the zone, a soft
rim around it, and the emitter's visibility from the zone point its ray reaches; Eq. 3 for
each emitter, evaluated exactly at every sample: no sampling of O itself). Each emitter
reaches only its footprint, the cone from it to the zone cut by the plate: the sum costs the
footprints' samples, not the plate's times the emitters'.

The kernel (``zone_sum.cl``) forms the phase exactly at each tile's centre (float64 where the
device has it) and follows it along rows by a recurrence, as the point sum does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy import float32, int32, int64

from ..opencl import get_runtime
from ..opencl.arrays import read
from ..opencl.kernel import BUFFER, REAL, kernel
from ..opencl.runtime import associated
from .plan import PARTNER_TURN, SEG

PROGRAM = associated(__file__)
# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
ZONE_SUM = kernel(
    PROGRAM, "zone_sum", out=BUFFER, first_plane=int32, row_first=int32, col_first=int32,
    oh=int32, ow=int32, pitch=REAL, row_pitch=REAL, x0=REAL, y0=REAL, k=REAL, k2=REAL, zx=REAL,
    zy=REAL, zz=REAL, ex=float32, ey=float32, ez=float32, rim_x=float32, rim_y=float32,
    px=BUFFER, py=BUFFER, pz=BUFFER, amp=BUFFER, amp2=BUFFER, shade=BUFFER, foot=BUFFER,
    vis_row=BUFFER, vis=BUFFER, g0x=float32, g0y=float32, gsx=float32, gsy=float32,
    list=BUFFER, start=BUFFER, blocks_x=int32, block=int32, block_row0=int32,
    block_col0=int32)
MIX_CLASSES = kernel(PROGRAM, "mix_classes", out=BUFFER, sums=BUFFER, mixing=BUFFER,
                     looks=int32, classes=int32, plane=int64)
# fmt: on

BLOCK = 256  # emitters are listed per BLOCK x BLOCK samples
SHARED_PHASE = 1e-6  # an emitter's channels whose amplitudes' phases agree to this share one


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class ZoneWindow:
    """Where the samples lie and the zone they serve, all in the plate's frame [m].

    origin : (x, y) of sample (row 0, column 0)
    pitch, row_pitch : the samples' spacing along x (columns) and y (rows) [m]
    shape : (rows, cols) of the whole window
    centre : Z (3,), the zone's centre (the carrier converges on it)
    half_extents : (3,) the zone box's half widths
    rim : the soft rim's width, a fraction of the half widths in x and y
    """

    origin: tuple
    pitch: float
    row_pitch: float
    shape: tuple
    centre: tuple
    half_extents: tuple
    rim: float


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class ZoneEmitters:
    """Emitters in the plate's frame with what the sum needs of them.

    position : (n, 3) [m], z < 0
    amplitude : (n, C) complex, a_j per channel (the random phase included; |a_j| carries the
        distance to the zone's centre so that the zone sees √I)
    visibility : (n,) int row of ``table`` (−1: seen from the whole zone)
    table : (m, Gy, Gx) uint8, the visibility 0…255 from the zone's Gy × Gx grid points
    grid : ((x0, step_x), (y0, step_y)) of the grid points, relative to the zone's centre [m]
    classes, mixing : optional, for L looks of C channels each (amplitude (n, L·C), look after
        look) that differ by a phase factor per emitter taken from a few values (coded looks):
        each emitter's class (n,) int and the factors (L, K) complex, look l's amplitudes
        mixing[l, classes]·(look 0's). The sum then runs once per class with look 0's C
        channels and mixes the classes' sums into the looks: a look costs no more emitter
        work (the coded pair: 4 channels an emitter, not 8)
    """

    position: np.ndarray
    amplitude: np.ndarray
    visibility: np.ndarray
    table: np.ndarray
    grid: tuple
    classes: np.ndarray | None = None
    mixing: np.ndarray | None = None


def shared_phase(a: np.ndarray, tolerance=SHARED_PHASE):
    """(w (n,) complex64, s (n, C) float32) with a = w[:, None]·s, where each row of the
    amplitudes ``a`` (n, C) shares one phase (an emitter's colours: √I_c times its wave), to
    ``tolerance`` of its largest; None where any row does not."""
    a = np.asarray(a, np.complex128)
    if not a.size:
        return np.zeros(len(a), np.complex64), np.zeros(a.shape, np.float32)
    w = a[np.arange(len(a)), np.abs(a).argmax(1)]
    ratio = a / np.where(w == 0, 1, w)[:, None]
    if np.abs(ratio.imag).max() > tolerance:
        return None
    return w.astype(np.complex64), ratio.real.astype(np.float32)


def _partner_ratio(partner, w):
    """(w, ρ) (n,) complex64 for the partner carried by the colours' light: the colours'
    shared amplitude ``w`` (the partner's own where an emitter's colours are all 0: their
    shares are 0 then) and the partner's amplitude ``partner`` over it."""
    w = np.asarray(w, np.complex128)
    black = w == 0
    w[black] = partner[black]
    return w.astype(np.complex64), (partner / np.where(w == 0, 1, w)).astype(np.complex64)


def footprints(position, window: ZoneWindow) -> np.ndarray:
    """(n, 4) int: the sample ranges (c0, c1, r0, r1), inclusive, that each emitter's cone
    towards the zone (its box widened by the rim) covers on the plate, clipped to the window
    (c1 < c0 where it misses)."""
    p = np.asarray(position, np.float64)
    c = np.asarray(window.centre)
    e = np.asarray(window.half_extents) * np.array([1 + window.rim, 1 + window.rim, 1.0])
    # the cone's rays through the box's near and far faces (z = c_z ∓ e_z): on each face's
    # plane the ray p -> q crosses the plate at p + t·(q - p), t = -p_z / (q_z - p_z) in
    # (0, 1) (the emitters behind the plate, the zone before it), so the face's corners at
    # -e and +e bound the footprint along x and y, each face's with its own t
    px, py, pz = p.T
    lo, hi = [np.inf, np.inf], [-np.inf, -np.inf]
    for sz in (-1, 1):
        t = -pz / (c[2] + sz * e[2] - pz)
        for i, q in enumerate((px, py)):
            lo[i] = np.minimum(lo[i], q + t * (c[i] - e[i] - q))
            hi[i] = np.maximum(hi[i], q + t * (c[i] + e[i] - q))
    lo, hi = np.stack(lo, 1), np.stack(hi, 1)
    o, dx, dy = np.asarray(window.origin), window.pitch, window.row_pitch
    h, w = window.shape
    c0 = np.maximum(np.floor((lo[:, 0] - o[0]) / dx), 0)
    c1 = np.minimum(np.ceil((hi[:, 0] - o[0]) / dx), w - 1)
    r0 = np.maximum(np.floor((lo[:, 1] - o[1]) / dy), 0)
    r1 = np.minimum(np.ceil((hi[:, 1] - o[1]) / dy), h - 1)
    return np.stack([c0, c1, r0, r1], 1).astype(np.int32)


def block_lists(foot, shape, block=BLOCK, region=None) -> tuple[np.ndarray, np.ndarray, tuple]:
    """(list, start, (blocks_y, blocks_x, first row, first column of blocks)): the emitters
    whose footprint overlaps each block of ``block``² samples of ``region`` (row0, col0, rows,
    cols; default the whole ``shape``), block b's (counted from the region's first block) in
    list[start[b]:start[b + 1]]. Only the region's blocks are listed: a tile's lists cost
    what the tile holds, not the plate."""
    h, w = shape
    row0, col0, rows, cols = region or (0, 0, h, w)
    br0, bc0 = row0 // block, col0 // block
    by, bx = (row0 + rows - 1) // block - br0 + 1, (col0 + cols - 1) // block - bc0 + 1
    f = foot.astype(np.int64) // block
    c0, c1 = np.maximum(f[:, 0], bc0) - bc0, np.minimum(f[:, 1], bc0 + bx - 1) - bc0
    r0, r1 = np.maximum(f[:, 2], br0) - br0, np.minimum(f[:, 3], br0 + by - 1) - br0
    ok = (foot[:, 1] >= foot[:, 0]) & (foot[:, 3] >= foot[:, 2]) & (c1 >= c0) & (r1 >= r0)
    j = np.nonzero(ok)[0]
    c0, c1, r0, r1 = c0[j], c1[j], r0[j], r1[j]
    nx, ny = c1 - c0 + 1, r1 - r0 + 1
    count = nx * ny
    emitter = np.repeat(j, count)
    q = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    col = np.repeat(c0, count) + q % np.repeat(nx, count)
    row = np.repeat(r0, count) + q // np.repeat(nx, count)
    b = row * bx + col
    order = np.argsort(b, kind="stable")
    start = np.searchsorted(b[order], np.arange(bx * by + 1)).astype(np.int32)
    return emitter[order].astype(np.int32), start, (int(by), int(bx), int(br0), int(bc0))


class ZoneSum:
    """The sum of ``em``'s channels over ``window`` at ``wavelength`` [m], and of ``partner``'s
    (λ2 [m], :class:`ZoneEmitters` of the same emitters: the depth pair's) in the same pass,
    its emitters on the device once; :meth:`region` computes any block of rows and columns
    (module docstring), the partner's channels after ``em``'s. The partner shares each
    emitter's geometry, window and visibility at a sample, and its set-up: summed apart it
    cost three quarters of the three colour channels' time for its one channel."""

    def __init__(
        self,
        em: ZoneEmitters,
        window: ZoneWindow,
        wavelength: float,
        rt=None,
        partner: tuple | None = None,
    ):
        self.rt = rt = rt or get_runtime()
        self.window, self.k = window, 2 * math.pi / wavelength
        self.k2 = 0.0 if partner is None else 2 * math.pi / partner[0]
        pos = np.asarray(em.position, np.float64)
        self.mixing = None if em.classes is None else np.asarray(em.mixing, np.complex64)
        groups = [(self.k, em)] + ([] if partner is None else [(self.k2, partner[1])])
        amps = [self._summed(k, e, pos, window) for k, e in groups]
        self.channels = sum(e.amplitude.shape[1] for _, e in groups)
        counts = [a.shape[1] for a in amps]
        self.planes = sum(counts)  # a class's sums: its channels an emitter
        amps, shade = self._factored(amps, partner is not None, window)
        self.foot = foot = footprints(pos, window)
        # (the emitters, their footprints) of each class; None: all of them, the looks summed
        # as channels
        self.members = (
            [(None, foot)]
            if self.mixing is None
            else [
                (m, foot[m])
                for m in (np.nonzero(em.classes == k)[0] for k in range(self.mixing.shape[1]))
            ]
        )
        self.pairs = float(
            np.sum(
                (foot[:, 1] - foot[:, 0] + 1.0).clip(0) * (foot[:, 3] - foot[:, 2] + 1.0).clip(0)
            )
        )
        table = em.table if len(em.table) else np.zeros((1, 2, 2), np.uint8)
        self.options = (
            f"-DVEC={rt.lanes}",
            f"-DSEG={SEG}",
            f"-DCHANNELS={counts[0]}",
            f"-DCHANNELS2={counts[1] if partner else 0}",
            f"-DSHADED={int(self.shaded)}",
            f"-DPARTNER_LERP={int(self.partner_lerp)}",
            f"-DGRID_Y={table.shape[1]}",
            f"-DGRID_X={table.shape[2]}",
            "-cl-fast-relaxed-math",
        ) + rt.real_options
        amp = [rt.to_device(np.ascontiguousarray(a, np.complex64)) for a in amps]
        self._mixing = None if self.mixing is None else rt.to_device(self.mixing)
        (g0x, gsx), (g0y, gsy) = em.grid
        # the emitters' arguments of the kernel, on the device as long as the sum lives
        self.args = dict(
            zip(("px", "py", "pz"), (rt.to_device(pos[:, i], rt.real) for i in range(3))),
            amp=amp[0],
            amp2=amp[-1],
            shade=rt.to_device(shade, np.float32),
            foot=rt.to_device(foot),
            vis_row=rt.to_device(np.asarray(em.visibility, np.int32)),
            vis=rt.to_device(np.ascontiguousarray(table, np.uint8)),
            g0x=g0x,
            g0y=g0y,
            gsx=gsx,
            gsy=gsy,
        )

    def _factored(self, amps, partner: bool, window) -> tuple[list, np.ndarray]:
        """The amplitudes as the kernel takes them, and the channels' real shares. Where each
        emitter's channels of a wavelength share one phase (``shaded``), one amplitude an
        emitter and wavelength; where the partner's light also turns from the colours' by
        (k2 - k)(r - |z|) at most PARTNER_TURN over a segment (|dr/dx| <= 1:
        ``partner_lerp``), the colours' amplitude and the partner's over it."""
        shared = [shared_phase(a) for a in amps]
        self.shaded = all(f is not None for f in shared)
        self.partner_lerp = (
            self.shaded
            and partner
            and amps[-1].shape[1] == 1
            and abs(self.k2 - self.k) * SEG * window.pitch <= PARTNER_TURN
        )
        if not self.shaded:
            return amps, np.zeros(1, np.float32)
        shade = np.concatenate([f[1] for f in shared], 1)
        if self.partner_lerp:
            return [a[:, None] for a in _partner_ratio(amps[1][:, 0], shared[0][0])], shade
        return [f[0][:, None] for f in shared], shade

    def _summed(self, k, em, pos, window) -> np.ndarray:
        """The amplitudes the kernel sums at wave number ``k`` [rad/m]: the carriers exp(ik|z_j|)
        of its phase and exp(ik·Z_z) of its epilogue folded in (float64), look 0's only where
        the classes mix them."""
        fold = np.exp(1j * np.remainder(k * (np.abs(pos[:, 2]) + window.centre[2]), 2 * math.pi))
        a = (
            em.amplitude
            if self.mixing is None
            else em.amplitude[:, : em.amplitude.shape[1] // len(self.mixing)]
        )
        return a * fold[:, None]

    def region(self, row0: int, col0: int, rows: int, cols: int) -> np.ndarray:
        """B (C, rows, cols) complex64 from sample (row0, col0); row0 and col0 multiples of
        the work items' tile (lanes, SEG)."""
        return read(self.on_device(row0, col0, rows, cols))

    def on_device(self, row0: int, col0: int, rows: int, cols: int):
        """As :meth:`region`, on the device: the runtime's workspace, valid until the next
        sum of any :class:`ZoneSum` of the runtime."""
        rt, win = self.rt, self.window
        sums = rt.workspace("zone-sum", (len(self.members) * self.planes, rows, cols))
        e = win.half_extents
        for k, (members, foot) in enumerate(self.members):
            lst, start, (_, blocks_x, block_row0, block_col0) = block_lists(
                foot, win.shape, region=(row0, col0, rows, cols)
            )
            if members is not None:
                lst = members[lst]
            ZONE_SUM.launch(
                rt,
                (-(-rows // rt.lanes), -(-cols // SEG)),
                rt.series_group,
                options=self.options,
                out=sums,
                first_plane=k * self.planes,
                row_first=row0,
                col_first=col0,
                oh=rows,
                ow=cols,
                pitch=win.pitch,
                row_pitch=win.row_pitch,
                x0=win.origin[0],
                y0=win.origin[1],
                k=self.k,
                k2=self.k2,
                **dict(zip(("zx", "zy", "zz"), win.centre)),
                ex=e[0],
                ey=e[1],
                ez=e[2],
                rim_x=win.rim * e[0],
                rim_y=win.rim * e[1],
                **self.args,
                list=rt.to_device(lst if len(lst) else np.zeros(1, np.int32), np.int32),
                start=rt.to_device(start),
                blocks_x=blocks_x,
                block=BLOCK,
                block_row0=block_row0,
                block_col0=block_col0,
            )
        if self.mixing is None:
            return sums
        out = rt.workspace("zone-sum-looks", (self.channels, rows, cols))
        looks, classes = self.mixing.shape
        MIX_CLASSES.launch(
            rt,
            (rows * cols, self.planes),
            options=self.options,
            out=out,
            sums=sums,
            mixing=self._mixing,
            looks=looks,
            classes=classes,
            plane=rows * cols,
        )
        return out


def zone_sum(
    em: ZoneEmitters, window: ZoneWindow, wavelength: float, region=None, rt=None
) -> np.ndarray:
    """B (C, rows, cols) complex64 over ``region`` (row0, col0, rows, cols) of the window
    (default: all of it) at ``wavelength`` [m] (module docstring)."""
    h, w = window.shape
    return ZoneSum(em, window, wavelength, rt).region(*(region or (0, 0, h, w)))
