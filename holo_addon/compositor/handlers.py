"""The frame handlers of a render: each rendered frame makes its holographic pass from the
render's own depsgraph (:func:`render_frame`), says in the log what it made (a farm's output
shows it), and a failure never leaves another state's pass in the frame (:func:`failed`).
Runtime state lives in :data:`holo_addon.compositor.session.session`."""

from __future__ import annotations

import json
import logging
import os
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

import bpy
from bpy.app.handlers import persistent

from holo_core import jobs
from holo_core.io.image import exr_attribute

from ..blender.images import show_image
from ..export import motion
from ..export.display import read as read_display
from ..export.display import scene_display
from ..export.scene import NoEmitters, emitter_instances
from ..render import display, pipeline
from . import tree
from .session import session

log = logging.getLogger(__name__)


@persistent
def render_init(scene, *_):
    """A render begins (F12, ``-f``, ``-a``: once): the holographic layers follow the render
    output's path, the blend the film, the passes the .blend's output folder."""
    session.render_started()
    with _failing(scene, scene.frame_current):
        tree.follow_render_output(scene)
        tree.follow_film(scene)
    if tree.uses_pass(scene):  # a frame of the render (F12's) gets a clear pass where it has
        # none before Blender's copy of the image looks for it (found missing then, it stays
        # missing for the render: the Image node's grey)
        _point_passes(
            scene,
            scene.frame_current,
            rendering=scene.frame_start <= scene.frame_current <= scene.frame_end,
        )


@persistent
def render_ended(*_):
    """A render completed or was cancelled: a pass an operator made for it is not for the
    next one, nor a shutter it left incomplete, and the worker kept between its frames ends
    (the plate it held in memory is freed)."""
    session.made = session.shutter = session.frame_done = None
    pipeline.release()


@persistent
def render_post(scene, *_):
    """A frame is composited: its holographic layers' depth channels named ``.Z``. A shutter
    the render did not evaluate whole has left the frame without its pass, and layers that
    cannot be rewritten are not what the frame delivers: either fails the render (status 1
    in the background, the error in the interface's reports), though Blender has composited
    the frame by now."""
    if session.shutter is not None:
        frame, session.shutter = session.shutter.frame, None
        _delivered_wrong(
            f"Holo: frame {frame}: the render never evaluated its shutter's "
            f"closing, so its holographic pass was not made (turn motion blur "
            f"off for this frame)"
        )
    session.frame_done = None
    if not tree.uses_pass(scene):
        return
    for path in tree.layers_file(scene, scene.frame_current):
        try:
            if path.is_file() and path.stat().st_mtime >= session.started - 1:
                tree.name_depths_z(path)
                _say_holes(scene, tree.holes(path))
        except Exception as e:  # noqa: BLE001 -- the library's errors, whatever their class
            _delivered_wrong(
                f"Holo: the holographic layers {path} of frame "
                f"{scene.frame_current} could not be rewritten with their depth "
                f"channels named .Z: {e}"
            )


def _say_holes(scene, count: int) -> None:
    """An opaque scene's frame with transparent pixels is said, with their count."""
    if count and not scene.render.film_transparent:
        warn(
            f"Holo: frame {scene.frame_current}: {count} pixels of the composite are "
            f"transparent (alpha below 0.99): neither Blender's render nor the holographic "
            f"pass covers them"
        )


ENGINES_WITH_SHUTTER = ("CYCLES", "BLENDER_EEVEE", "BLENDER_EEVEE_NEXT")  # evaluate sub-frames


@persistent
def render_frame(scene, depsgraph=None):
    """``frame_change_post``: when Blender has evaluated a frame for rendering (F12, ``-f``,
    ``-a``; its depsgraph is then the render's, in RENDER mode), the holographic pass of that
    frame from that depsgraph: the frame being rendered whatever the timeline shows, render
    modifier levels and render visibility. With motion blur (Camera mode, Cycles or EEVEE),
    the emitters are also taken where the render evaluates the shutter's opening and closing
    (its sub-frames), and the pass is made once both are in, blurred as the raster is. The
    hologram is recorded again only when the scene changed. A failed pass never leaves
    another state's pass in the composite (see :func:`failed`)."""
    if depsgraph is None or depsgraph.mode != "RENDER":
        return
    frame = session.shutter.frame if session.shutter is not None else scene.frame_current
    with _failing(scene, frame):
        _render_frame(scene, depsgraph)


