"""The recording of a plate of meshes' looks, its public entry (:func:`record_looks`;
:func:`record_plate` for one look): the plate planned once (:mod:`.recording`), then every
look summed in one pass, whole in memory (:class:`~holo_core.plate.recording.PlateRecording`)
or tile by tile into a store a look (:mod:`.tiles`).
"""

from __future__ import annotations

from .. import jobs, validate
from ..scene.hologram import Hologram
from ..scene.plate import DEFAULT_ZONE_MARGIN, Plate, ViewingZone
from ..validate import InputError
from .recording import PlannedPlate, plate_plan, prepare_plate
from .tiles import record_looks_tiled


def record_plate(
    meshes,
    *,
    plate: Plate,
    camera=None,
    zone: ViewingZone | None = None,
    zone_margin=DEFAULT_ZONE_MARGIN,
    wavelength=None,
    depth=True,
    seed=0,
    code=None,
    encoding="complex",
    budget=(None, None),
    url=None,
    tile=None,
    scheduler=None,
    overwrite=False,
    progress: jobs.Progress = None,
    dashboard=None,
) -> Hologram:
    """A plate hologram of ``meshes`` (world metres), independent of any camera: what it
    records depends on the meshes, the plate's placement and size, the viewing zone and the
    views' sharpness (:mod:`holo_core.plate.plan`). Its samples are the object wave against
    the carrier converging on the zone's centre (:mod:`.carrier`), as many as the zone can
    see; every emitter is seen from the zone points it is seen from (:mod:`.emitters`:
    occlusion by depth buffers over the zone), its light summed onto its footprint
    (:mod:`.zone_sum`).

    Parameters
    ----------
    meshes : Mesh or sequence of Mesh
        World-space surfaces; colours are linear RGB intensities.
    plate : Plate
    camera : Camera, optional
        The zone's reference view where the zone does not say: its pupil and pixel angle
        set the wavelength (λ = D·Δ/2: its views resolve a fine pixel); and where no zone is
        given, the zone covers its pupil with ``zone_margin`` [m] around it.
    zone : ViewingZone, optional
        The region [m, the plate's frame] the plate will be looked at from; default
        ``plate.zone``, else from ``camera``.
    wavelength : float, optional
        λ1 [m] instead of the planned one.
    depth : bool
        Also record the depth partner λ2 (Sect. VII-C).
    seed : int
        Seeds the emitters' random phases.
    code : (k, m), optional
        Look k of m² with the emitters' phases shifted by 2π·(k1·i + k2·j)/m on the lattice
        cells (i, j) they lie in (k = k1·m + k2): the mean intensity of the m² looks has no
        cross terms between emitters of neighbouring cells (the looks' speckle cancels
        where random looks would only average it down).
    encoding : 'complex'
        The object wave (against its carrier); a display's or a print's intensity pattern is
        made from it (:mod:`holo_core.phase.display`).
    budget : (memory, disk) [bytes]
        What the recording may hold in memory and the plate take on disk (None: no limit);
        a plate that needs more is refused before any work, with its sizes (in memory, the
        whole plate; tiled, one tile).
    url : str or path, optional
        Record tile by tile into the tiled store there, on Dask, and return it opened
        (:func:`holo_core.plate.tiles.record_looks_tiled`: ``tile`` samples a side, a
        multiple of 256, by default fitted to the plate (:func:`holo_core.plate.plan.
        fitted_tile`); ``scheduler``, ``overwrite``, ``dashboard`` as there). Default: the
        whole plate in memory.
    progress : callable, optional
        Called with the fraction done (rows in memory, tiles in a store).

    Returns
    -------
    Hologram
        The plate: its object wave against the carrier (λ1, and λ2 with ``depth``), in
        memory, or the tiled store at ``url`` opened.

    Raises
    ------
    InputError
        Where an argument is out of range, naming it, or the plate needs more than
        ``budget`` (with its sizes).

    See Also
    --------
    record_looks : several looks of one plate in one pass.
    holo_core.render_view : a camera's view of the plate.
    """
    planned = plate_plan(
        meshes,
        plate=plate,
        camera=camera,
        zone=zone,
        zone_margin=zone_margin,
        wavelength=wavelength,
        looks=1,
        depth=depth,
        budget=budget,
        tiled=url is not None,
        tile=tile,
    )
    return record_planned(
        planned,
        codes=(code,),
        urls=None if url is None else [url],
        seed=seed,
        encoding=encoding,
        scheduler=scheduler,
        overwrite=overwrite,
        progress=progress,
        dashboard=dashboard,
    )[0]


