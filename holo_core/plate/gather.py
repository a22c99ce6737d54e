"""The decimated samples of a carrier plate's window summed onto the plane waves of a camera's
entrance pupil (:class:`~holo_core.plate.to_pupil.CarrierPupil`'s last stage): a non-uniform
FFT. Each sample is spread onto a 2× oversampled grid of the pupil's spectrum bins by an
exponential-of-semicircle kernel (``SPREAD_TAPS`` a side), weighted by Rayleigh–Sommerfeld's
obliquity and distance (Eq. 7), layer by layer in depth so that each layer's curvature is
exact to ``LAYER_PHASE`` at the pupil's rim; the grid's transform and the kernel's
de-apodization are the pupil stage's.
"""

from __future__ import annotations

import math

import numpy as np
from numpy import float32, int32

from ..opencl.arrays import empty, exclusive_scan, extent, read
from ..opencl.kernel import BUFFER, REAL, kernel
from ..opencl.runtime import associated
from ..optics.imaging import SPECTRA
from ..propagation.tilt import ES_TABLE, cached_array, es_profile, es_table

PROGRAM = associated(__file__)

# the gather's ES kernel taps per axis: 1e-4 at 2x oversampling, as the image's read
# (optics/imaging.py TAPS); 6 cost twice as much for 1e-5
SPREAD_TAPS = 4
ES_TAPS = SPREAD_TAPS
# grid units a side of the cells the samples are listed by for the gather, each grid point reading a
# row of cells as one run of the list (1 is faster than 2: docs, Performance)
SPREAD_CELL = 1
LAYER_PHASE = math.pi / 2  # a layer's largest curvature error at the pupil's rim [rad]

# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
SPREAD = kernel(PROGRAM, "spread", out=BUFFER, grid_h=int32, grid_w=int32, row_first=int32,
                col_first=int32, v=BUFFER, wt=BUFFER, gy=BUFFER, gx=BUFFER, start=BUFFER,
                cells_h=int32, cells_w=int32, scale=float32, es=BUFFER)
PUPIL_LAYER = kernel(PROGRAM, "pupil_layer", u=BUFFER, g=BUFFER, h=int32, w=int32,
                     pairs=BUFFER, n=int32, dr=BUFFER, dc=BUFFER, dy=float32, dx=float32,
                     k=float32, z=float32, scale=float32)
GATHER_GEOMETRY = kernel(
    PROGRAM, "gather_geometry", gy=BUFFER, gx=BUFFER, wt=BUFFER, inv_depth=BUFFER, rows=int32,
    cols=int32, x0=REAL, xs=REAL, y0=REAL, ys=REAL, px=REAL, py=REAL, pz=REAL, rot=BUFFER,
    cy=REAL, cx=REAL, grid_units=REAL, w0=REAL)
GATHER_KEYS = kernel(PROGRAM, "gather_keys", key=BUFFER, count=BUFFER, gy=BUFFER, gx=BUFFER,
                     lo_y=float32, lo_x=float32, cells_h=int32, cells_w=int32)
GATHER_PLACE = kernel(PROGRAM, "gather_place", order=BUFFER, fill=BUFFER, key=BUFFER,
                      start=BUFFER)
# fmt: on
GATHER_SORT_CELLS = kernel(PROGRAM, "gather_sort_cells", order=BUFFER, start=BUFFER)
# the kernels' signatures as tables (their arguments in the .cl file's order)
# fmt: off
GATHER_PERMUTE = kernel(
    PROGRAM, "gather_permute", at_y=BUFFER, at_x=BUFFER, wt_at=BUFFER, inv_at=BUFFER,
    slot=BUFFER, order=BUFFER, gy=BUFFER, gx=BUFFER, wt=BUFFER, inv_depth=BUFFER)
LAYER_WEIGHTS = kernel(PROGRAM, "layer_weights", out=BUFFER, wt=BUFFER, inv_at=BUFFER,
                       lo=float32, step=float32, layers=int32, layer=int32)
# fmt: on


