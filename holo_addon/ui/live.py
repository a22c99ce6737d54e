"""The plate's live view in the 3D viewport: Plate mode, a recorded plate (or set), Live Plate
View on, a 3D view in Rendered shading; the viewport shows the plate's view from its own camera
(:func:`holo_addon.export.viewport.viewport_camera`) while the artist orbits, pans, zooms and
refocuses.

A worker process of its own holds the plate (:class:`holo_core.worker.Views`) and hands its
pictures back through shared memory: no OpenCL in Blender's process, and the interface never
waits. The draw handler asks a coarse view whenever the view's camera changes; a timer takes
the pictures as they come and, once the view has been still for ``STILL`` s, asks the full
one. Where the eye leaves the plate's zone, the viewport says so in words (the zone is the
blue box of the coverage overlay) and shows no picture. The state is the session's
(:attr:`holo_addon.compositor.session.Session.live`).
"""

from __future__ import annotations

import atexit
import logging
import textwrap
import time
from dataclasses import dataclass, field

import bpy
import numpy as np
from bpy.app.handlers import persistent

from holo_core.job import CameraRoute, SetRoute
from holo_core.preview import srgb
from holo_core.worker import Views, WorkerError

from ..blender import compat
from ..compositor.session import session
from ..export.scene import ExportError
from ..export.viewport import viewport_camera
from ..render import pipeline
from ..render.options import worker_options
from .overlay import attach, detach
from .preview import frame_rect

log = logging.getLogger(__name__)
STILL = 0.15  # s of stillness after a move before the full view is asked
POLL = 0.02  # s between the timer's looks at the worker while a view is awaited
REREAD = 0.3  # s after the last scene change before the plate's files are looked up again
ZONE_HINT = "The plate's viewing zone is the blue box (Overlays ▸ Holo Plate Coverage)."


@dataclass(frozen=True)
class Source:
    """The plate a live view reads: its files (``plates``: the looks' files, or a set's
    folder), the ``recording`` they must be and the view's ``options``
    (:class:`holo_core.job.ViewOpen`'s); or ``why`` there is none ('' : there is)."""

    plates: tuple = ()
    recording: str = ""
    options: tuple = ()
    why: str = ""


@dataclass
class Live:
    """What the live view shows and asks: the plate's ``source`` and its ``views``; the 3D
    view's ``region`` it serves (``as_pointer``: the one that moved last; ``keys``, each
    view's camera as it was asked), the ``camera`` asked last and its ``key``,
    when it ``moved`` [s, ``time.perf_counter``], the request of its full view (``full``; 0:
    not asked yet); the picture ``shown`` (:class:`holo_core.worker.ViewPicture`) and its GPU
    ``texture``; the latencies [s] from the last move to its first picture (``coarse``) and to
    its full picture (``latency``); ``why`` nothing is drawn ('' : something is)."""

    source: Source | None = None
    views: Views | None = None
    region: int = 0
    camera: object = None
    key: tuple = ()
    moved: float = 0.0
    full: int = 0
    first: int = 0
    shown: object = None
    texture: object = None
    coarse: float | None = None
    latency: float | None = None
    why: str = ""
    seen: list = field(default_factory=list)  # when pictures arrived [s], the latest 32
    keys: dict = field(default_factory=dict)


def state() -> Live:
    if not isinstance(session.live, Live):
        session.live = Live()
    return session.live


# -- the plate ----------------------------------------------------------------------------


def plate_source(scene, depsgraph) -> Source:
    """The plate's files the scene's render would view (:func:`holo_addon.export.job.read`),
    or why there are none: not Plate mode, no plate, not recorded since the scene changed."""
    if scene.holo.mode != "PLATE":
        return Source(why="Live Plate View shows a recorded plate: set Hologram to Plate")
    try:
        prepared = pipeline.prepare(scene, depsgraph, render=False)
    except (ExportError, ValueError) as e:
        return Source(why=str(e))
    route = prepared.job.route
    if isinstance(route, CameraRoute):
        return Source(why=prepared.instead or "the frame is a camera hologram")
    if route.record:
        return Source(
            why=f"plate '{prepared.plate_name}' is not recorded for the scene as it "
            f"is: Record Hologram (Render ▸ Holo), then look through it"
        )
    plates = (
        (str(route.folder),) if isinstance(route, SetRoute) else tuple(map(str, route.holograms))
    )
    # the route's settings, Supersample at Auto resolved as the render resolves it
    return Source(
        plates=plates,
        recording=route.recording,
        options=(
            ("supersample", route.supersample),
            ("composition", route.composition),
            ("opacity_threshold", route.opacity_threshold),
            ("exposure", route.exposure),
        ),
    )