def _render_frame(scene, depsgraph) -> None:
    frame, pending = scene.frame_current, session.shutter
    if pending is not None:  # the frame's shutter, as the render evaluates it
        pending.add(motion.sample(scene, depsgraph))
        if pending.complete():
            session.shutter = None
            job = pipeline.moving(
                pending.job, list(pending.samples.values()), pending.opening, pending.closing
            )
            _frame_pass(scene, pending.frame, job)
        return
    if scene.frame_subframe or session.frame_done == (scene.name, frame):
        return  # a sub-frame, or the frame's own time again, of a frame already seen
    session.frame_started(frame)
    session.frame_done = (scene.name, frame)
    shown = scene_display(scene)
    if shown is not None:
        display_frame(scene, depsgraph, shown, resident=True)
    names = [inst.object.original.name for inst, _ in emitter_instances(depsgraph)]
    if not tree.uses_pass(scene):
        if (
            names and shown is None
        ):  # never a silent vanish: the camera sees emitters through the pass only
            _warn_once(
                "setup",
                f"Holo: the holographic objects ({_listed(names)}) are not "
                f"in this render: the compositor has no holographic pass "
                f"(Render ▸ Holo ▸ Set Up Compositing, or Render with "
                f"Hologram)",
            )
        return
    if not _point_passes(scene, frame, rendering=True):
        return
    blur = names and motion.blurs(scene)
    if names and scene.render.use_motion_blur and not blur:
        _warn_once(
            "blur",
            "Holo: motion blur is on: in Plate mode the holographic objects "
            "are rendered at each frame's time, without blur",
        )
    elif blur and scene.render.engine not in ENGINES_WITH_SHUTTER:
        _warn_once(
            "blur",
            f"Holo: motion blur is on, but {scene.render.engine} evaluates no "
            f"shutter: the holographic objects are not blurred",
        )
        blur = False
    if session.take_made(scene.name, frame):
        log.info("Holo: frame %d: holographic pass made just before this render, reused", frame)
        return
    try:
        job = pipeline.prepare(scene, depsgraph)
    except NoEmitters:  # none left: the frame is the raster alone
        if scene.holo.pass_on_render:
            pipeline.clear_pass(scene, frame)
            tree.point_passes(scene, frame)
            log.info(
                "Holo: frame %d: no holographic emitters left: it renders the raster "
                "alone (Render ▸ Holo ▸ Remove Holo Compositing takes the pass out)",
                frame,
            )
        elif (path := tree.point_passes(scene, frame)) is not None and path.is_file():
            warn(
                f"Holo: the holographic pass of frame {frame} is stale: no holographic "
                f"emitter is left, and it is composited as it is (Pass on Every Render is "
                f"off)"
            )
        return
    except Exception as e:
        if not scene.holo.pass_on_render:  # the scene cannot be read: say so, render on
            warn(f"Holo: the holographic pass of frame {frame} could not be checked: {e}")
            return
        raise
    for warning in job.warnings:
        _log(logging.WARNING, warning)
    if blur:
        pending = motion.Shutter(frame, *motion.shutter(scene), job=job)
        pending.add(motion.sample(scene, depsgraph))
        session.shutter = pending
        return
    _frame_pass(scene, frame, job)


SHEET_IMAGE = "Holo Display Focal Stack"


def display_frame(scene, depsgraph, obj, *, resident=False, progress=None):
    """The display's frame of the scene as ``depsgraph`` evaluates it (a render's: the frame
    rendered): its patterns, layout and focal stack written together (or found up to date),
    the stack's contact sheet shown in the Image Editor, and one log line with each laser's
    PSNR and SSIM per focal slice. A scene the display cannot show is refused before any
    work (:class:`holo_addon.export.scene.ExportError`). Returns the
    :class:`holo_addon.render.display.FrameResult`."""
    prepared = read_display(scene, depsgraph, obj)
    for warning in prepared.warnings:
        _log(logging.WARNING, warning)
    session.pass_started(prepared.frame)
    try:
        result = display.run(prepared, progress or _progress, _log, resident=resident)
    finally:
        session.pass_ended()
    show_image(result.sheet, SHEET_IMAGE)
    log.info("Holo: %s", display.summary(obj.name, result))
    return result


