"""A plate set recorded: the parts of one plate along a camera path
(:func:`holo_core.plate.path.parts_along`), recorded from the same emitters (each frame is
viewed from the part whose zone holds its pupil: :func:`holo_core.plate.view.render_set_view`).

- One set of emitters (:func:`set_emitters`). The zone centre of one part in each run of the
  path turning by at most 5° about the objects (:func:`lattice_parts`) casts its rays (one
  per resolved spot, the spacing every part shares) and finds their crossings with the
  surfaces, up to three deep; a surface point is kept from the lattice that sees it most
  face-on (a closed surface from its outside: one behind it finds it through the object, if
  its layers reach so far), so every surface holds emitters of one lattice, one resolved
  spot apart as seen from there. From another zone a surface then holds cos(slant from the
  lattice)/cos(slant from the zone) emitters a resolved spot; each part weighs their
  amplitudes by the root of its inverse, so that the surfaces' coverage (the views' alpha)
  stays one (without it the silhouettes of a 30° orbit's frames swelled: IoU 0.956-0.967
  against 0.975-0.980).
- Every part reads the same emitters, their phases drawn once from the seed and shifted by
  the same looks' codes, so a pupil in the overlap of two parts receives the same wave from
  either (but for the weights, which differ little between neighbouring parts).
- Visibility per part: each part's zone rasters its own depth buffers
  (:func:`holo_core.plate.emitters.visibility`), and a part sums only the emitters its zone
  sees.
- Each part is then a plate of its own (:func:`holo_core.plate.recording.prepare_plate`): its
  plan, its carrier converging on its zone's centre, its window, its looks summed in one pass.
"""

from __future__ import annotations

import hashlib
import itertools
import logging
import math
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext

import numpy as np

from .. import jobs, memory, validate
from ..io.plate_set import read_plate_set, recorded_parts, set_folder, write_manifest, write_part
from ..scene.mesh import Mesh, outward
from ..scene.plate_set import PathPart, PlateSet
from ..validate import InputError
from .emitters import Emitters, grid_points, surface_points, visibility, zone_frame
from .look_codes import look_code
from .path import lattice_parts
from .plan import LAYERS
from .recording import PlannedPlate, mesh_list, plate_plan, prepare_plate

log = logging.getLogger(__name__)

MIN_SLANT = 0.05  # cos of the most grazing view a lattice's density is weighted for (87°)


