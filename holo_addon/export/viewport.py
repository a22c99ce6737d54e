"""The 3D viewport's own camera (Blender → :class:`holo_core.scene.camera.Camera`), for the
plate's live view: its pose from ``region_3d.view_matrix``, its lens from the view's Focal
Length on the sensor Blender's 3D view uses, the scene camera's depth of field; in camera view,
the scene camera itself (:func:`holo_addon.export.scene.camera_from_object`).

Blender's 3D view projects as a camera of the view's lens on a 72 mm sensor fitted to the
region's larger side: the default 36 mm sensor at its zoom of 2 (``CAMERA_PARAM_ZOOM_INIT_PERSP``
in ``BKE_camera_params_from_view3d``), so a 50 mm view frames what a 25 mm camera frames.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from holo_core.scene.camera import Camera

from .scene import ExportError, camera_from_object, evaluated, scale, world_matrix

VIEW_SENSOR = (72.0, 48.0)  # [mm] the 3D view's sensor (36 x 24 mm at zoom 2), AUTO fit


@dataclass(frozen=True, slots=True)
class Focus:
    """The scene camera's depth of field as the viewport's camera takes it: its pupil
    ``aperture`` [m] (the camera's lens / N: the same pupil, so the same blur and the same
    place in the plate's zone, whatever the viewport's lens), and where it focuses:
    ``distance`` [m] along the view, or the world point ``target`` [m] (a focus object: its
    distance along the viewport's own axis)."""

    aperture: float
    distance: float | None = None
    target: tuple | None = None


def live_resolution(size, pixels: int) -> tuple[int, int]:
    """The live picture's (width, height) [px]: ``size`` (w, h) scaled so that its larger side
    is ``pixels`` (never scaled up), the aspect kept."""
    w, h = (max(1, int(n)) for n in size)
    k = min(1.0, pixels / max(w, h))
    return max(1, round(w * k)), max(1, round(h * k))


def view_camera(
    view_matrix, lens: float, resolution, unit: float, focus: Focus | None = None
) -> Camera:
    """A perspective 3D view as a camera.

    Parameters
    ----------
    view_matrix : (4, 4) array
        ``region_3d.view_matrix``: world → view, Blender units.
    lens : float
        The view's Focal Length (``SpaceView3D.lens``) [mm].
    resolution : (int, int)
        The picture's (width, height) [px], of the region's aspect.
    unit : float
        Metres per Blender unit; the lens and sensor scale with it as
        :func:`~holo_addon.export.scene.camera_from_object`'s do.
    focus : Focus, optional
        The scene camera's depth of field (None: a pinhole).

    Returns
    -------
    Camera
        At the view's eye [m], looking down its −Z, on :data:`VIEW_SENSOR`.

    Examples
    --------
    >>> import numpy as np
    >>> cam = view_camera(np.eye(4), 50.0, (64, 36), 1.0)
    >>> round(float(np.degrees(cam.field_of_view()[0])), 2)   # 2 atan(36 / 50)
    71.51
    """
    m = world_matrix(np.linalg.inv(np.asarray(view_matrix, np.float64)), unit, normalise=True)
    fstop = distance = None
    if focus is not None:
        fstop = lens * unit * 1e-3 / focus.aperture  # the camera's pupil on this lens
        distance = focus.distance
        if focus.target is not None:
            distance = float(-(np.asarray(focus.target, np.float64) - m[:3, 3]) @ m[:3, 2])
        if distance is None or distance <= 0:
            raise ExportError(
                "the camera's focus lies behind the viewport's eye: move the "
                "view, or the focus object, so that it lies in front"
            )
    return Camera(
        matrix_world=m,
        lens=lens * unit,
        sensor_width=VIEW_SENSOR[0] * unit,
        sensor_height=VIEW_SENSOR[1] * unit,
        sensor_fit="AUTO",
        resolution=tuple(resolution),
        focus_distance=distance,
        fstop=fstop,
    )


def scene_focus(scene, unit: float, depsgraph=None) -> Focus | None:
    """The scene camera's depth of field as :class:`Focus` (None: none, or no camera)."""
    if scene.camera is None or scene.camera.type != "CAMERA":
        return None
    cam = scene.camera.data
    if not cam.dof.use_dof:
        return None
    aperture = cam.lens * unit * 1e-3 / cam.dof.aperture_fstop
    if cam.dof.focus_object is not None:
        target = cam.dof.focus_object
        if depsgraph is not None:
            target = evaluated(target.original, depsgraph)
        return Focus(aperture, target=tuple(np.array(target.matrix_world.translation) * unit))
    return Focus(aperture, distance=cam.dof.focus_distance * unit)


def viewport_camera(scene, space, region_3d, size, pixels: int, depsgraph=None) -> Camera:
    """The camera a 3D view looks through, at a picture of ``pixels`` on its larger side.

    Parameters
    ----------
    scene : bpy.types.Scene
    space : bpy.types.SpaceView3D
        Its Focal Length (``lens``) [mm].
    region_3d : bpy.types.RegionView3D
        Its view matrix and perspective; in camera view, the scene camera is the camera.
    size : (int, int)
        The region's (width, height) [px].
    pixels : int
        The picture's larger side [px] (:func:`live_resolution`).
    depsgraph : bpy.types.Depsgraph, optional
        Where the scene camera and a focus object are evaluated.

    Returns
    -------
    Camera
        In camera view, :func:`~holo_addon.export.scene.camera_from_object`'s camera (the
        whole frame) at the live resolution; else :func:`view_camera`'s.

    Raises
    ------
    ExportError
        In an orthographic view (a plate's view needs an eye), or camera view without a
        scene camera.
    """
    unit = scale(scene)
    if region_3d.view_perspective == "CAMERA":
        if scene.camera is None:
            raise ExportError("camera view without a scene camera")
        obj = evaluated(scene.camera, depsgraph) if depsgraph is not None else scene.camera
        cam = camera_from_object(scene, obj, unit, depsgraph, crop=False)
        return replace(cam, resolution=live_resolution(cam.resolution, pixels))
    if not region_3d.is_perspective:
        raise ExportError(
            "the view is orthographic: a plate is looked through from an eye "
            "(View ▸ Perspective/Orthographic, or numpad 5)"
        )
    return view_camera(
        region_3d.view_matrix,
        space.lens,
        live_resolution(size, pixels),
        unit,
        scene_focus(scene, unit, depsgraph),
    )
