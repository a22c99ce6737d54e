"""A plate of meshes prepared for its sums: planned once (:func:`plate_plan`), then its
emitters, their amplitudes and visibility tables found (:func:`prepare_plate`), from which any
block of the plate is summed alike (:class:`PlateRecording`): whole in memory here, or tile by
tile into stores (:mod:`.tiles`). Its samples are the object wave against the carrier
converging on the zone's centre (:mod:`.carrier`), from the emitters the zone sees
(:mod:`.emitters`) summed onto their footprints (:mod:`.zone_sum`). Its looks differ only in
their emitters' phases (:mod:`.look_codes`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from .. import jobs, memory, validate
from ..opencl.arrays import nonfinite_count, read
from ..optics.raster import CROSSING_BYTES, crossing_count
from ..scene.hologram import Hologram, HologramInfo
from ..scene.mesh import Mesh, outward
from ..scene.plate import DEFAULT_ZONE_MARGIN, Carrier, Plate, ViewingZone
from ..validate import InputError
from .emitters import Emitters, zone_emitters, zone_frame
from .look_codes import code_classes, emitter_phases, in_phase_at_zone, look_code, look_seed
from .plan import LAYERS, LOOKS, PlatePlan, plan
from .zone_light import RIM, seen_area
from .zone_sum import ZoneEmitters, ZoneSum, ZoneWindow

log = logging.getLogger(__name__)
PHASES = ("random", "smooth")  # the emitters' phases (prepare_plate)


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class PlateRecording:
    """A plate of meshes ready to be summed (:func:`prepare_plate`): what it will be
    (``info``, its carrier included), where its samples lie (``window``), its emitters per
    wavelength (``groups``: (λ [m], :class:`ZoneEmitters`) in channel order) and what it was
    made from (``plan``, ``meshes`` in the plate's frame, ``seed``, ``codes``: each look's
    code, or None for the look of seed + its index). Any block of it is the same sum computed
    alone (:meth:`sums`): recorded whole in memory (:meth:`record`) or tile by tile
    (:mod:`.tiles`), its samples are the same. Every look is summed in one pass
    (:func:`~holo_core.plate.looks.record_looks`): the groups' channels are the looks' channels, look after look
    within each wavelength, so a block's samples are (R₀ G₀ B₀ R₁ G₁ B₁ … Z₀ Z₁ …)
    (:meth:`look_channels`)."""

    info: HologramInfo
    window: ZoneWindow
    groups: tuple
    plan: PlatePlan
    meshes: tuple
    seed: int
    codes: tuple

    @property
    def looks(self) -> int:
        return len(self.codes)

    def look_columns(self, look: int) -> list[slice]:
        """Per group, the columns of its emitters' amplitudes that are look ``look``'s."""
        return [
            slice(look * n, (look + 1) * n)
            for n in (em.amplitude.shape[1] // self.looks for _, em in self.groups)
        ]

    def look_channels(self, look: int) -> list[int]:
        """The channels of a block's samples (:meth:`region`) that are look ``look``'s, in the
        hologram's channel order."""
        out, first = [], 0
        for (_, em), columns in zip(self.groups, self.look_columns(look)):
            out += range(first + columns.start, first + columns.stop)
            first += em.amplitude.shape[1]
        return out

    def look_seed(self, look: int) -> int:
        """The seed of look ``look``'s random phases (its code shifts them, where it has one)."""
        return look_seed(self.seed, self.codes, look)

    @property
    def shape(self) -> tuple[int, int]:
        return self.window.shape

    def sums(self, rt=None) -> list[ZoneSum]:
        """The :class:`ZoneSum` of the wavelengths, its emitters on the device: the depth
        pair's partner summed with the colours in one pass where their channels an emitter
        fit the kernel's accumulators (FUSED_CHANNELS), else one a wavelength."""
        (lam, em), *rest = self.groups
        per_emitter = sum(
            e.amplitude.shape[1] // (1 if e.mixing is None else len(e.mixing))
            for _, e in self.groups
        )
        if len(rest) == 1 and per_emitter <= FUSED_CHANNELS:
            return [ZoneSum(em, self.window, lam, rt, partner=rest[0])]
        return [ZoneSum(e, self.window, lam, rt) for lam, e in self.groups]

    def region(self, sums, row0: int, col0: int, rows: int, cols: int) -> np.ndarray:
        """The samples (C, rows, cols) complex64 of a block (row0, col0 multiples of 256),
        every channel; :class:`RuntimeError` if any is not finite (never written)."""
        samples = np.concatenate([s.region(row0, col0, rows, cols) for s in sums])
        if not np.isfinite(samples).all():  # never a hologram of NaN: it would be written
            _not_finite(row0, col0, rows, cols)
        return samples

    def record(
        self, progress: jobs.Progress = None, buffers: memory.HostBuffers | None = None
    ) -> list[Hologram]:
        """Each look's whole plate in memory, summed in bands of rows, each channel read from
        the device into its look's plane (no block on the host: its copies cost 2.3 s of the
        shot's 28 s); the planes taken from ``buffers`` where given (every sample of them is
        written)."""
        rows, cols = self.shape
        channels = len(self.info.wavelengths)
        take = buffers.take if buffers is not None else memory.aligned_zeros
        waves = [take((channels, rows, cols)) for _ in range(self.looks)]
        # each sum's channel c goes to plane i of look l
        where, first = [], 0
        for s in self.sums():
            where.append(
                (
                    s,
                    [
                        (look, i, b - first)
                        for look in range(self.looks)
                        for i, b in enumerate(self.look_channels(look))
                        if first <= b < first + s.channels
                    ],
                )
            )
            first += s.channels
        for r0 in range(0, rows, SUM_ROWS):
            here = min(SUM_ROWS, rows - r0)
            for s, planes in where:
                block = s.on_device(r0, 0, here, cols)
                if nonfinite_count(s.rt, block):  # never a hologram of NaN
                    _not_finite(r0, 0, here, cols)
                for look, i, c in planes:
                    read(block[c], out=waves[look][i, r0 : r0 + here])
            jobs.report(progress, r0 + here, rows)
        return [Hologram(info=self.info, object_wave=w) for w in waves]


