"""The plate (Blender → :class:`holo_core.scene.plate.Plate`), checked against what the
camera sees of the holographic objects: the lines of sight through it, the share of the
objects it covers, whether the camera's pupil stays inside its viewing zone; a plate made a
set of parts along the camera's path (Fit Zone to Shot over a long move: the part that holds
the frame's camera); and a plate imported from a hologram file (File ▸ Import ▸ Hologram),
viewed as it is.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from holo_core.io.plate_set import parts_from_json
from holo_core.plate.path import part_for
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.mesh import Mesh, sample_points
from holo_core.scene.plate import Plate, ViewingZone
from holo_core.scene.plate_set import PlateSet
from holo_core.validate import InputError

from .scene import (
    ExportError,
    SceneData,
    camera_from_object,
    evaluated,
    render_region,
    scale,
    world_matrix,
)


def scene_plate(scene, *, required: bool):
    """The scene's one plate object (None when there is none and none is ``required``)."""
    plates = [o for o in scene.objects if o.holo.is_plate]
    if required and not plates:
        raise ExportError(
            "no hologram plate: mark a plane with Object ▸ Holo ▸ Plate, or "
            "record for the camera (Holo ▸ Hologram: Camera)"
        )
    if len(plates) > 1:
        raise ExportError(f"one plate per scene; found {', '.join(o.name for o in plates)}")
    return plates[0] if plates else None


def with_plate(data: SceneData, plate_object, depsgraph, strict=False) -> SceneData:
    """``data`` with the plate ``plate_object`` as ``depsgraph`` evaluates it and its viewing
    zone (the plate's own, else the camera's pupil with the plate's Zone Margin around it:
    ``data.zone``, to keep on the plate once it is recorded), checked against the camera: in
    front of it (an :class:`ExportError` otherwise), covering what the camera sees of the
    emitters (a warning when it covers part, an error when none), the camera's pupil inside
    its viewing zone (a warning naming it otherwise; ``strict``: an :class:`ExportError`).
    Its ``view``, the camera of the emitters' radiance, is the zone's centre
    (:func:`zone_view`)."""
    name, camera = plate_object.name, data.camera
    plate = plate_from_object(evaluated(plate_object, depsgraph), data.unit)
    _in_front(plate, name, camera)
    zone = None
    if plate.zone is None:
        zone = kept(zone_around(plate, camera, plate_object.holo.zone_margin * data.unit))
    beyond = outside_zone(plate, name, camera)
    if beyond and strict:
        raise ExportError(f"{beyond} (Outside Zone: Fail)")
    warnings = data.warnings + tuple(
        filter(None, (beyond, plate_coverage(plate, name, camera, data.points + data.triangles)))
    )
    data = replace(
        data,
        plate=replace(plate, zone=plate.zone or zone),
        plate_name=name,
        warnings=warnings,
        zone=zone,
    )
    return replace(data, view=zone_view(data))


def plate_parts(obj) -> tuple | None:
    """The plate's parts along the camera's path (Fit Zone to Shot keeps them on its settings,
    world metres), or None for one plate. Read from the original object, as its zone."""
    holo = (obj.original if obj.is_evaluated else obj).holo
    if not holo.parts:
        return None
    try:
        return parts_from_json(holo.parts)
    except InputError as e:
        raise ExportError(
            f"plate '{obj.name}': its parts along the path: {e}; run Fit Zone to Shot again"
        ) from None


def nearest_part(parts, camera: Camera) -> tuple[int, float]:
    """(the part whose zone holds ``camera``'s pupil with the most room, 0) or, where none
    holds it, (the nearest part, how far [m] the pupil reaches beyond its zone): the part the
    worker views the frame from (:func:`holo_core.plate.path.part_for`, which reads no
    samples)."""
    placed = PlateSet(parts=tuple(parts), looks=(None,) * len(parts), load=_unrecorded)
    return part_for(placed, camera)


def _unrecorded(k):
    raise ExportError(f"part {k} of the plate set is not recorded here")  # never asked for


