"""Gigapixel plates: point emitters recorded tile by tile, out of core, as Dask tasks.

The plate's object wave (Eq. 3) is written tile by tile into a tiled store
(:mod:`holo_core.io.tiles`), so no process ever holds the whole plate: a task computes one
tile from the emitters whose cone reaches it (``point_sources``: a point lights only the disc
its pitch samples alias-free, ρ ≤ |z|·tan θ), writes it and sets its flag. Every tile is the
whole plate's recording cut to its rows and columns (the same sum, the same sample positions,
the same random phases), so a tiled plate equals the plate recorded in memory.

The tasks run on Dask's distributed scheduler: by default a local cluster with one worker
process per core (each its own OpenCL context), or the cluster at ``scheduler``
(``tcp://host:8786``, or the environment's ``DASK_SCHEDULER_ADDRESS``) with no other change;
the emitters are scattered to the workers once, not sent with every tile. Tiles already
flagged in the store are skipped, so a killed recording resumes where it stopped.
"""

from __future__ import annotations

import logging
import math
import os
from contextlib import contextmanager

import numpy as np

from .. import jobs, validate
from ..io import tiles as store
from ..scene.hologram import Hologram, HologramInfo
from ..validate import InputError
from .point_sources import check_distance, point_wave, sampling_grid
from .record import DEFAULT_WAVELENGTHS, point_amplitudes

log = logging.getLogger(__name__)
DEFAULT_TILE = 2048
TILE_STEP = 64  # tiles are multiples of this: the kernel's column segments (<= 32) align


def record_tiled(positions, colours, *, url, shape, pitch, wavelengths=DEFAULT_WAVELENGTHS,
                 tile=DEFAULT_TILE, phases=None, seed=0, band=None, plate=None, bounds=None,
                 channels=(), zone=None, method="direct", scheduler=None,
                 progress: jobs.Progress = None, dashboard=None) -> Hologram:
    """Record the complex plate of point emitters into the tiled store at ``url`` and return
    it opened (:func:`holo_core.io.tiles.open_plate`).

    positions, colours, wavelengths, phases, seed, band, method
        As for :func:`holo_core.plate.record.record_points` (positions [m] in the plate's
        frame, z < 0; colours: intensities, one column per wavelength [m]).
    url : str or path
        The store: a folder, or any fsspec URL the workers can reach. An existing store of
        the same plate is resumed (its written tiles are kept); one of another plate is
        refused.
    shape : (rows, cols) of the plate; pitch : sample spacing [m]
    tile : samples per tile side, a multiple of 64 (default 2048: 32 MiB per channel)
    plate, bounds, channels, zone
        Stored with the plate (:class:`holo_core.scene.hologram.Hologram`); bounds default to
        the points' box [m].
    scheduler : str, optional
        A Dask scheduler's address; default ``DASK_SCHEDULER_ADDRESS``, else a local cluster
        of one single-threaded worker per core.
    progress : callable, optional
        Called with the fraction of tiles done; raising :class:`holo_core.jobs.Cancelled`
        cancels the tasks not yet finished (the tiles written stay, for a resume).
    dashboard : callable, optional
        Called with the address of the cluster's dashboard (its task stream and progress).
    """
    pos, wavelengths, amp = point_amplitudes(positions, colours, wavelengths, phases, seed)
    shape = validate.shape2d("shape", shape)
    pitch = validate.pitch("pitch", pitch)
    tile = validate.integer("tile", tile, store.MIN_TILE, store.MAX_TILE)
    if tile % TILE_STEP:
        raise InputError(f"tile must be a multiple of {TILE_STEP} samples in "
                         f"[{store.MIN_TILE}, {store.MAX_TILE}]; got {tile}")
    validate.choice("method", method, ("direct", "wrp"))
    for lam in set(wavelengths):
        check_distance(pos, sampling_grid(shape, lam, pitch, band))
    info = HologramInfo(shape=shape, encoding="complex", wavelengths=wavelengths, pitch=pitch,
                        band=band or 0.0, plate=np.eye(4) if plate is None else plate,
                        channels=channels, zone=zone,
                        bounds=np.array([pos.min(0), pos.max(0)]) if bounds is None else bounds)
    store.create_plate(url, info, tile)
    todo = [(i, j) for i, j in zip(*np.nonzero(~store.tiles_done(url)))]
    log.info("%s: %d of %d tiles to record", url, len(todo), math.prod(store.tile_grid(shape,
                                                                                     tile)))
    if todo:
        spec = {"url": str(url), "shape": shape, "pitch": pitch, "tile": tile, "band": band,
                "wavelengths": wavelengths, "method": method}
        with client_for(scheduler) as client:
            if dashboard is not None:
                dashboard(client.dashboard_link)
            points = client.scatter((pos, amp), broadcast=True)
            futures = [client.submit(record_tile, points, spec, int(i), int(j), pure=False)
                       for i, j in todo]
            _wait(client, futures, progress)
    return store.open_plate(url)