@contextmanager
def _failing(scene, frame: int):
    """Whatever fails inside, of whatever class, fails frame ``frame`` (:func:`failed`): a
    handler's exception would only print a traceback, and Blender would render on and write
    the frame without its pass."""
    try:
        yield
    except Exception as e:  # noqa: BLE001 -- any failure must stop the frame, not pass by
        failed(scene, f"Holo: the holographic pass of frame {frame} failed: {e}")


def _point_passes(scene, frame: int, *, rendering: bool) -> bool:
    """The compositor reads frame ``frame``'s pass from the output folder
    (:func:`tree.point_passes`); a folder that cannot be written (under a file, read-only, a
    link to either) fails the frame, naming the setting and the folder. Returns whether it
    could."""
    try:
        tree.point_passes(scene, frame, rendering=rendering)
    except Exception as e:  # noqa: BLE001 -- the OS's errors and the writer's InputError
        reason = e.strerror if isinstance(e, OSError) and e.strerror else e
        failed(
            scene,
            f"Holo: the holographic pass of frame {frame} cannot be written: the "
            f"Output Folder (Render Properties ▸ Holo) "
            f"{_folder_of(scene)}: {reason}",
        )
        return False
    return True


def _folder_of(scene) -> str:
    """The Output Folder as the user set it, made absolute (a link not followed: the reason
    names the folder it leads to)."""
    return bpy.path.abspath(scene.holo.output_dir or "//holo/")


def _frame_pass(scene, frame: int, job) -> None:
    """The frame's pass of ``job``: made (or found up to date), or with Pass on Every Render
    off, the pass on disk checked; one line in the log says which."""
    if not scene.holo.pass_on_render:
        _check_stale(scene, job)
        return
    session.pass_started(frame)
    started = time.perf_counter()
    try:
        # the frames of a render share one worker, which holds the plate between them
        result = pipeline.run(job, _progress, _log, resident=True)
        pipeline.apply(scene, job, result)
        tree.pass_made(scene, result)
    except jobs.Cancelled:
        failed(scene, f"Holo: the holographic pass of frame {frame} was cancelled")
        return
    finally:
        session.pass_ended()
    log.info(
        "Holo: frame %d: %s",
        frame,
        made(result, time.perf_counter() - started, session.warnings["texts"], job.made_by),
    )


def made(result, seconds: float, warnings=(), route="") -> str:
    """One line of what a frame's pass was: made or reused, its time, the ``route`` that
    made it (:attr:`holo_addon.export.job.Prepared.made_by`), its file and its warnings."""
    if result.reused == result.pass_path:
        verb = "reused (up to date)"
    elif result.reused is not None:
        verb = f"reused from {result.reused.name} (a static shot: only the frame changed)"
    else:
        verb = f"made in {seconds:.1f} s" + (" (hologram recorded)" if result.recorded else "")
    said = (
        f"; {len(warnings)} warning{'s' * (len(warnings) != 1)}: " + " | ".join(warnings)
        if warnings
        else "; no warnings"
    )
    return f"holographic pass {verb}{' ' * bool(route)}{route}: {result.pass_path}{said}"


def _listed(names, most=3) -> str:
    names = list(dict.fromkeys(names))
    more = f" and {len(names) - most} more" if len(names) > most else ""
    return ", ".join(f"'{n}'" for n in names[:most]) + more


def _warn_once(key: str, text: str) -> None:
    """A warning given once per render (an animation included)."""
    if session.warn_once(key):
        warn(text)


def warn(text: str) -> None:
    """A warning of a render's pass: in the log (a farm's output), in Render ▸ Holo, and in
    the interface in Blender's reports (status bar, Info log)."""
    _log(logging.WARNING, text)
    if not bpy.app.background:
        bpy.app.timers.register(lambda: _show_warning(text), first_interval=0.0)