def _not_finite(row0, col0, rows, cols):
    raise RuntimeError(
        f"the object wave holds non-finite samples in rows {row0}-"
        f"{row0 + rows - 1}, columns {col0}-{col0 + cols - 1} (the OpenCL "
        f"device's arithmetic failed); nothing was recorded"
    )


SUM_ROWS = 256  # rows of the plate summed at once in memory (a multiple of the block lists')
# channels an emitter the zone sum carries in one pass at most: its accumulators (32 columns x 16
# lanes x re, im) stay within a core's L1
FUSED_CHANNELS = 8


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class PlannedPlate:
    """A plate of meshes planned (:func:`plate_plan`), before any emitter is found: its
    ``plan`` (:class:`~holo_core.plate.plan.PlatePlan`: the zone, the samples, the
    wavelengths, the looks, the tile, the costs), its ``meshes`` in the plate's frame, the
    ``plate``, whether it records the depth partner (``depth``) and whether tile by tile
    (``tiled``), its budget checked for that. Made once a job; the runner's checks, the
    recording and its tiles read it, and the view reads what it made (the looks' zone,
    bounds and carrier)."""

    plan: PlatePlan
    meshes: tuple
    plate: Plate
    depth: bool = True
    tiled: bool = False
    sides: tuple = ()  # each mesh's holo_core.scene.mesh.outward, found once (() : not yet)

    @property
    def channels(self) -> list[str]:
        """The channels of a look: R, G, B and, with ``depth``, the partner Z."""
        return ["R", "G", "B"] + (["Z"] if self.depth else [])


def mesh_list(meshes) -> list[Mesh]:
    """``meshes`` (a Mesh or a sequence of them) as a list; :class:`InputError` otherwise."""
    meshes = [meshes] if isinstance(meshes, Mesh) else list(meshes)
    if not meshes or not all(isinstance(m, Mesh) for m in meshes):
        raise InputError("meshes must be a Mesh or a non-empty sequence of Mesh")
    return meshes


