"""Gigapixel plates: recorded tile by tile, out of core, as Dask tasks.

The plate's samples are written tile by tile into a tiled store (:mod:`holo_core.io.store`),
so no process ever holds the whole plate: a task computes one tile, writes it and its record.
Every tile is the whole plate's recording cut to its rows and columns (the same sums, the same
sample positions, the same phases), so a tiled plate equals the plate recorded in memory.

- Point emitters (:func:`record_tiled`): a tile sums the emitters whose cone reaches it
  (``point_sources``: a point lights only the disc its pitch samples alias-free).
- Plates of meshes (:func:`record_looks_tiled`), with occlusion, against the carrier
  converging on their zone: the emitters the zone sees and their visibility tables are found
  once, on the client (:func:`holo_core.plate.recording.prepare_plate`); a tile is
  :meth:`ZoneSum.region <holo_core.plate.zone_sum.ZoneSum.region>` of its block, from the
  emitters whose footprint reaches it.

The tasks run on Dask's distributed scheduler: by default a local cluster with one worker
process per core (each its own OpenCL context), or the cluster at ``scheduler``
(``tcp://host:8786``, or the environment's ``DASK_SCHEDULER_ADDRESS``) with no other change;
the emitters are scattered to the workers once, not sent with every tile (a worker puts them
on its device once). A store holds one recording (the digest of what its samples depend on):
the same call again resumes it, keeping the tiles that read back whole and writing again those
missing or damaged; another recording is refused by name (or replaces it with ``overwrite``),
and two recordings never write one store at once (its lock).
"""

from __future__ import annotations

import contextlib
import logging
from dataclasses import replace

import numpy as np

from .. import cluster, jobs, validate
from ..io import digests, store
from ..io.files import StoreError, check_output
from ..io.tiled_wave import open_plate
from ..scene.hologram import Hologram, HologramInfo
from ..validate import InputError
from .point_sources import check_distance, sampling_grid
from .points import DEFAULT_WAVELENGTHS, point_amplitudes
from .recording import PlannedPlate, PlateRecording, prepare_plate
from .tile_tasks import record_plate_tile, record_tile
from .zone_sum import BLOCK

log = logging.getLogger(__name__)
DEFAULT_TILE = 2048
TILE_STEP = 64  # point tiles are multiples of this: the kernel's column segments (<= 32) align
ZONE_TILE_STEP = BLOCK  # a plate of meshes' tiles: multiples of its emitters' block lists


def record_tiled(
    positions,
    colours,
    *,
    url,
    shape,
    pitch,
    wavelengths=DEFAULT_WAVELENGTHS,
    tile=DEFAULT_TILE,
    phases=None,
    seed=0,
    band=None,
    plate=None,
    bounds=None,
    channels=(),
    zone=None,
    method="direct",
    scheduler=None,
    overwrite=False,
    progress: jobs.Progress = None,
    dashboard=None,
) -> Hologram:
    """Record the complex plate of point emitters into the tiled store at ``url`` and return
    it opened (:func:`holo_core.io.tiled_wave.open_plate`).

    positions, colours, wavelengths, phases, seed, band, method
        As for :func:`holo_core.plate.points.record_points` (positions [m] in the plate's
        frame, z < 0; colours: intensities, one column per wavelength [m]).
    url : str or path
        The store: a folder (made absolute before the workers see it), or an fsspec URL the
        workers can reach (not ``memory://``). It is checked before the work: a file in the
        way, a folder that takes no new file, a protocol whose package is missing, a folder
        or Zarr group that is not a Holo store are refused. A store of the same recording is
        resumed (its tiles that read back whole are kept); one of another recording is
        refused, naming both.
    shape : (rows, cols) of the plate; pitch : sample spacing [m]
    tile : samples per tile side, a multiple of 64 (default 2048: 32 MiB per channel)
    plate, bounds, channels, zone
        Stored with the plate (:class:`holo_core.scene.hologram.Hologram`); bounds default to
        the points' box [m].
    scheduler : str, optional
        A Dask scheduler's address; default ``DASK_SCHEDULER_ADDRESS``, else a local cluster
        of one single-threaded worker per core. One that cannot be reached within
        ``CONNECT_TIMEOUT`` seconds, refuses, or answers other than a scheduler is an
        :class:`InputError` naming it, and leaves no store behind.
    overwrite : bool
        Replace a store of another recording at ``url`` (never data that is not a Holo store).
    progress : callable, optional
        Called with the fraction of tiles done; raising :class:`holo_core.jobs.Cancelled`
        cancels the tasks not yet finished (the tiles written stay, for a resume).
    dashboard : callable, optional
        Called with the address of the cluster's dashboard (its task stream and progress).
    """
    pos, wavelengths, amp = point_amplitudes(positions, colours, wavelengths, phases, seed)
    shape = validate.shape2d("shape", shape)
    pitch = validate.pitch("pitch", pitch)
    tile = _tile(tile, TILE_STEP)
    validate.choice("method", method, ("direct", "wrp"))
    _flag("overwrite", overwrite)
    for lam in set(wavelengths):
        check_distance(pos, sampling_grid(shape, lam, pitch, band))
    info = HologramInfo(
        shape=shape,
        encoding="complex",
        wavelengths=wavelengths,
        pitch=pitch,
        band=band or 0.0,
        plate=np.eye(4) if plate is None else plate,
        channels=channels,
        zone=zone,
        bounds=np.array([pos.min(0), pos.max(0)]) if bounds is None else bounds,
    )
    files, address = _output_and_scheduler([url], scheduler)
    recording = _recording(
        pos,
        colours,
        phases,
        seed,
        method=method,
        shape=shape,
        pitch=pitch,
        band=band,
        wavelengths=wavelengths,
        tile=tile,
    )
    _record_tiles(
        files,
        info,
        tile,
        [recording],
        overwrite=overwrite,
        address=address,
        task=record_tile,
        shared=(pos, amp),
        progress=progress,
        dashboard=dashboard,
    )
    return open_plate(files[0].name)