def record_tile(points, spec: dict, i: int, j: int) -> tuple[int, int]:
    """One task: tile (i, j) of the plate ``spec`` describes, from the emitters ``points``
    (positions, amplitudes) whose cones reach it, written to the store."""
    pos, amp = points
    shape, pitch, tile = spec["shape"], spec["pitch"], spec["tile"]
    r0, r1, c0, c1 = store.tile_window(shape, tile, i, j)
    # the tile's centre in the plate's frame: its samples lie where the whole plate's do
    centre = np.array([((c0 + c1 - 1) / 2 - (shape[1] - 1) / 2) * pitch,
                       ((r0 + r1 - 1) / 2 - (shape[0] - 1) / 2) * pitch, 0.0])
    half = np.array([(c1 - c0) / 2 * pitch, (r1 - r0) / 2 * pitch])
    waves = np.zeros((len(spec["wavelengths"]), r1 - r0, c1 - c0), np.complex64)
    groups = {}
    for c, lam in enumerate(spec["wavelengths"]):
        groups.setdefault(lam, []).append(c)
    for lam, chans in groups.items():
        cone = sampling_grid(shape, lam, pitch, spec["band"]).cone
        reach = np.abs(pos[:, 2]) * cone + pitch
        gap = np.maximum(np.abs(pos[:, :2] - centre[:2]) - half, 0)
        near = (gap ** 2).sum(1) <= reach ** 2
        if near.any():
            waves[chans] = point_wave(pos[near] - centre, amp[near][:, chans], wavelength=lam,
                                      pitch=pitch, shape=(r1 - r0, c1 - c0),
                                      band=spec["band"], method=spec["method"])
    store.write_tile(spec["url"], i, j, waves)
    return i, j


@contextmanager
def client_for(scheduler=None):
    """A Dask client: of the scheduler at ``scheduler`` (or ``DASK_SCHEDULER_ADDRESS``), else
    of a local cluster with one single-threaded worker process per core (each worker holds
    its own OpenCL context); its dashboard's address is logged."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise InputError("tiled plates need Dask: pip install 'holo[tiles]'") from None
    address = scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS")
    if address:
        with Client(address) as client:
            log.info("Dask scheduler %s, dashboard %s", address, client.dashboard_link)
            yield client
        return
    with LocalCluster(n_workers=os.cpu_count() or 1, threads_per_worker=1, processes=True,
                      dashboard_address=":0") as cluster, Client(cluster) as client:
        log.info("local Dask cluster, dashboard %s", client.dashboard_link)
        yield client


def _wait(client, futures, progress) -> None:
    """Each task's result as it finishes, with the fraction done to ``progress``; on a
    cancellation or a failed task the rest are cancelled."""
    from distributed import as_completed
    try:
        for n, future in enumerate(as_completed(futures), 1):
            future.result()  # a failed tile raises its error here
            jobs.report(progress, n, len(futures))
    except BaseException:
        client.cancel(futures)
        raise