def plate_plan(
    meshes,
    *,
    plate: Plate,
    camera=None,
    zone: ViewingZone | None = None,
    zone_margin=DEFAULT_ZONE_MARGIN,
    wavelength=None,
    looks=LOOKS,
    depth=True,
    budget=(None, None),
    tiled: bool | None = False,
    tile: int | None = None,
    sides=None,
) -> PlannedPlate:
    """The plan of a plate of ``meshes`` and its ``looks`` (``sides``: each mesh's
    :func:`holo_core.scene.mesh.outward`, where the caller found it; the other arguments as
    :func:`holo_core.plate.looks.record_plate` takes them): what its recording will hold and
    cost, before any emitter is found, checked against the host's memory and the ``budget``
    (memory, disk) [bytes] of the looks recorded together: the whole plate, or where
    ``tiled``, one tile of ``tile`` samples a side (None: fitted to the plate). ``tiled``
    None: tile by tile where the looks in one piece need more than the memory budget or the
    host's share of its memory (:func:`holo_core.memory.host_share`)."""
    if not isinstance(plate, Plate):
        raise InputError(f"plate must be a Plate; got {type(plate).__name__}")
    meshes = mesh_list(meshes)
    memory.check_host(
        f"moving {sum(len(m.triangles) for m in meshes)} triangles onto the plate",
        sum(320.0 * len(m.triangles) + 96.0 * len(m.vertices) for m in meshes),
    )
    local = [replace(m, vertices=plate.to_plate(m.vertices)) for m in meshes]
    every = np.concatenate([m.vertices for m in local])
    bounds = np.array([every.min(0), every.max(0)])
    if bounds[1, 2] >= 0:
        raise InputError(
            f"the objects must lie behind the plate (z < 0 in its frame); they "
            f"reach z = {bounds[1, 2]:.4g} m"
        )
    zone = plate.recording_zone(zone, camera, zone_margin, bounds)
    pixel = zone.pixel or (camera.pixel_angle() if camera is not None else None)
    if pixel is None and wavelength is None:
        raise InputError(
            "a plate needs the sharpness of its views: a camera, a zone with its "
            "pixel angle, or a wavelength"
        )
    sides = tuple(outward(m) for m in local) if sides is None else tuple(sides)
    p = plan(
        (plate.width, plate.height),
        bounds,
        zone=zone,
        pixel_angle=pixel or 1.0,
        wavelength=wavelength,
        looks=looks,
        tile=tile,
        seen=seen_area(local, zone.centre, sides),
        triangles=sum(len(m.triangles) for m in local),
    )
    count = crossing_count(
        local, np.asarray(zone.centre, np.float64), zone_frame(zone, bounds), p.spacing
    )  # what finding the emitters holds, before it starts
    memory.check_host(
        f"finding the emitters of {sum(len(m.triangles) for m in local)} "
        f"triangles ({count:.3g} crossings of the zone's rays: many large "
        f"triangles through each other cross many)",
        CROSSING_BYTES * count,
    )
    depth, decided = _flag("depth", depth), tiled is None
    tiled = p.check_recording(memory=budget[0], disk=budget[1], channels=3 + depth, tiled=tiled)
    if decided and tiled:
        log.info(
            "the plate's %d look(s) need %s in one piece, more than %s: recording them "
            "tile by tile",
            p.looks,
            memory.gib(p.memory_bytes((3 + depth) * p.looks)),
            memory.gib(memory.host_share(budget[0])),
        )
    return PlannedPlate(plan=p, meshes=local, plate=plate, depth=depth, tiled=tiled, sides=sides)


def _flag(name, value) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise InputError(f"{name} must be True or False; got {value!r}"[:200])
    return bool(value)