@validate.scale_free()  # each part's wavelength is the plan's (as record_looks)
def record_set(
    meshes,
    parts,
    *,
    looks: int = 2,
    seed: int = 0,
    depth: bool = True,
    budget=(None, None),
    folder=None,
    overwrite=False,
    recording: str = "",
    progress: jobs.Progress = None,
) -> PlateSet:
    """Record the looks of every part of a plate along a path, in memory or into a folder.

    Parameters
    ----------
    meshes : sequence of Mesh
        The scene, in world metres.
    parts : sequence of PathPart
        The parts, from :func:`holo_core.plate.path.parts_along`.
    looks : int
        Coded looks of ``seed`` (:func:`holo_core.plate.look_codes.look_code`) per part, all
        parts from one set of emitters (module docstring).
    seed : int
        The emitters' random phases' seed.
    depth : bool
        Also record the depth partner.
    budget : (int or None, int or None)
        (memory, disk) [bytes]: the memory one part holds while recorded and the whole set's
        disk, checked for every part before any emitter is found.
    folder : str or Path, optional
        Each part written there as soon as it is recorded and its samples let go (the memory
        that of one part) and named in its manifest (:mod:`holo_core.io.plate_set`), the set
        returned as read from there. A folder that holds this recording already (the same
        meshes, parts, seed and looks) records only the parts it lacks: nothing, for a second
        render of the shot; the rest of a recording stopped.
    overwrite : bool
        Replace a folder's set of another recording (refused naming both otherwise).
    recording : str
        The name (a hex digest) the caller knows this recording by, written into the
        manifest and matched when a folder's set is resumed (the add-on's digest of the scene
        and its settings: emitters lit by a renderer differ in their noise from one render to
        the next); '' (default): :func:`set_digest` of the meshes, parts, seed and looks.
    progress : callable, optional
        Given the fraction done in [0, 1] between units of work.

    Returns
    -------
    PlateSet
        The parts and their looks.

    Raises
    ------
    InputError
        Where a budget would be exceeded, ``folder`` holds another recording and not
        ``overwrite``, or a setting is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import Camera, Mesh, look_at, parts_along, record_set
    >>> cameras = [Camera(matrix_world=look_at((x, -0.5, 0.0), (0, 0, 0)), resolution=(32, 24),
    ...                   fstop=8.0, focus_distance=0.5) for x in (-0.01, 0.01)]
    >>> bounds = np.array([[-0.01, -0.01, -0.01], [0.01, 0.01, 0.01]])
    >>> parts = parts_along(cameras, bounds, distance=0.1)
    >>> triangle = Mesh(vertices=np.array([[-0.01, 0, -0.01], [0.01, 0, -0.01], [0, 0, 0.01]]),
    ...                 triangles=np.array([[0, 1, 2]]), colours=np.ones((3, 3)))
    >>> plates = record_set([triangle], parts, looks=1, depth=False)
    >>> len(plates), len(plates.part_looks(0))
    (1, 1)
    """
    parts = tuple(parts)
    if not parts or not all(isinstance(p, PathPart) for p in parts):
        raise InputError("parts must be a non-empty sequence of PathPart (parts_along)")
    looks = validate.integer("looks", looks, 1)
    seed = validate.seed(seed)
    world = mesh_list(meshes)
    sides = [outward(m) for m in world]  # each mesh's outside, found once for every part
    plans = [
        _part_plan(world, k, part, looks=looks, depth=depth, memory=budget[0], sides=sides)
        for k, part in enumerate(parts)
    ]
    spacing = plans[0].plan.spacing
    for k, p in enumerate(planned.plan for planned in plans):
        if not math.isclose(p.spacing, spacing, rel_tol=1e-9):
            raise InputError(
                f"part {k}'s emitters would lie {p.spacing:.4g} apart in direction "
                f"cosine, part 0's {spacing:.4g}: a set's parts share one pupil "
                f"and pixel angle (parts_along gives them that)"
            )
    stored = sum(planned.plan.disk_bytes(len(planned.channels)) for planned in plans)
    if budget[1] is not None and stored > budget[1]:
        raise InputError(
            f"the set of {len(parts)} parts needs {stored / 2**30:.2f} GiB on disk "
            f"({looks} look(s) each); the disk budget is "
            f"{budget[1] / 2**30:.2f} GiB: longer stretches share more, a "
            f"smaller pupil or coarser views need less"
        )
    digest = validate.digest("recording", recording) or set_digest(
        meshes, parts, seed=seed, looks=looks, depth=depth
    )
    recorded = [None] * len(parts)
    if folder is not None:
        folder = set_folder(folder)
        for k, files in recorded_parts(folder, digest, len(parts), overwrite=overwrite).items():
            recorded[k] = files
        if all(r is not None for r in recorded):
            log.info(
                "plate set: %s holds its %d parts already; nothing recorded", folder, len(parts)
            )
            return read_plate_set(folder)
    shared = set_emitters(world, parts, plans, spacing, sides)
    codes = tuple(look_code(k, looks) for k in range(looks))

    # the parts' samples fill the same host memory part after part, once a part is written
    buffers = memory.HostBuffers(kept=2 * looks) if folder is not None else None

    def write(k, held):  # a part's files, then the manifest naming every part written so far
        recorded[k] = write_part(folder, k, held)
        write_manifest(folder, parts, recorded, seed=seed, recording=digest, looks=looks)
        for h in held:
            buffers.give(h.object_wave)

    # a part is written while the next is recorded where both fit the memory: the writes wait
    # on the disk (1 GiB a part took 3-6 s, a sixth of a part's time), the sum on the CPU
    pending = None
    with (
        ThreadPoolExecutor(1, thread_name_prefix="holo-set-writer")
        if folder is not None and _overlap_fits(plans, budget[0])
        else nullcontext() as writer
    ):
        for k, (part, em) in enumerate(zip(parts, shared)):
            if recorded[k] is not None:
                continue  # written by a recording that stopped
            done = jobs.scaled(progress, k / len(parts), (k + 1) / len(parts))
            recording = prepare_plate(plans[k], codes=codes, seed=seed, emitters=em)
            held = tuple(recording.record(done, buffers))
            log.info(
                "part %d of %d: %d emitters of the set's %d, %s",
                k + 1,
                len(parts),
                len(em),
                em.count,
                recording.plan.describe(),
            )
            if folder is None:
                recorded[k] = held
            elif writer is None:
                write(k, held)
            else:  # the part before written first: the manifest grows in order
                if pending is not None:
                    pending.result()
                pending = writer.submit(write, k, held)
            del held, recording  # a part's samples let go as soon as they are written
        if pending is not None:  # a failed write raises here; a stopped recording's part
            pending.result()  # being written finishes as the block ends
    if folder is None:
        return PlateSet(parts=parts, looks=tuple(recorded), seed=seed, recording=digest)
    return read_plate_set(folder)


