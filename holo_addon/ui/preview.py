"""The holographic result in the viewport while the artist works (Camera mode, camera view).

The emitters are holdouts in the raster, so a viewport in Rendered shading shows a hole where
they stand: a draw handler fills the camera's frame with the latest holographic pass (the
render's own when one is made, else a preview pass), its colours through the scene's view
transform, aligned on the frame as Blender draws it (:func:`frame_rect`). When the scene
changes while a 3D view looks through the camera, a preview pass at 1/``PREVIEW_SCALE`` of
the render's resolution is made again (a quarter of a second after the last change), by the
same worker process as every pass: no OpenCL in Blender's process, and the interface never
waits (a timer drains the worker; a newer change cancels it). The state is the session's
(:attr:`holo_addon.compositor.session.Session.preview`).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import bpy
import numpy as np
from bpy.app.handlers import persistent

from ..blender.images import save_as_displayed
from ..compositor.session import session
from ..export.scene import ExportError, border_pixels, render_size
from ..render import pipeline
from .overlay import attach, detach

log = logging.getLogger(__name__)
PREVIEW_SCALE = 4  # the preview pass's resolution: the render's over this
DEBOUNCE = 0.25  # s after the last change before a preview pass starts
POLL = 0.1  # s between the timer's looks at the worker


@dataclass
class Preview:
    """What the viewport shows: ``picture`` (h, w, 4) straight RGBA as the display shows it
    (the scene's view transform applied), row 0 at the bottom, from ``source`` (a pass
    file), and its GPU texture once drawn; the running preview ``worker``; the latest
    latency [s] from the change to the picture; the ``key`` of the pass shown last."""

    picture: np.ndarray | None = None
    source: str = ""
    stamp: float = 0.0
    texture: object = None
    worker: object = None
    changed: float = 0.0
    latency: float | None = None
    key: str = ""


def state() -> Preview:
    if not isinstance(session.preview, Preview):
        session.preview = Preview()
    return session.preview


# -- alignment ---------------------------------------------------------------------------


def camera_frame(scene, camera) -> np.ndarray:
    """The world corners (4, 3) of the part of the camera's frame the pass covers, in the
    order of ``Camera.view_frame`` (the whole frame; the render region when the render is
    cropped to it)."""
    local = np.array([tuple(v) for v in camera.data.view_frame(scene=scene)])
    r = scene.render
    if r.use_border and r.use_crop_to_border:
        (w, h), (left, top, right, bottom) = render_size(r), border_pixels(r)
        lo, hi = local.min(0), local.max(0)
        fx = np.where(local[:, 0] > (lo[0] + hi[0]) / 2, right / w, left / w)
        fy = np.where(local[:, 1] > (lo[1] + hi[1]) / 2, 1 - top / h, 1 - bottom / h)
        local[:, 0], local[:, 1] = lo[0] + fx * (hi[0] - lo[0]), lo[1] + fy * (hi[1] - lo[1])
    m = np.array(camera.matrix_world)
    return local @ m[:3, :3].T + m[:3, 3]


def frame_rect(perspective, size, corners) -> tuple[float, float, float, float]:
    """(left, bottom, right, top) [region pixels] where the world ``corners`` (4, 3) land
    in a region of ``size`` (w, h) whose view has the 4x4 ``perspective`` matrix (the
    viewport's ``region_3d.perspective_matrix``), as Blender projects them."""
    p = (
        np.c_[np.asarray(corners, np.float64), np.ones(len(corners))]
        @ np.asarray(perspective, np.float64).T
    )
    xy = (p[:, :2] / p[:, 3:] + 1) / 2 * np.asarray(size, np.float64)
    return (
        float(xy[:, 0].min()),
        float(xy[:, 1].min()),
        float(xy[:, 0].max()),
        float(xy[:, 1].max()),
    )


# -- the picture ---------------------------------------------------------------------------


def show(path) -> None:
    """Show the pass ``path`` (its PNG through the scene's view transform beside it): the
    picture the viewport's texture is made from. The texture is made again at the next
    draw."""
    png = path.with_suffix(".png")
    image = bpy.data.images.load(str(png), check_existing=False)
    try:
        w, h = image.size
        pixels = np.empty(w * h * 4, np.float32)
        image.pixels.foreach_get(pixels)  # a byte image: its values as stored, bottom row first
    finally:
        bpy.data.images.remove(image)
    p = state()
    p.picture, p.source, p.stamp, p.texture = (
        pixels.reshape(h, w, 4),
        str(path),
        png.stat().st_mtime,
        None,
    )
    if p.changed:
        p.latency, p.changed = time.perf_counter() - p.changed, 0.0
    _redraw()


def shown_pass(scene):
    """The pass the viewport should show for the current frame: the render's own when its
    file is newer than the preview's, else the preview's; None when neither exists."""
    try:
        out = pipeline.output_dir(scene)
    except ExportError:
        return None
    found = [
        p
        for p in (
            pipeline.pass_file(out, scene.frame_current),
            pipeline.pass_file(out / "preview", scene.frame_current),
        )
        if p.is_file() and p.with_suffix(".png").is_file()
    ]
    return max(found, key=lambda p: p.stat().st_mtime, default=None)


# -- the preview pass -----------------------------------------------------------------------


def start(scene, depsgraph) -> bool:
    """Start a preview pass of the scene as ``depsgraph`` evaluates it (a running one is
    cancelled); returns at once. False (nothing started) outside Camera mode, or when the
    scene cannot be read (no emitter, no camera: nothing to show)."""
    p = state()
    if p.worker is not None:
        p.worker.cancel()
        p.worker = None
    if scene.holo.mode != "CAMERA":
        return False
    try:
        job = pipeline.prepare(scene, depsgraph, preview=PREVIEW_SCALE)
    except (ExportError, ValueError) as e:
        log.debug("preview: %s", e)
        return False
    key = job.job.output.pass_key
    if key == p.key:  # already shown (a change that does not touch the pass)
        p.changed = 0.0
        return False
    p.key = key
    p.changed = p.changed or time.perf_counter()
    cached = pipeline.cached_pass(job)
    if cached is not None:
        _done(scene, cached)
        return True
    try:
        p.worker = pipeline.start(job)
    except OSError as e:
        log.warning("preview: the worker process did not start: %s", e)
        return False
    return True


def poll(scene) -> bool:
    """Drain the running preview's messages (a timer does, every ``POLL`` s); returns
    whether it still runs."""
    p = state()
    if p.worker is None:
        return False
    for kind, value in p.worker.poll():
        if kind == "done":
            p.worker = None
            _done(scene, value)
        elif kind == "failed":
            p.worker, p.key = None, ""
            log.warning("preview: %s", value)
    return p.worker is not None


def _done(scene, result) -> None:
    path = result.pass_path
    if path is None:
        return
    save_as_displayed(scene, path, path.with_suffix(".png"))  # the view transform as it is now
    show(path)


# -- the interface ---------------------------------------------------------------------------


def _camera_views():
    """The 3D views that look through the scene camera."""
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if (
                area.type == "VIEW_3D"
                and area.spaces.active.region_3d is not None
                and area.spaces.active.region_3d.view_perspective == "CAMERA"
            ):
                yield area


def _redraw():
    if bpy.app.background:
        return
    for area in _camera_views():
        area.tag_redraw()


@persistent
def _changed(scene, depsgraph=None):
    """The scene changed (or the frame): a preview pass after ``DEBOUNCE`` s of quiet, when
    a 3D view looks through the camera."""
    if (
        depsgraph is None
        or depsgraph.mode != "VIEWPORT"
        or not scene.holo.preview
        or not any(_camera_views())
    ):
        return
    if depsgraph.updates and all(isinstance(u.id, bpy.types.Image) for u in depsgraph.updates):
        return  # the preview's own pictures
    state().changed = state().changed or time.perf_counter()
    if bpy.app.timers.is_registered(_refresh):
        bpy.app.timers.unregister(_refresh)
    bpy.app.timers.register(_refresh, first_interval=DEBOUNCE)


def _refresh():
    scene = bpy.context.scene
    if start(scene, bpy.context.evaluated_depsgraph_get()) and not bpy.app.timers.is_registered(
        _drain
    ):
        bpy.app.timers.register(_drain, first_interval=POLL)
    return None


def _drain():
    return POLL if poll(bpy.context.scene) else None


def _draw():
    """POST_PIXEL in every 3D view: the pass over the camera's frame, in camera view."""
    context = bpy.context
    scene, rv3d = context.scene, context.region_data
    if (
        rv3d is None
        or rv3d.view_perspective != "CAMERA"
        or scene.camera is None
        or not scene.holo.preview
        or scene.holo.mode != "CAMERA"
    ):
        return
    p = state()
    path = shown_pass(scene)
    if path is None:
        return
    if str(path) != p.source or path.with_suffix(".png").stat().st_mtime != p.stamp:
        show(path)
    if p.picture is None:
        return
    import gpu
    from gpu_extras.presets import draw_texture_2d

    if p.texture is None:
        h, w, _ = p.picture.shape
        data = gpu.types.Buffer("FLOAT", w * h * 4, p.picture.ravel().tolist())
        p.texture = gpu.types.GPUTexture((w, h), format="RGBA16F", data=data)
    region = context.region
    left, bottom, right, top = frame_rect(
        rv3d.perspective_matrix, (region.width, region.height), camera_frame(scene, scene.camera)
    )
    gpu.state.blend_set("ALPHA")
    draw_texture_2d(p.texture, (left, bottom), right - left, top - bottom)
    gpu.state.blend_set("NONE")


HANDLERS = (("depsgraph_update_post", _changed), ("frame_change_post", _changed))
_handle = []


def register():
    attach(HANDLERS, _draw, "POST_PIXEL", _handle)


def unregister():
    p = state()
    if p.worker is not None:
        p.worker.cancel()
    session.preview = None
    detach(HANDLERS, _handle)
    for timer in (_refresh, _drain):
        if bpy.app.timers.is_registered(timer):
            bpy.app.timers.unregister(timer)