def prepare_plate(
    planned: PlannedPlate,
    *,
    codes=None,
    seed=0,
    encoding="complex",
    emitters: Emitters | None = None,
    recording: str = "",
    phases: str = "random",
) -> PlateRecording:
    """The emitters, visibility tables and sampling of the plate ``planned`` (its budget
    checked as it was planned), before any sum: the emitters the zone sees with their amplitudes, for
    the looks ``codes`` summed at once (:func:`holo_core.plate.looks.record_looks`), look
    l's phases coded by codes[l], or where that is None drawn from ``seed`` + l (default:
    the plan's looks, coded where their count allows, :func:`look_code`). ``emitters`` (the
    plate's frame, their visibility from this zone): found elsewhere, once for several
    plates that share them (:mod:`.parts`), in place of the zone's own. ``recording``: the
    digest the looks' description carries (:attr:`holo_core.scene.hologram.HologramInfo.
    recording`), in memory and in their stores alike. ``phases``: one of :data:`PHASES`:
    'random' (each emitter's drawn from the seed, the looks' codes shifting them: a diffuse
    surface, speckle through any pupil) or 'smooth' (each emitter's −k·|p − Z| at each
    channel's wavelength before the codes: every emitter's light reaches the zone's centre
    Z in one phase, as display holograms are made so that an eye's pupil there sees a
    picture, not speckle; one phase on the surface itself would send a tilted surface's
    light along its normal, past the eye)."""
    if encoding != "complex":
        raise InputError(
            f"encoding must be 'complex' for a plate of meshes (a display's "
            f"intensity pattern is made from it: holo_core.phase.display); got "
            f"{encoding!r}"[:200]
        )
    seed = validate.seed(seed)
    phases = validate.choice("phases", phases, PHASES)
    p, local, zone = planned.plan, planned.meshes, planned.plan.zone
    codes = tuple(look_code(k, p.looks) for k in range(p.looks)) if codes is None else tuple(codes)
    if len(codes) != p.looks:  # the plan's budget counts its looks
        raise InputError(
            f"codes must give one code per look of the plan ({p.looks}); got {len(codes)}"
        )
    bounds, depth, channels = p.bounds, planned.depth, planned.channels
    log.info("sampling: %s", p.describe())
    em = (
        emitters
        if emitters is not None
        else zone_emitters(local, zone, p.spacing, layers=LAYERS, sides=planned.sides or None)
    )
    if not len(em):
        raise InputError(
            f"no surface of the meshes is seen from the viewing zone ({zone.describe()})"
        )
    # |a| = √I·|p − Z|: each emitter's light reaches the zone's centre with its own amplitude
    reach = np.linalg.norm(em.position - np.asarray(zone.centre), axis=1)
    if em.weight is not None:  # a shared set's emitters, weighted for this zone
        reach = reach * em.weight
    smooth = phases == "smooth"
    waves = [
        np.exp(
            1j
            * (
                emitter_phases(em, look_seed(seed, codes, look), c, smooth)
                + in_phase_at_zone(reach, p.wavelength, smooth)
            )
        )
        * reach
        for look, c in enumerate(codes)
    ]
    partial = em.visibility.reshape(len(em), -1).min(1) < 1
    rows = np.where(partial, np.cumsum(partial) - 1, -1).astype(np.int32)
    table = np.round(em.visibility[partial] * 255).astype(np.uint8)
    window = ZoneWindow(
        origin=p.origin,
        pitch=p.pitch,
        row_pitch=p.row_pitch,
        shape=p.shape,
        centre=zone.centre,
        half_extents=zone.half_extents,
        rim=RIM,
    )
    amplitudes = [
        (p.wavelength, np.concatenate([np.sqrt(em.colour) * wave[:, None] for wave in waves], 1))
    ]
    if depth:  # the depth channel's own wavelength: its light in phase at the zone too
        turn = in_phase_at_zone(reach, p.depth_wavelength, smooth) - in_phase_at_zone(
            reach, p.wavelength, smooth
        )
        amplitudes.append((p.depth_wavelength, np.stack(waves, 1) * np.exp(1j * turn)[:, None]))
    classes, mixing = code_classes(em, codes)
    groups = tuple(
        (
            lam,
            ZoneEmitters(
                position=em.position,
                amplitude=a,
                visibility=rows,
                table=table,
                grid=em.grid,
                classes=classes,
                mixing=mixing,
            ),
        )
        for lam, a in amplitudes
    )
    distance = float(np.linalg.norm(bounds.mean(0) - np.asarray(zone.centre)))
    wavelengths = (p.wavelength,) * 3 + ((p.depth_wavelength,) if depth else ())
    info = HologramInfo(
        shape=p.shape,
        encoding="complex",
        wavelengths=wavelengths,
        pitch=p.pitch,
        band=max(p.band),
        channels=tuple(channels),
        point_density=1 / (p.spacing * distance) ** 2,
        zone=zone,
        bounds=bounds,
        plate=planned.plate.matrix_world,
        carrier=Carrier(centre=zone.centre, origin=p.origin, row_pitch=p.row_pitch),
        recording=validate.digest("recording", recording),
    )
    return PlateRecording(
        info=info,
        window=window,
        groups=groups,
        plan=p,
        meshes=local,
        seed=seed,
        codes=tuple(None if c is None else tuple(c) for c in codes),
    )