def _show_warning(message):
    try:
        bpy.ops.holo.report(message=message, level="WARNING")
    except RuntimeError as e:
        log.debug("report: %s", e)


def _age(seconds: float) -> str:
    seconds = max(0.0, seconds)
    for unit, size in (("days", 86400), ("h", 3600), ("min", 60)):
        if seconds >= size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.0f} s"


def _check_stale(scene, job) -> None:
    """Pass on Every Render is off: the frame composites the pass on disk as it is; a warning
    when it was made from another state of the scene (with its age) or is missing (a clear
    pass then takes its place: a missing file shows as the Image node's grey)."""
    frame, key, path = job.job.output.frame, job.job.output.pass_key, job.job.output.pass_path
    if not path.is_file() or _is_clear(path):
        warn(
            f"Holo: frame {frame} has no holographic pass (Pass on Every Render is off): "
            f"its holographic objects' places are left empty"
        )
        pipeline.clear_pass(scene, frame)
        tree.point_passes(scene, frame)
        return
    if pipeline.stored_key(path) != key:
        age = _age(time.time() - path.stat().st_mtime)
        warn(
            f"Holo: the holographic pass of frame {frame} is stale: made {age} ago from "
            f"another state of the scene, it is composited as it is (Pass on Every Render "
            f"is off; Render Pass makes it again)"
        )
    else:
        log.info(
            "Holo: frame %d: holographic pass up to date, composited as it is: %s", frame, path
        )


def _is_clear(path) -> bool:
    """Whether the pass file ``path`` is a clear pass (no emitter was in it)."""
    try:
        return json.loads(exr_attribute(path, "holo") or "{}").get("emitters") == 0
    except ValueError:
        return False


def _log(level, text):
    log.log(level, text)
    if level >= logging.WARNING:
        session.warning(text)


def _progress(fraction):
    session.running.fraction = fraction
    if session.running.cancel:
        raise jobs.Cancelled()


def _show_progress():
    """A timer on the interface's thread: the render's pass progress in the status bar."""
    running = session.running
    text = (
        None
        if running.frame is None
        else (
            f"Holo: holographic pass of frame {running.frame}: {running.fraction:.0%} (Render "
            f"Properties ▸ Holo ▸ Cancel Pass)"
        )
    )
    if text != session.shown:
        session.shown = text
        for window in bpy.context.window_manager.windows:
            try:
                with bpy.context.temp_override(window=window):
                    window.workspace.status_text_set(text)
                for area in window.screen.areas:
                    if area.type == "PROPERTIES":
                        area.tag_redraw()
            except Exception as e:  # noqa: BLE001 -- a timer that raises is unregistered
                log.debug("status text: %s", e)
    return 0.25


def failed(scene, message: str) -> None:
    """A failed pass. In a background render the process exits with status 1 before the frame
    is rendered, so ``blender -b ... -a`` fails and no frame with a stale pass is written. In
    the interface (a handler cannot cancel Blender's render) the frame's earlier pass, now
    stale, is set aside as ``holo_pass_NNNN.stale.exr`` (kept, but out of the image sequence)
    and a clear pass takes its place (a missing file shows as the Image node's grey), so the
    composite shows the raster alone (the holographic objects' holes empty), never a pass of
    another state, folder or file; the error goes to Blender's reports and a popup. (Muting
    the node would not do: the render has already evaluated its copy of the compositor.)"""
    _exit_in_background(message)
    log.error(message)
    try:
        stale = pipeline.pass_file(pipeline.output_dir(scene), scene.frame_current)
        if stale.is_file() and not _is_clear(stale):
            os.replace(stale, stale.with_suffix(".stale.exr"))
        if not stale.is_file():
            pipeline.clear_pass(scene, scene.frame_current)
        tree.point_passes(scene)
    except Exception as e:  # noqa: BLE001 -- the OS's errors and the writer's InputError
        log.error("the stale pass could not be set aside: %s", e)
        _raster_alone(scene)
    _report(message)