def record_looks_tiled(
    planned: PlannedPlate,
    *,
    urls,
    codes=None,
    seed=0,
    encoding="complex",
    scheduler=None,
    overwrite=False,
    progress: jobs.Progress = None,
    dashboard=None,
    recording="",
    phases="random",
) -> list[Hologram]:
    """The looks ``codes`` of the plate of meshes ``planned`` (with occlusion, against the
    carrier converging on its zone: :func:`holo_core.plate.recording.plate_plan`; the other
    arguments as :func:`holo_core.plate.looks.record_plate` takes them; look l coded by
    codes[l], or where that is None of seed + l; default: the plan's looks), each into its
    own tiled store at ``urls`` [l], returned opened
    (:func:`holo_core.io.tiled_wave.open_plate`).

    The emitters and their visibility tables are found once, here, and scattered once to the
    workers; each task sums one tile (the plan's ``tile`` samples a side, a multiple of
    256: the emitters' block lists; its budget checked as it was planned) for every look at
    once (as :func:`holo_core.plate.looks.record_looks` does in memory) and writes each
    look with its record into the stores that lack it. A store's digest covers the meshes
    in the plate's frame (vertices, triangles, colours, UVs, texture: the plate's pose too),
    the zone, the plan (samples, pitches, origin, wavelengths), its look's seed, code and
    amplitudes, the tile and the emitters found (their positions and visibility): only the
    same recording resumes into it, and a look recorded alone resumes into a store made with
    others and the other way round.
    ``scheduler``, ``overwrite``, ``progress``, ``dashboard``: as for :func:`record_tiled`;
    ``recording``: the digest the stores' plates carry (the name the caller knows them by);
    ``phases``: as :func:`holo_core.plate.recording.prepare_plate` takes it.
    """
    tile = _tile(planned.plan.tile, ZONE_TILE_STEP)
    _flag("overwrite", overwrite)
    looks = planned.plan.looks if codes is None else len(codes)
    if len(urls) != looks or not urls:
        raise InputError(f"urls must name one store per look; got {len(urls)} for {looks} look(s)")
    files, address = _output_and_scheduler(urls, scheduler)
    job = prepare_plate(
        planned, codes=codes, seed=seed, encoding=encoding, recording=recording, phases=phases
    )
    recordings = [_plate_recording(job, tile, look) for look in range(job.looks)]
    _record_tiles(
        files,
        job.info,
        tile,
        recordings,
        overwrite=overwrite,
        address=address,
        task=record_plate_tile,
        shared=replace(job, meshes=()),
        progress=progress,
        dashboard=dashboard,
    )
    return [open_plate(f.name) for f in files]


def _tile(tile, step) -> int:
    tile = validate.integer("tile", tile, store.MIN_TILE, store.MAX_TILE)
    if tile % step:
        raise InputError(
            f"tile must be a multiple of {step} samples in "
            f"[{store.MIN_TILE}, {store.MAX_TILE}]; got {tile}"
        )
    return tile


def _flag(name, value) -> bool:
    if not isinstance(value, bool):
        raise InputError(f"{name} must be True or False; got {value!r}"[:200])
    return value


def _output_and_scheduler(urls, scheduler):
    """(the stores' files, the scheduler's address or None), each checked before the work:
    the outputs' problems first, then a scheduler that cannot serve (before a store is
    touched)."""
    files = [check_output(url) for url in urls]
    if len({f.name for f in files}) != len(files):
        raise InputError(f"each look needs a store of its own; got {[f.name for f in files]}")
    return files, cluster.scheduler_address(scheduler)


