"""Operators: record_hologram, render_pass, setup_compositing, render.

In the interface the work runs on a worker thread that never touches bpy: it posts progress
to a queue that a modal timer drains (progress bar, header text); Esc sets an event the
worker's progress callback checks. ``execute()`` (``blender --background``, scripts) runs the
same work synchronously. Errors reach the user through ``self.report``.
"""

from __future__ import annotations

import logging
import queue
import threading

import bpy

from holo_core import jobs
from holo_core.hologram_io import HologramFileError

from . import compositing, pipeline
from .scene_export import ExportError

USER_ERRORS = (ExportError, HologramFileError, ValueError, OSError)


class _Collect(logging.Handler):
    """Keeps holo_core's log records of one run, to report them to the user."""

    def __init__(self):
        super().__init__(logging.INFO)
        self.records = []

    def emit(self, record):
        self.records.append(record)


def _report_log(op, records):
    for r in records:
        op.report({"WARNING"} if r.levelno >= logging.WARNING else {"INFO"}, r.getMessage())


def _run_logged(job, progress):
    handler = _Collect()
    core = logging.getLogger("holo_core")
    core.addHandler(handler)
    level = core.level
    core.setLevel(min(level or logging.INFO, logging.INFO))
    try:
        return pipeline.run(job, progress), handler.records
    finally:
        core.removeHandler(handler)
        core.setLevel(level)


class _PipelineOperator:
    """Shared by the operators that run the pipeline; subclasses set ``render`` and may
    override :meth:`finish`."""

    render = True
    _timer = None

    @classmethod
    def poll(cls, context):
        if context.scene is None or context.scene.camera is None:
            cls.poll_message_set("The scene needs a camera")
            return False
        return True

    def _prepare(self, context):
        try:
            return pipeline.prepare(context.scene, context.evaluated_depsgraph_get(),
                                    render=self.render)
        except USER_ERRORS as e:
            self.report({"ERROR"}, str(e))
            return None

    def execute(self, context):
        job = self._prepare(context)
        if job is None:
            return {"CANCELLED"}
        wm = context.window_manager
        wm.progress_begin(0, 1000)
        try:
            outcome, records = _run_logged(job, lambda f: wm.progress_update(int(f * 1000)))
        except USER_ERRORS as e:
            self.report({"ERROR"}, f"{self.bl_label} failed: {e}")
            return {"CANCELLED"}
        finally:
            wm.progress_end()
        _report_log(self, records)
        return self._done(context, job, outcome)

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        job = self._prepare(context)
        if job is None:
            return {"CANCELLED"}
        self._queue, self._cancel = queue.SimpleQueue(), threading.Event()
        self._job = job

        def progress(f):
            if self._cancel.is_set():
                raise jobs.Cancelled()
            self._queue.put(("progress", f))

        def work():
            try:
                self._queue.put(("done", _run_logged(job, progress)))
            except jobs.Cancelled:
                self._queue.put(("cancelled", None))
            except Exception as e:  # reported on the main thread, never lost
                self._queue.put(("error", e))

        self._thread = threading.Thread(target=work, name="holo", daemon=True)
        self._thread.start()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.2, window=context.window)
        wm.progress_begin(0, 1000)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC":
            self._cancel.set()
            context.workspace.status_text_set("Holo: cancelling…")
        if event.type != "TIMER":
            return {"RUNNING_MODAL"}
        wm = context.window_manager
        while not self._queue.empty():
            kind, value = self._queue.get()
            if kind == "progress":
                wm.progress_update(int(value * 1000))
                context.workspace.status_text_set(f"Holo: {self.bl_label} {value:.0%} "
                                                  f"(Esc to cancel)")
                continue
            self._end(context)
            if kind == "cancelled":
                self.report({"WARNING"}, f"{self.bl_label} cancelled; earlier results kept")
                return {"CANCELLED"}
            if kind == "error":
                self.report({"ERROR"}, f"{self.bl_label} failed: {value}")
                return {"CANCELLED"}
            outcome, records = value
            _report_log(self, records)
            return self._done(context, self._job, outcome)
        return {"RUNNING_MODAL"}

    def _end(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)

    def _done(self, context, job, outcome):
        pipeline.apply(context.scene, job, outcome)
        what = "recorded" if outcome.recorded else "up to date"
        msg = f"hologram {what}: {outcome.holograms[0]}"
        if outcome.pass_path is not None:
            msg += f"; holographic pass: {outcome.pass_path}"
        self.report({"INFO"}, msg)
        return self.finish(context)

    def finish(self, context):
        return {"FINISHED"}


class HOLO_OT_record_hologram(_PipelineOperator, bpy.types.Operator):
    """Record the plate's hologram from the holographic emitters (again only when the scene or
    the settings changed)"""

    bl_idname = "holo.record_hologram"
    bl_label = "Record Hologram"
    bl_options = {"REGISTER"}
    render = False


class HOLO_OT_render_pass(_PipelineOperator, bpy.types.Operator):
    """Render the holographic pass from the scene camera: a multilayer EXR with Combined and
    Depth (recording the hologram first when it is out of date)"""

    bl_idname = "holo.render_pass"
    bl_label = "Render Holographic Pass"
    bl_options = {"REGISTER"}


class HOLO_OT_setup_compositing(bpy.types.Operator):
    """Depth-combine the holographic pass with Blender's rendered image and depth in the
    compositor"""

    bl_idname = "holo.setup_compositing"
    bl_label = "Set Up Compositing"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        try:
            compositing.setup(context.scene, pipeline.output_dir(context.scene)
                              / pipeline.PASS_NAME)
        except USER_ERRORS as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, "compositor: holographic pass depth-combined with the render")
        return {"FINISHED"}


class HOLO_OT_render(_PipelineOperator, bpy.types.Operator):
    """Record (when needed), render the holographic pass, set up compositing, then render the
    image with Blender and write it to the output path"""

    bl_idname = "holo.render"
    bl_label = "Render with Hologram"
    bl_options = {"REGISTER"}

    def finish(self, context):
        if bpy.ops.holo.setup_compositing() != {"FINISHED"}:
            return {"CANCELLED"}
        scene = context.scene
        scene.holo["skip_pass_once"] = True  # the pass is fresh: the render handler skips it
        try:
            if bpy.app.background:
                bpy.ops.render.render(write_still=True)
            else:
                bpy.ops.render.render("INVOKE_DEFAULT", write_still=True)
        finally:
            if bpy.app.background:
                scene.holo.pop("skip_pass_once", None)
        return {"FINISHED"}


CLASSES = (HOLO_OT_record_hologram, HOLO_OT_render_pass, HOLO_OT_setup_compositing,
           HOLO_OT_render)

register, unregister = bpy.utils.register_classes_factory(CLASSES)