def _exit_in_background(message: str) -> None:
    """In a background Blender (unless :attr:`Session.exit_on_failure` says otherwise), the
    process ends here with status 1, ``message`` said once on stderr whatever the log's
    handlers (the farm's output)."""
    exit_now = bpy.app.background if session.exit_on_failure is None else session.exit_on_failure
    if exit_now:
        sys.stderr.write(message + "\n")
        sys.stderr.flush()
        os._exit(1)


def _report(message: str) -> None:
    if not bpy.app.background:
        bpy.app.timers.register(lambda: _show_error(message), first_interval=0.0)


def _delivered_wrong(message: str) -> None:
    """The frame Blender has composited is not what was asked (it is written or about to
    be): status 1 in the background, the error in the interface's reports."""
    _exit_in_background(message)
    log.error(message)
    _report(message)


def _raster_alone(scene) -> None:
    """The frame composites a clear pass kept in this process's own temporary folder: the
    output folder cannot take one (it cannot be written), and the images must not go on
    reading another folder's pass."""
    folder = Path(tempfile.gettempdir()) / f"holo-clear-{os.getpid()}"
    try:
        tree.read_passes_from(pipeline.clear_pass(scene, scene.frame_current, folder))
    except Exception as e:  # noqa: BLE001 -- the OS's errors and the writer's InputError
        log.error("no clear pass could be written for the failed frame: %s", e)


def _show_error(message):
    """On the interface's thread: the error in Blender's reports (status bar, Info log) and a
    popup."""
    try:
        bpy.ops.holo.report(message=message)
    except RuntimeError:  # what Python sees of an error report, once it is reported
        pass

    def draw(menu, _context):
        menu.layout.label(text=message)

    bpy.context.window_manager.popup_menu(draw, title="Holo", icon="ERROR")


@persistent
def file_loaded(*_):
    """A file was loaded: nothing of another file's render is shown, its passes are read
    from its own output folder, and emitters of files from before holdouts are holdouts."""
    session.new_file()
    for scene in bpy.data.scenes:
        if tree.uses_pass(scene):
            tree.point_passes(scene)


@persistent
def file_saved(*_):
    """Saved (*Save As* into another folder included): the passes follow the .blend's output
    folder (Blender remaps the images' relative paths to keep the old folder's files)."""
    for scene in bpy.data.scenes:
        if tree.uses_pass(scene):
            tree.point_passes(scene)


def _handlers():
    h = bpy.app.handlers
    return (
        (h.frame_change_post, render_frame),
        (h.load_post, file_loaded),
        (h.save_post, file_saved),
        (h.render_init, render_init),
        (h.render_post, render_post),
        (h.render_complete, render_ended),
        (h.render_cancel, render_ended),
    )


def register():
    if bpy.app.background:  # a farm's log: what each frame's pass was (INFO and up)
        _log_to_stderr()
    for handlers, fn in _handlers():
        handlers.append(fn)
    if not bpy.app.background:
        bpy.app.timers.register(_show_progress, persistent=True)


def unregister():
    for handlers, fn in _handlers():
        if fn in handlers:
            handlers.remove(fn)
    if bpy.app.timers.is_registered(_show_progress):
        bpy.app.timers.unregister(_show_progress)
    if STDERR in logging.getLogger(ADDON_LOG).handlers:
        logging.getLogger(ADDON_LOG).removeHandler(STDERR)


ADDON_LOG = __package__.rsplit(".", 1)[0]  # the add-on's loggers: holo_addon or bl_ext.….holo
STDERR = logging.StreamHandler(sys.stderr)
STDERR.setFormatter(logging.Formatter("%(levelname)s %(message)s"))


def _log_to_stderr() -> None:
    """In a background Blender, the add-on's INFO lines reach the log (Python's default shows
    only warnings): per frame, whether its pass was made or reused, its time and its
    warnings."""
    logger = logging.getLogger(ADDON_LOG)
    if logger.level == logging.NOTSET or logger.level > logging.INFO:
        logger.setLevel(logging.INFO)
    if STDERR not in logger.handlers and not logging.getLogger().handlers:
        logger.addHandler(STDERR)  # where a script logs already (basicConfig), it says them