def _record_tiles(
    files, info, tile, recordings, *, overwrite, address, task, shared, progress, dashboard
) -> None:
    """Write the tiles of each of ``recordings`` still missing from its store (``files``: one
    each; resumed, made, or replaced with ``overwrite``): ``shared`` scattered once to every
    worker, then one ``task(shared, spec, i, j)`` per tile that any store lacks."""
    with contextlib.ExitStack() as held:
        plates = [
            held.enter_context(store.recording_into(f, info, tile, r, overwrite=overwrite))
            for f, r in zip(files, recordings)
        ]
        lacking = [set(_to_record(plate)) for plate in plates]
        todo = sorted(set().union(*lacking))
        for f, plate, missing in zip(files, plates, lacking):
            log.info("%s: %d of %d tiles to record", f.name, len(missing), plate.written().size)
        if todo:
            spec = {"urls": [f.url for f in files], "recordings": [r["digest"] for r in recordings]}
            # a tile is written only into the stores that lack it (the others keep theirs)
            cluster.run_tasks(
                task,
                shared,
                [
                    (
                        {
                            **spec,
                            "looks": [k for k, missing in enumerate(lacking) if (i, j) in missing],
                        },
                        int(i),
                        int(j),
                    )
                    for i, j in todo
                ],
                address=address,
                progress=progress,
                dashboard=dashboard,
                lost=lambda: _kept(files),
            )


def _kept(files) -> str:
    """Each store's tiles written so far, as a recording that stops says them."""
    said = []
    for f in files:
        try:
            done = store.read_store(f.name, files=f).written()
            said.append(f"{f.name} keeps {int(done.sum())} of {done.size} tiles")
        except StoreError as e:
            said.append(f"{f.name} cannot be read now ({str(e).split(': ', 1)[-1]})")
    return "; ".join(said)


def _recording(pos, colours, phases, seed, **sampling) -> dict:
    """What a store records, its digest and the parts a message names when two differ."""
    cols = np.asarray(colours, np.float64).reshape(len(pos), -1)
    parts = {
        "emitters": len(pos),
        "geometry": digests.array_digest(pos),
        "colours": digests.array_digest(cols),
        "phases": "from the seed"
        if phases is None
        else digests.array_digest(np.asarray(phases, np.float64)),
        "seed": int(seed) if phases is None else None,
        "method": sampling.pop("method"),
        "sampling": digests.array_digest(
            np.array(
                [
                    *sampling["shape"],
                    sampling["pitch"],
                    sampling["band"] or 0.0,
                    sampling["tile"],
                    *sampling["wavelengths"],
                ],
                np.float64,
            )
        ),
        "encoding": "complex",
    }
    return {"digest": digests.digest_of(parts), "parts": parts}


def _plate_recording(job: PlateRecording, tile: int, look: int = 0) -> dict:
    """What the store of look ``look`` of a plate of meshes records: its digest and the parts
    a message names when two differ (the look's own seed, code and amplitudes: the same
    whether it is recorded alone or with other looks)."""
    meshes = digests.digest_of(
        {
            str(n): [
                None if a is None else digests.array_digest(a)
                for a in (m.vertices, m.triangles, m.colours, m.uvs, m.texture)
            ]
            for n, m in enumerate(job.meshes)
        }
    )
    z, p = job.info.zone, job.plan
    emitters = [
        digests.array_digest(np.ascontiguousarray(a))  # the look's own amplitudes
        for (_, em), columns in zip(job.groups, job.look_columns(look))
        for a in (em.position, em.amplitude[:, columns], em.visibility, em.table, em.grid)
    ]
    parts = {
        "method": "zone",
        "meshes": meshes[:16],
        "zone": digests.array_digest(
            np.array([*z.centre, *z.half_extents, z.pupil, z.pixel], np.float64)
        ),
        "plan": digests.array_digest(
            np.array(
                [
                    *p.shape,
                    p.pitch,
                    p.row_pitch,
                    *p.origin,
                    *job.info.wavelengths,
                    *p.band,
                    p.spacing,
                    tile,
                ],
                np.float64,
            )
        ),
        "seed": job.look_seed(look),
        "code": None if job.codes[look] is None else list(job.codes[look]),
        "emitters": len(job.groups[0][1].position),
        "emitters_found": digests.digest_of({"groups": emitters})[:16],
        "encoding": "complex",
    }
    return {"digest": digests.digest_of(parts), "parts": parts}


def _to_record(plate) -> list[tuple[int, int]]:
    """The tiles to write: those without this recording's record, and those whose samples do
    not read back as recorded (damage found on resuming: named, then written again)."""
    todo = []
    for why in plate.bad.values():
        log.warning("%s: %s; writing it again", plate.files.name, why)
    for i, j in np.ndindex(*plate.written().shape):
        if plate.written()[i, j]:
            why = plate.damaged(i, j)
            if why is None:
                continue
            log.warning("%s; writing it again", why)
        todo.append((i, j))
    return todo
