"""Wavefront recording planes (Shimobaba et al. 2009): the points cut into depth slabs, each
slab's points summed directly onto a plane just in front of them, where their cones are small
(:func:`.point_sum.add_points`), and that plane carried to the hologram by the angular
spectrum (Eq. 14). Cheaper than the direct sum where the points lie far from the plate.
"""

from __future__ import annotations

import math

import numpy as np

from .. import jobs
from ..opencl.arrays import cached, empty, fill, window
from ..propagation import grid
from ..propagation.convolution import chirp_transfer, convolve
from .point_sum import Grid, add_points, cone_weight, pixels_reached

WRP_WIDEN, WRP_RIM = 1.5, 0.17  # on a recording plane the cone reaches 1.5x the band (past
# Nyquist for the full band: aliases land beyond the cone)
MIN_CONE_PIXELS = 32  # a recording plane keeps this many pixels of cone radius to its points
BINNED_RATE = 6e8  # pairs/s on recording planes (small cones: setup-bound)
FFT_SECONDS_PER_SAMPLE = 3.5e-8  # one plane carried to the hologram, per plane sample


def slab_plan(pos, g: Grid):
    """Slab edges (far to near, [m]) and the modelled seconds, for the cheapest slab thickness."""
    z = np.sort(pos[:, 2])
    depth = z[-1] - z[0]
    best = (None, math.inf)
    for slabs in (1, 2, 4, 8, 16, 32, 64, 128, 256):
        edges = np.linspace(z[0], z[-1], slabs + 1)
        edges[-1] = np.nextafter(edges[-1], 0)
        plane = np.minimum(edges[_slab_of(z, edges) + 1] + _gap(g), 0)
        pairs = pixels_reached(pos, _on_plane(g, g.shape), plane - z).sum()
        h, w = _plane_shape(g, plane.min())
        fft = slabs * h * w * FFT_SECONDS_PER_SAMPLE
        seconds = pairs / BINNED_RATE + fft
        if seconds < best[1]:
            best = (edges, seconds)
        if depth == 0:
            break
    return best


def record_on_planes(rt, out, pos, amp, g: Grid, obliquity, progress):
    edges, _ = slab_plan(pos, g)
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
        add_points(rt, out, local, amp, g, obliquity, binned=True)
        return
    wrp = empty(rt, out.shape[:1] + w_shape)
    fill(rt, wrp, 0)
    add_points(rt, wrp, local, amp, _on_plane(g, w_shape), obliquity, binned=True)
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
    w, f2, fz = cone_in_angle(shape, g)
    return w + 1j * (2 * np.pi * f2 / (1 / g.wavelength + fz))


def cone_in_angle(shape, g: Grid):
    """(w, f², fz) on the FFT grid of ``shape``: w the cone's weight at each direction (the
    soft rim of :func:`cone_weight` in tan θ) over the inverse FFT's N, 0 for evanescent waves."""
    fy, fx = grid.freqs(shape[0], g.pitch)[:, None], grid.freqs(shape[1], g.pitch)[None, :]
    f2 = fx * fx + fy * fy
    fz2 = 1 / g.wavelength**2 - f2
    w = np.where(fz2 > 0, cone_weight(f2 / np.maximum(fz2, 1e-300), g.cone**2, g.rim), 0)
    return w / (shape[0] * shape[1]), f2, np.sqrt(np.maximum(fz2, 0))