class Gather:
    """The decimated samples' way onto a pupil's spectrum grid, the same for every look and
    channel of a view: their grid coordinates (gy, gx: 2× oversampled bins, around the
    spectrum's centre), Rayleigh–Sommerfeld weights (Eq. 7: (q·pitch)²·cos θ/R, times 1/λ
    per wavelength), depth layers, and the cells of the grid they are listed by; ``view``: the
    :class:`~holo_core.plate.to_pupil.CarrierPupil` whose window it gathers, decimated by
    ``qy`` × ``qx`` samples."""

    def __init__(self, view, qy: int, qx: int):
        rt, h = view.rt, view.h
        self.view = view
        r0, r1, c0, c1 = view.window
        rows, cols = -(-(r1 - r0) // qy), -(-(c1 - c0) // qx)
        (x0,), (y0,) = h.carrier.coords(h.pitch, [r0], [c0])
        self.count = count = rows * cols
        real = rt.real
        # the samples' places on the grid, weights and depths: made on the device, as the
        # list below (a pass over every sample on the host costs a quarter of a view)
        gy, gx, wt, inv = (
            rt.workspace(f"gather-{name}", (count,), np.float32)
            for name in ("gy", "gx", "weight", "inverse-depth")
        )
        rot = rt.to_device(np.asarray(view.rotation), real)
        px, py, pz = view.position
        GATHER_GEOMETRY.launch(
            rt,
            (cols, rows),
            options=rt.real_options,
            gy=gy,
            gx=gx,
            wt=wt,
            inv_depth=inv,
            rows=rows,
            cols=cols,
            x0=x0,
            xs=qx * h.pitch,
            y0=y0,
            ys=qy * h.carrier.row_pitch,
            px=px,
            py=py,
            pz=pz,
            rot=rot,
            cy=view.centre[1],
            cx=view.centre[0],
            grid_units=2 / view.bin,
            w0=qx * h.pitch * qy * h.carrier.row_pitch * pz,
        )
        (gy_lo, gy_hi), (gx_lo, gx_hi), self.inverse_depth = map(extent, (gy, gx, inv))
        hh, ww = view.shape
        # only the grid points the samples reach: their box in grid coordinates, in cells
        self.lo = (
            max(math.floor(gy_lo - ES_TAPS / 2), -hh),
            max(math.floor(gx_lo - ES_TAPS / 2), -ww),
        )
        self.hi = (
            min(math.ceil(gy_hi + ES_TAPS / 2), hh - 1),
            min(math.ceil(gx_hi + ES_TAPS / 2), ww - 1),
        )
        self.cells = tuple(max(-(-(b - a + 1) // SPREAD_CELL), 1) for a, b in zip(self.lo, self.hi))
        # the list: by cell, a cell's samples by index (a stable sort by cell)
        n_cells = self.cells[0] * self.cells[1]
        key = rt.workspace("gather-key", (count,), np.int32)
        counts = rt.workspace("gather-count", (n_cells + 1,), np.int32)
        counts.fill(0)
        GATHER_KEYS.launch(
            rt,
            (count,),
            options=(f"-DCELL={SPREAD_CELL}",),
            key=key,
            count=counts,
            gy=gy,
            gx=gx,
            lo_y=self.lo[0],
            lo_x=self.lo[1],
            cells_h=self.cells[0],
            cells_w=self.cells[1],
        )
        self.start = empty(rt, (n_cells + 1,), np.int32)
        exclusive_scan(rt, counts, self.start)
        order, fill = (
            rt.workspace(f"gather-{name}", shape, np.int32)
            for name, shape in (("order", (count,)), ("fill", (n_cells,)))
        )
        fill.fill(0)
        GATHER_PLACE.launch(rt, (count,), order=order, fill=fill, key=key, start=self.start)
        GATHER_SORT_CELLS.launch(rt, (n_cells,), order=order, start=self.start)
        self.at = [empty(rt, (count,), np.float32) for _ in range(2)]
        self.weight, self.inverse = (empty(rt, (count,), np.float32) for _ in range(2))
        # where the decimation puts each sample: in the gather's order, planes side by side
        self.slot = empty(rt, (count,), np.int32)
        GATHER_PERMUTE.launch(
            rt,
            (count,),
            at_y=self.at[0],
            at_x=self.at[1],
            wt_at=self.weight,
            inv_at=self.inverse,
            slot=self.slot,
            order=order,
            gy=gy,
            gx=gx,
            wt=wt,
            inv_depth=inv,
        )
        self.deapod = [es_profile(rt, n, ES_TAPS) for n in (hh, ww)]
        self.layers = {}

    def _layers(self, wavelength):
        """(planar distance [m], sorted weights on the device) per depth layer: spaced in 1/z
        so that the curvature error at the pupil's rim stays within LAYER_PHASE (the camera
        hologram's rule)."""
        key = round(wavelength, 12)
        if key not in self.layers:
            lo, hi = self.inverse_depth
            step = 16 * LAYER_PHASE * wavelength / (2 * math.pi * self.view.diameter**2)
            n = max(1, int(math.ceil((hi - lo) / step)))
            edges = np.linspace(lo, hi, n + 1)
            if n == 1:
                self.layers[key] = [(2 / (lo + hi), self.weight)]
            else:  # the layers that hold samples
                which = np.clip(np.floor((read(self.inverse) - lo) / ((hi - lo) / n)), 0, n - 1)
                self.layers[key] = [
                    (2 / (edges[i] + edges[i + 1]), self._layer(i, n, lo, hi))
                    for i in np.unique(which).astype(int)
                ]
        return self.layers[key]

    def _layer(self, i, n, lo, hi):
        """The sorted weights of layer ``i`` of ``n`` spread evenly over the inverse depths
        ``lo`` … ``hi`` [1/m], 0 for the other layers' samples (a device array)."""
        rt = self.view.rt
        out = empty(rt, (self.count,), np.float32)
        LAYER_WEIGHTS.launch(
            rt,
            (self.count,),
            out=out,
            wt=self.weight,
            inv_at=self.inverse,
            lo=lo,
            step=(hi - lo) / n,
            layers=n,
            layer=i,
        )
        return out

    def pupil(self, values, runs, out, scale):
        """Added into ``out`` (device (P, h, w)): the pupil fields of the decimated samples
        ``values`` (device (samples, planes), the gather's order), times ``scale``, ``runs`` saying which:
        (first plane of ``values``, first plane of ``out``, planes, wavelength [m]). All
        planes are spread at once onto the 2× oversampled spectrum grid per depth layer (the
        layers of the shortest wavelength: a quarter wave at the rim for every one),
        transformed, deapodized and curved by the layer's distance at each wavelength."""
        view = self.view
        rt = view.rt
        hh, ww = view.shape
        planes = values.shape[1]
        es = cached_array(rt, "es-table", es_table, ES_TAPS)
        options = (
            f"-DCHANNELS={planes}",
            f"-DES_TAPS={ES_TAPS}",
            f"-DES_TABLE={ES_TABLE}",
            f"-DCELL={SPREAD_CELL}",
        )
        grid_shape = (2 * hh, 2 * ww)
        if self.hi[0] < self.lo[0] or self.hi[1] < self.lo[1]:
            return
        # the buffer of the imager's spectra (PupilImage.fold), of this shape: the grids are
        # spent once their layers are in ``out``, and a view keeps one stack, not two
        spread = rt.workspace(SPECTRA, (planes,) + grid_shape)
        # each wavelength's (plane of out, plane of the grids): its curvature found once
        planes_by_wavelength = {}
        for first, to, n, wavelength in runs:
            planes_by_wavelength.setdefault(wavelength, []).extend(
                (to + i, first + i) for i in range(n)
            )
        planes_by_wavelength = {
            lam: rt.to_device(np.array(p, np.int32)) for lam, p in planes_by_wavelength.items()
        }
        for z, weight in self._layers(min(run[3] for run in runs)):
            spread.fill(0)
            SPREAD.launch(
                rt,
                (self.hi[1] - self.lo[1] + 1, self.hi[0] - self.lo[0] + 1),
                options=options,
                out=spread,
                grid_h=grid_shape[0],
                grid_w=grid_shape[1],
                row_first=self.lo[0],
                col_first=self.lo[1],
                v=values,
                wt=weight,
                gy=self.at[0],
                gx=self.at[1],
                start=self.start,
                cells_h=self.cells[0],
                cells_w=self.cells[1],
                scale=scale,
                es=es,
            )
            # every plane in place; only the pupil's columns are read (pupil_layer)
            rt.fft.backward(spread, read=[(0, (ww + 1) // 2), (2 * ww - ww // 2, 2 * ww)])
            for wavelength, pairs in planes_by_wavelength.items():
                dy, dx = wavelength / (hh * view.bin), wavelength / (ww * view.bin)
                PUPIL_LAYER.launch(
                    rt,
                    (ww, hh),
                    u=out,
                    g=spread,
                    h=hh,
                    w=ww,
                    pairs=pairs,
                    n=pairs.shape[0],
                    dr=self.deapod[0],
                    dc=self.deapod[1],
                    dy=dy,
                    dx=dx,
                    k=2 * math.pi / wavelength,
                    z=z,
                    scale=1 / wavelength,
                )