def with_set(data: SceneData, plate_object, parts, strict=False) -> SceneData:
    """``data`` with the plate's set of ``parts``: its ``plate`` the part that holds the
    camera's pupil (:func:`nearest_part`), checked as :func:`with_plate` checks a plate (in
    front of the camera, covering what it sees; a pupil outside every part warns, or with
    ``strict`` is an :class:`ExportError`), its ``view`` that part's zone centre."""
    name, camera = plate_object.name, data.camera
    k, beyond = nearest_part(parts, camera)
    plate = parts[k].plate
    _in_front(plate, f"{name} (part {k + 1} of {len(parts)})", camera)
    outside = None
    if beyond > 1e-9:
        outside = (
            f"the camera's pupil reaches {beyond:.3g} m beyond every part of plate "
            f"'{name}' (the nearest, part {k + 1} of {len(parts)}: "
            f"{plate.zone.describe()}): what the set cannot send there is left out of "
            f"its view; run Fit Zone to Shot for this camera's path"
        )
        if strict:
            raise ExportError(f"{outside} (Outside Zone: Fail)")
    warnings = data.warnings + tuple(
        filter(None, (outside, plate_coverage(plate, name, camera, data.points + data.triangles)))
    )
    data = replace(data, plate=plate, plate_name=name, warnings=warnings, zone=None)
    return replace(data, view=zone_view(data))


def kept(zone: ViewingZone) -> ViewingZone:
    """``zone`` as the plate's settings keep it (single precision), so that the digest of a
    job read after it is kept is the digest of this one."""
    return ViewingZone(
        centre=tuple(map(float, np.float32(zone.centre))),
        half_extents=tuple(map(float, np.float32(zone.half_extents))),
        pupil=float(np.float32(zone.pupil)),
    )


def zone_view(data: SceneData) -> Camera:
    """A pinhole at the zone's centre looking at the emitters' centre, with the render
    camera's lens and frame: what a plate's radiance is rendered from (a camera moving inside
    the zone reuses the plate, and its highlights are the zone centre's)."""
    plate = data.plate
    eye = plate.matrix_world[:3, :3] @ np.asarray(plate.zone.centre) + plate.matrix_world[:3, 3]
    every = np.concatenate([m.vertices for m in data.points + data.triangles])
    centre = (every.min(0) + every.max(0)) / 2
    return replace(data.view, matrix_world=look_at(eye, centre, up=plate.matrix_world[:3, 1]))


def _in_front(plate: Plate, name: str, camera: Camera) -> None:
    if plate.to_plate(camera.position[None])[0, 2] <= 0:
        raise ExportError(
            f"the camera is behind plate '{name}': viewers must be on its +Z "
            f"side (rotate the plate 180°)"
        )


def plate_from_object(obj, unit: float) -> Plate:
    """The plate: the object's pose (scale removed) and its width and height [m] from its
    dimensions; the hologram is its local z = 0 plane and viewers are on its +Z side."""
    w, h = obj.dimensions.x * unit, obj.dimensions.y * unit
    if w <= 0 or h <= 0:
        raise ExportError(f"plate '{obj.name}' must have a width and height (a plane)")
    return Plate(
        matrix_world=world_matrix(obj.matrix_world, unit, normalise=True),
        width=w,
        height=h,
        zone=plate_zone(obj),
    )


def plate_zone(obj) -> ViewingZone | None:
    """The plate's viewing zone [m, the plate's frame] as its settings hold it, or None while
    none is set (it is set around the camera when the plate is recorded). Read from the
    original object: an evaluated copy holds the settings of the last evaluation."""
    holo = (obj.original if obj.is_evaluated else obj).holo
    if not holo.zone_set:
        return None
    try:
        return ViewingZone(
            centre=tuple(holo.zone_centre),
            half_extents=tuple(holo.zone_half),
            pupil=holo.zone_pupil,
            pixel=holo.zone_pixel,
        )
    except InputError as e:
        raise ExportError(f"plate '{obj.name}': its viewing zone: {e}") from None


def zone_around(plate: Plate, camera: Camera, margin: float) -> ViewingZone:
    """The viewing zone covering ``camera``'s pupil with ``margin`` [m] around it."""
    try:
        return plate.zone_for(camera, margin)
    except InputError as e:
        raise ExportError(str(e)) from None