def refresh(scene, depsgraph) -> Source:
    """Look up the plate again: a changed plate (or its settings) gets views of its own, the
    picture of the one before is dropped; no plate closes the views."""
    p = state()
    source = plate_source(scene, depsgraph)
    if source == p.source and (p.views is not None or source.why):
        return source
    close()
    p.source, p.why = source, source.why
    if not source.why:
        p.views = Views(
            source.plates, recording=source.recording, **dict(source.options), **worker_options()
        )
    _redraw()
    return source


def close() -> None:
    """End the live view's worker; nothing is shown until the next look."""
    p = state()
    if p.views is not None:
        p.views.close()
    p.views, p.shown, p.texture, p.key, p.camera, p.full, p.first = None, None, None, (), None, 0, 0
    p.keys = {}


# -- asking and taking views -----------------------------------------------------------------


def camera_key(camera) -> tuple:
    """What a view depends on of ``camera`` (its pose, lens, sensor, frame and focus)."""
    return (
        camera.matrix_world.tobytes(),
        camera.lens,
        camera.sensor_width,
        camera.sensor_height,
        camera.sensor_fit,
        camera.shift_x,
        camera.shift_y,
        camera.resolution,
        camera.pixel_aspect,
        camera.fstop,
        camera.focus_distance,
    )


def look(region: int, camera, now: float | None = None) -> int:
    """The 3D view ``region`` looks through ``camera`` now: a coarse view is asked when it
    differs from the one this view asked last (a move: the moving view is the one served,
    so two views open at once do not take turns); returns that request, or 0 (no move, or no
    plate). Never waits."""
    p = state()
    key = camera_key(camera)
    if p.views is None or key == p.keys.get(region):
        return 0
    now = time.perf_counter() if now is None else now
    p.keys[region] = key
    p.region, p.camera, p.key, p.moved, p.full = region, camera, key, now, 0
    try:
        p.first = p.views.ask(camera, coarse=True)
    except (WorkerError, OSError) as e:
        p.why = f"the live view's worker failed: {e}"
        return 0
    _ensure_timer()
    return p.first


def poll(now: float | None = None) -> bool:
    """Take the newest answer; ask the full view once the camera has been still for
    ``STILL`` s. Returns whether an answer is still awaited (the timer goes on)."""
    p = state()
    if p.views is None:
        return False
    now = time.perf_counter() if now is None else now
    shown = p.views.latest()
    if shown is not None and shown is not p.shown:
        p.shown, p.texture = shown, None
        p.seen = (p.seen + [now])[-32:]
        if p.first and shown.request >= p.first:  # the move's first picture
            p.coarse, p.first = now - p.moved, 0
        if p.full and shown.request >= p.full:
            p.latency = now - p.moved
        if shown.error:
            log.warning("live plate view: %s", shown.error)
        _redraw()
    if not p.full and p.camera is not None and now - p.moved >= STILL:
        try:
            p.full = p.views.ask(p.camera)
        except (WorkerError, OSError) as e:
            p.why = f"the live view's worker failed: {e}"
            return False
    return not p.full or p.shown is None or p.shown.request < p.full


def rate() -> float | None:
    """Pictures a second over the latest ones that arrived (None: fewer than 2)."""
    seen = state().seen
    if len(seen) < 2 or seen[-1] <= seen[0]:
        return None
    return (len(seen) - 1) / (seen[-1] - seen[0])


def texture_pixels(rgba, exposure: float = 0.0, *, linear: bool = True) -> np.ndarray:
    """A picture (H, W, 4) straight RGBA, row 0 at the top, as a texture's float32 values:
    rows from the bottom, the colour management's ``exposure`` [stops] applied; ``linear``
    False: encoded with the sRGB curve (a drawing that takes display values)."""
    out = np.array(rgba[::-1], np.float32)
    rgb = out[..., :3]
    rgb *= np.float32(2.0**exposure)
    if not linear:
        rgb[...] = srgb(rgb)
    np.clip(out[..., 3], 0.0, 1.0, out=out[..., 3])
    return out.ravel()


def words(scene) -> str:
    """What the panel says of the live view: its rate and latency, or why it shows none."""
    p = state()
    if not scene.holo.live_plate:
        return ""
    if p.why:
        return p.why
    if p.shown is not None and p.shown.where:
        return "outside the plate's zone (the viewport says where)"
    parts = []
    if rate() is not None:
        parts.append(f"{rate():.1f} pictures a second")
    if p.latency is not None:
        parts.append(f"full view {p.latency:.2f} s after the last move")
    return ", ".join(parts) or "waiting for the first picture"


# -- the interface ---------------------------------------------------------------------------


def _ensure_timer():
    if not bpy.app.timers.is_registered(_tick):
        bpy.app.timers.register(_tick, first_interval=POLL)


def _tick():
    return POLL if poll() else None


def _redraw():
    if bpy.app.background:
        return
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()


def shows(context) -> bool:
    """Whether this 3D view draws the live view: Live Plate View on, Plate mode, Rendered
    shading."""
    scene, space = context.scene, context.space_data
    return (
        scene.holo.live_plate
        and scene.holo.mode == "PLATE"
        and space is not None
        and space.type == "VIEW_3D"
        and space.shading.type == "RENDERED"
    )