def _overlap_fits(plans, budget) -> bool:
    """Whether a part's samples, held while they are written, and the next part's recording
    fit the host's share of its memory and the memory ``budget`` [bytes] (None: no limit)."""
    need = [
        (p.plan.memory_bytes(len(p.channels) * p.plan.looks), p.plan.disk_bytes(len(p.channels)))
        for p in plans
    ]
    most = max(
        (held + recording for (_, held), (recording, _) in itertools.pairwise(need)), default=0.0
    )
    return most <= memory.host_share(budget)


def _part_plan(meshes, k: int, part: PathPart, *, looks, depth, memory, sides=None) -> PlannedPlate:
    """Part ``k``'s plan (:func:`~holo_core.plate.recording.plate_plan`, its looks held
    together within ``memory`` [bytes]); its refusal names the part."""
    try:
        return plate_plan(
            meshes, plate=part.plate, looks=looks, depth=depth, budget=(memory, None), sides=sides
        )
    except InputError as e:
        raise InputError(f"part {k}: {e}") from None


def set_emitters(meshes, parts, plans, spacing: float, sides=None) -> Iterator[Emitters]:
    """Each part's emitters (its plate's frame, its visibility), made as the recording asks
    for them, drawn from one set found for all (module docstring): ``plans`` the parts'
    :class:`~holo_core.plate.recording.PlannedPlate` (their plan and zone, the meshes in the
    plate's frame), ``spacing`` their shared spacing in direction cosine, ``sides`` each
    mesh's :func:`~holo_core.scene.mesh.outward` where the caller found it."""
    world = [meshes] if isinstance(meshes, Mesh) else list(meshes)
    poses = []  # each part's zone centre and its pupil's axes, in the world
    for part, planned in zip(parts, plans):
        m, zone = part.plate.matrix_world, planned.plan.zone
        every = np.concatenate([x.vertices for x in planned.meshes])
        poses.append(
            (
                m[:3, :3] @ np.asarray(zone.centre) + m[:3, 3],
                m[:3, :3] @ zone_frame(zone, np.array([every.min(0), every.max(0)])),
            )
        )
    every = np.concatenate([x.vertices for x in world])
    lattices = [poses[k] for k in lattice_parts([c for c, _ in poses], every.mean(0))]
    centres = np.array([c for c, _ in lattices])
    points = []
    sides = [outward(m) for m in world] if sides is None else sides  # found once a set
    for k, (centre, rotation) in enumerate(lattices):
        position, colour, normal, cell, key, closed = surface_points(
            world, centre, rotation, spacing, layers=LAYERS, lattice=k, sides=sides
        )
        towards = centres[None, :, :] - position[:, None, :]
        cosine = np.einsum("nj,npj->np", normal, towards) / np.linalg.norm(towards, axis=2)
        facing = np.abs(cosine)
        # each surface point from the lattice seeing it most face-on. A closed surface shows
        # its outside only: a lattice behind it finds it through the object (a back layer),
        # if its layers reach that far, so it ranks below every lattice in front (else the
        # surface has no emitters where they run out: a 90° orbit's end frame lost a bite of
        # the sphere, and gained a blur beyond it, to the far end's lattice)
        own = np.where(closed[:, None], cosine, facing).argmax(1) == k
        points.append(
            (
                position[own],
                colour[own],
                normal[own],
                cell[own],
                facing[own, k],
                key[own],
                closed[own],
            )
        )
    position, colour, normal, cell, slant, key, closed = (np.concatenate(a) for a in zip(*points))
    seen = []
    for part, planned, (centre, _) in zip(parts, plans, poses):
        local, zone = planned.meshes, planned.plan.zone
        m = part.plate.matrix_world
        every = np.concatenate([x.vertices for x in local])
        rotation = zone_frame(zone, np.array([every.min(0), every.max(0)]))
        here = part.plate.to_plate(position)
        offsets, table = visibility(
            local,
            here,
            normal @ m[:3, :3],
            zone,
            rotation,
            spacing,
            grid_points(zone),
            closed=closed,
        )
        towards = centre - position
        facing = np.abs(np.einsum("nj,nj->n", normal, towards)) / np.linalg.norm(towards, axis=1)
        # a lattice seen from this zone holds cos(its slant)/cos(this zone's) emitters a
        # resolved spot: their light scaled to one's, so that the surfaces' coverage is one
        weight = np.sqrt(np.maximum(facing, MIN_SLANT) / np.maximum(slant, MIN_SLANT))
        keep = np.flatnonzero(table.reshape(len(table), -1).max(1) > 0)
        # held as the recording's own 8-bit table (prepare_plate rounds it so), not float32:
        # a long path's parts hold every one of their emitters' tables at once here
        seen.append((keep, offsets, np.round(table[keep] * 255).astype(np.uint8), weight[keep]))
    kept = np.zeros(len(position), bool)
    for keep, *_ in seen:
        kept[keep] = True
    ids = np.cumsum(kept) - 1  # the set's emitters: those some part sees, numbered once
    count = int(kept.sum())
    return (
        Emitters(
            position=part.plate.to_plate(position[keep]),
            colour=colour[keep],
            cell=cell[keep],
            visibility=table / np.float32(255),
            grid=offsets,
            ids=ids[keep],
            count=count,
            weight=weight,
            key=key[keep],
        )
        for part, (keep, offsets, table, weight) in zip(parts, seen)
    )


def set_digest(meshes, parts, *, seed: int, looks: int, depth: bool) -> str:
    """The digest (hex) of a set's recording: the meshes (world), each part's plate (pose,
    size, zone), the seed, the looks and the depth partner."""
    h = hashlib.sha256(f"holo plate set {seed} {looks} {bool(depth)}".encode())
    for m in [meshes] if isinstance(meshes, Mesh) else meshes:
        for name in ("vertices", "triangles", "colours", "uvs", "texture", "motion"):
            a = getattr(m, name)
            a = np.ascontiguousarray(a if a is not None else np.zeros(0))
            h.update(f"{name}{a.dtype.str}{a.shape}".encode())
            h.update(a.tobytes())
    for part in parts:
        z = part.plate.zone
        h.update(np.asarray(part.plate.matrix_world, np.float64).tobytes())
        h.update(
            repr(
                (part.plate.width, part.plate.height, z.centre, z.half_extents, z.pupil, z.pixel)
            ).encode()
        )
    return h.hexdigest()