def beyond_zone(plate: Plate, camera: Camera) -> float:
    """How far [m] the camera's pupil reaches beyond the plate's viewing zone (0: inside it,
    or no zone yet)."""
    if plate.zone is None:
        return 0.0
    position = plate.to_plate(camera.position[None])[0]
    beyond = plate.zone.distance_outside(position, (camera.aperture_diameter or 0.0) / 2)
    return beyond if beyond > 1e-9 else 0.0


def outside_zone(plate: Plate, name: str, camera: Camera) -> str | None:
    """A warning naming the zone when the camera's pupil reaches beyond it, else None."""
    beyond = beyond_zone(plate, camera)
    if not beyond:
        return None
    return (
        f"the camera's pupil reaches {beyond:.3g} m beyond the viewing zone of plate "
        f"'{name}' ({plate.zone.describe()}): what the plate cannot send there is left "
        f"out of its view, transparent in the composite, and its view may be soft; use "
        f"Fit Zone to Shot (Object ▸ Holo) to record the plate for every frame of the "
        f"camera's move, or Fit Zone to Camera for where it is now"
    )


def export_imported(scene, depsgraph, plate_object) -> SceneData:
    """The scene's imported plate (File ▸ Import ▸ Hologram) and camera: a hologram viewed as
    it is needs no emitters."""
    if scene.camera is None:
        raise ExportError("the scene has no camera")
    unit = scale(scene)
    camera_object = evaluated(scene.camera, depsgraph)
    camera = camera_from_object(scene, camera_object, unit, depsgraph)
    plate = plate_from_object(evaluated(plate_object, depsgraph), unit)
    _in_front(plate, plate_object.name, camera)
    outside = outside_zone(plate, plate_object.name, camera)
    return SceneData(
        points=[],
        triangles=[],
        plate=plate,
        plate_name=plate_object.name,
        camera=camera,
        warnings=(outside,) if outside else (),
        view=replace(camera, fstop=None, focus_distance=None),
        region=render_region(scene.render),
        unit=unit,
    )


def _surface_samples(mesh: Mesh, count=4000) -> np.ndarray:
    """About ``count`` points spread over ``mesh``'s surface [m] (and its vertices)."""
    area = float(mesh.areas().sum())
    if area <= 0:
        return mesh.vertices
    points, _ = sample_points(mesh, math.sqrt(area / count), max_points=count)
    return np.concatenate([points, mesh.vertices])


def through_plate(plate: Plate, eye, world) -> tuple:
    """(whether the line of sight from ``eye`` to each of ``world`` (N, 3) crosses the plate
    with the point behind it, where the lines of sight of the points behind cross its plane
    (M, 2) in plate coordinates); lengths in any one unit."""
    eye, local = plate.to_plate(np.asarray(eye, np.float64)[None])[0], plate.to_plate(world)
    behind = local[:, 2] < 0
    t = eye[2] / (eye[2] - local[behind, 2])
    hits = eye[:2] + t[:, None] * (local[behind, :2] - eye[:2])
    inside = np.zeros(len(local), bool)
    inside[behind] = (np.abs(hits) <= (plate.width / 2, plate.height / 2)).all(1)
    return inside, hits


def plate_coverage(plate: Plate, name: str, camera: Camera, meshes) -> str | None:
    """A warning when the plate covers only part of what the camera sees of the emitters (the
    rest would be cut from the pass), an :class:`ExportError` when it covers none of it (the
    pass would be empty); None when it covers all."""
    world = np.concatenate([_surface_samples(m) for m in meshes])
    xy, depth = camera.project(world)
    w, h = camera.resolution
    seen = (depth > 0) & (xy[:, 0] >= 0) & (xy[:, 0] < w) & (xy[:, 1] >= 0) & (xy[:, 1] < h)
    if not seen.any():
        raise ExportError("no holographic object is in the camera's view")
    inside, hits = through_plate(plate, camera.position, world[seen])
    share = inside.mean()
    if share == 0:
        raise ExportError(
            f"plate '{name}' is not between the camera and the holographic "
            f"objects: the pass would be empty (move it onto the line of sight)"
        )
    if share < 1:
        need = 2 * np.abs(hits).max(0) if len(hits) else (plate.width, plate.height)
        return (
            f"plate '{name}' covers {share:.0%} of the holographic objects the camera "
            f"sees; the rest is cut from the pass (it needs about {need[0]:.3g} x "
            f"{need[1]:.3g} m where it stands)"
        )
    return None