@validate.scale_free()  # as record_hologram: the renderer's jobs come this way
def record_looks(
    meshes,
    *,
    looks: int,
    plate: Plate,
    camera=None,
    zone: ViewingZone | None = None,
    zone_margin=DEFAULT_ZONE_MARGIN,
    wavelength=None,
    depth=True,
    seed=0,
    budget=(None, None),
    urls=None,
    tile=None,
    scheduler=None,
    overwrite=False,
    progress: jobs.Progress = None,
    dashboard=None,
    recording="",
) -> list[Hologram]:
    """Several looks of one plate, recorded in one pass.

    The looks differ only in their emitters' phases, so one sum carries them all as further
    channels: each emitter's distance, phase and visibility at a sample are found once for
    every look, which costs less than recording them one after the other (``bench/shot.py``
    times the pass; the docs' Performance page).

    Parameters
    ----------
    meshes : Mesh or sequence of Mesh
        World-space surfaces [m]; colours are linear RGB intensities.
    looks : int
        How many looks, >= 1: the coded looks of ``seed``
        (:func:`~holo_core.plate.look_codes.look_code`) where ``looks`` allows (a square
        number), else seeds ``seed``, ``seed`` + 1, ….
    plate, camera, zone, zone_margin, wavelength, depth, seed
        As for :func:`record_plate` (lengths [m]).
    budget : (memory, disk) [bytes]
        What all the looks held together may take (None: no limit).
    urls : sequence of str or path, optional
        One a look: each look tile by tile into its own store, every tile's looks summed at
        once (:func:`holo_core.plate.tiles.record_looks_tiled`). Default: in memory.
    tile, scheduler, overwrite, dashboard
        As for :func:`record_plate`, with ``urls``.
    progress : callable, optional
        Called with the fraction done.
    recording : str
        The digest the looks carry in their description and their stores (the name the
        caller knows them by: ``HologramInfo.recording``).

    Returns
    -------
    list of Hologram
        One a look, in memory or the stores at ``urls`` opened.

    Raises
    ------
    InputError
        Where ``looks`` is not an integer >= 1, or as :func:`record_plate`.
    """
    looks = validate.integer("looks", looks, 1)
    planned = plate_plan(
        meshes,
        plate=plate,
        camera=camera,
        zone=zone,
        zone_margin=zone_margin,
        wavelength=wavelength,
        looks=looks,
        depth=depth,
        budget=budget,
        tiled=urls is not None,
        tile=tile,
    )
    return record_planned(
        planned,
        seed=seed,
        urls=urls,
        scheduler=scheduler,
        overwrite=overwrite,
        progress=progress,
        dashboard=dashboard,
        recording=recording,
    )


@validate.scale_free()
def record_planned(
    planned: PlannedPlate,
    *,
    codes=None,
    seed=0,
    encoding="complex",
    urls=None,
    scheduler=None,
    overwrite=False,
    progress: jobs.Progress = None,
    dashboard=None,
    recording="",
    phases="random",
) -> list[Hologram]:
    """The looks of the plate ``planned`` (:func:`~holo_core.plate.recording.plate_plan`,
    made once a job, its budget checked there) in one pass: ``codes`` one a look (default:
    the coded looks of its plan's looks, :func:`~holo_core.plate.recording.prepare_plate`),
    in memory, or where the plan is tiled into ``urls``, a store a look (the other arguments
    as for :func:`record_looks`; ``phases`` as
    :func:`~holo_core.plate.recording.prepare_plate` takes it)."""
    if planned.tiled != (urls is not None):
        raise InputError(
            "urls must name the stores of a plate planned tile by tile, and only "
            f"of one; this plate is planned {'in tiles' if planned.tiled else 'in memory'}"
            f" and urls is {'None' if urls is None else 'given'}"
        )
    if urls is not None:
        return record_looks_tiled(
            planned,
            urls=list(urls),
            codes=codes,
            scheduler=scheduler,
            overwrite=overwrite,
            progress=progress,
            dashboard=dashboard,
            seed=seed,
            encoding=encoding,
            recording=recording,
            phases=phases,
        )
    return prepare_plate(
        planned, codes=codes, seed=seed, encoding=encoding, recording=recording, phases=phases
    ).record(progress)