def toggled(context) -> None:
    """Live Plate View turned on (the plate looked up now) or off (its worker ended)."""
    if context.scene.holo.live_plate:
        refresh(context.scene, context.evaluated_depsgraph_get())
    else:
        close()
        state().source = None
    _redraw()


@persistent
def _changed(scene, depsgraph=None):
    """The scene changed: the plate is looked up again after ``REREAD`` s of quiet (a new
    recording, a plate moved, the settings changed)."""
    if depsgraph is None or depsgraph.mode != "VIEWPORT" or not scene.holo.live_plate:
        return
    if depsgraph.updates and all(isinstance(u.id, bpy.types.Image) for u in depsgraph.updates):
        return
    if bpy.app.timers.is_registered(_reread):
        bpy.app.timers.unregister(_reread)
    bpy.app.timers.register(_reread, first_interval=REREAD)


def _reread():
    scene = bpy.context.scene
    if scene.holo.live_plate:
        refresh(scene, bpy.context.evaluated_depsgraph_get())
    return None


@persistent
def _forget(*_):
    close()
    session.live = None


def _frame(scene, rv3d, region):
    """Where the picture goes (left, bottom, width, height) [region px]: the whole region, or
    in camera view the camera's frame as Blender draws it."""
    if rv3d.view_perspective != "CAMERA":
        return 0.0, 0.0, float(region.width), float(region.height)
    cam = scene.camera
    local = np.array([tuple(v) for v in cam.data.view_frame(scene=scene)])
    m = np.array(cam.matrix_world)
    left, bottom, right, top = frame_rect(
        rv3d.perspective_matrix, (region.width, region.height), local @ m[:3, :3].T + m[:3, 3]
    )
    return left, bottom, right - left, top - bottom


def _draw():
    """POST_PIXEL in every 3D view: the plate's view from the view's camera, or why not."""
    context = bpy.context
    if not shows(context):
        return
    scene, rv3d, region = context.scene, context.region_data, context.region
    p = state()
    if p.source is None:  # looked up from a timer: a drawing evaluates nothing
        if not bpy.app.timers.is_registered(_reread):
            bpy.app.timers.register(_reread, first_interval=0.0)
        return
    if p.why:
        _text(region, [p.why])
        return
    try:  # the objects as the viewport shows them (their matrices are the evaluated ones)
        camera = viewport_camera(
            scene, context.space_data, rv3d, (region.width, region.height), scene.holo.live_pixels
        )
    except (ExportError, ValueError) as e:
        _text(region, [str(e)])
        return
    look(region.as_pointer(), camera)
    shown = p.shown
    if region.as_pointer() != p.region or shown is None:
        return
    if shown.where or shown.error:  # never the picture from before as if it were current
        _text(region, [shown.where or shown.error, ZONE_HINT if shown.where else ""])
        return
    import gpu
    from gpu_extras.presets import draw_texture_2d

    linear = compat.draws_linear_textures()
    if p.texture is None:
        h, w, _ = shown.rgba.shape
        pixels = texture_pixels(shown.rgba, scene.view_settings.exposure, linear=linear)
        data = gpu.types.Buffer("FLOAT", pixels.size, pixels)
        p.texture = gpu.types.GPUTexture((w, h), format="RGBA16F", data=data)
    left, bottom, width, height = _frame(scene, rv3d, region)
    gpu.state.blend_set("ALPHA")
    compat.draw_linear_texture(
        draw_texture_2d, p.texture, (left, bottom), width, height, linear=linear
    )
    gpu.state.blend_set("NONE")
    if shown.coarse:
        _text(region, ["Holo: coarse view (the full view follows when the view stops)"], dim=True)


def _text(region, lines, *, dim=False) -> None:
    """``lines`` written in the view's top-left corner, wrapped to its width."""
    import blf

    font, size = 0, 13
    blf.size(font, size)
    blf.color(font, 1.0, 1.0, 1.0, 0.6 if dim else 0.95)
    width = max(20, int(region.width / (size * 0.55)))
    wrapped = [w for line in lines if line for w in textwrap.wrap(line, width)]
    y = region.height - 60
    for line in wrapped:
        blf.position(font, 20, y, 0)
        blf.draw(font, line)
        y -= int(size * 1.5)


HANDLERS = (("depsgraph_update_post", _changed), ("load_post", _forget))
_handle = []
atexit.register(close)  # Blender's end: the worker ended, the shared memory unlinked


def register():
    attach(HANDLERS, _draw, "POST_PIXEL", _handle)


def unregister():
    close()
    session.live = None
    detach(HANDLERS, _handle)
    for timer in (_tick, _reread):
        if bpy.app.timers.is_registered(timer):
            bpy.app.timers.unregister(timer)
