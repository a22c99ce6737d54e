"""Operators: record_hologram, render_pass, setup_compositing, render.

The work runs in a worker process (:mod:`holo_core.worker`; no OpenCL in Blender's process). In
the interface a modal timer drains its messages (progress bar, status text, warnings as they
arise) while every other event passes through, so Blender stays usable; Esc kills the worker,
Enter stops a camera hologram's samples early and keeps the pass so far. A recorded plate's
pass runs in the worker kept between passes (:func:`_kept`), which holds the plate: the next
click's pass reads no file again.
``execute()`` (``blender --background``, scripts) waits for the same worker. Errors, a crashed
or killed worker included, reach the user through ``self.report``.
"""

from __future__ import annotations

import logging

import bpy

from holo_core.io.hologram import HologramFileError
from holo_core.io.plate_paths import plate_files
from holo_core.job import Report, Result
from holo_core.worker import WorkerError

from ..blender.objects import shown_as_rendered
from ..compositor import tree
from ..compositor.session import session
from ..export import motion
from ..export.scene import ExportError, viewport_matches_render
from ..render import pipeline

USER_ERRORS = (ExportError, HologramFileError, ValueError, OSError, WorkerError)


def _report_log(op, level, text):
    op.report({"WARNING"} if level >= logging.WARNING else {"INFO"}, text)


def _kept(job) -> bool:
    """Whether ``job`` (a Prepared) runs in the worker kept between passes: a view of a plate
    whose holograms are current (the worker holds them for the next click, or a render's
    frames, until a render ends or it is left idle); a recording or a camera hologram runs
    in a worker of its own."""
    return not job.records


class _PipelineOperator:
    """Shared by the operators that run the pipeline; subclasses set ``render`` and may
    override :meth:`finish`."""

    render = True
    _timer = None
    _worker = None

    @classmethod
    def poll(cls, context):
        if context.scene is None or context.scene.camera is None:
            cls.poll_message_set("The scene needs a camera")
            return False
        return True

    def _prepare(self, context):
        scene = context.scene
        try:  # what the render draws, emitters hidden in the viewport only included
            with shown_as_rendered(scene, getattr(context, "view_layer", None)):
                job = pipeline.prepare(
                    scene, context.evaluated_depsgraph_get(), render=self.render, bake=True
                )
                if motion.blurs(scene):  # blurred as the render's raster will be
                    now = motion.sample(scene, context.evaluated_depsgraph_get())
                    job = pipeline.moving(
                        job,
                        [now, *motion.evaluate_shutter(scene, context.evaluated_depsgraph_get)],
                        *motion.shutter(scene),
                    )
        except USER_ERRORS as e:
            self.report({"ERROR"}, str(e))
            return None
        for warning in job.warnings:
            self.report({"WARNING"}, warning)
        if not viewport_matches_render(context.scene):
            self.report(
                {"WARNING"},
                "an emitter's modifiers differ between viewport and render: "
                "this pass uses the viewport's; F12 and animation renders "
                "make theirs at render settings",
            )
        return job

    def execute(self, context):
        job = self._prepare(context)
        if job is None:
            return {"CANCELLED"}
        wm = context.window_manager
        wm.progress_begin(0, 1000)
        try:
            result = pipeline.run(
                job,
                lambda f: wm.progress_update(int(f * 1000)),
                lambda level, text: _report_log(self, level, text),
                resident=_kept(job),
            )
        except USER_ERRORS as e:
            self.report({"ERROR"}, f"{self.bl_label} failed: {e}")
            return {"CANCELLED"}
        finally:
            wm.progress_end()
        return self._done(context, job, result)

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        job = self._prepare(context)
        if job is None:
            return {"CANCELLED"}
        cached = pipeline.cached_pass(job)
        if cached is not None:
            return self._done(context, job, cached)
        try:
            self._worker = pipeline.start(job, resident=_kept(job))
        except OSError as e:
            self.report({"ERROR"}, f"{self.bl_label}: the worker process did not start: {e}")
            return {"CANCELLED"}
        self._job = job
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 1000)
        wm.modal_handler_add(self)
        context.workspace.status_text_set(f"Holo: {self.bl_label} (Esc to cancel)")
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            self.cancel(context)
            self.report({"WARNING"}, f"{self.bl_label} cancelled; earlier results kept")
            return {"CANCELLED"}
        if (
            event.type in {"RET", "NUMPAD_ENTER"}
            and event.value == "PRESS"
            and self._worker.partial
        ):
            return self._keep(context)
        if event.type != "TIMER" or event.timer is not self._timer:
            return {"PASS_THROUGH"}  # the interface stays usable while the worker runs
        wm = context.window_manager
        for kind, value in self._worker.poll():
            if kind == "progress":
                wm.progress_update(int(value * 1000))
                context.workspace.status_text_set(
                    f"Holo: {self.bl_label} {value:.0%} (Esc to cancel)"
                )
            elif kind == "log":
                _report_log(self, *value)
            elif kind == "partial":
                context.workspace.status_text_set(
                    f"Holo: {self.bl_label}: {value} samples so far (Enter keeps them, Esc cancels)"
                )
            elif kind == "failed":
                self._end(context)
                self.report({"ERROR"}, f"{self.bl_label} failed: {value}")
                return {"CANCELLED"}
            else:
                self._end(context)
                return self._done(context, self._job, value)
        return {"PASS_THROUGH"}

    def _keep(self, context):
        """Stop the samples here: the latest running pass becomes the frame's pass."""
        job = self._job
        frame = job.job.output.pass_path
        frame.parent.mkdir(parents=True, exist_ok=True)
        samples = self._worker.stop_and_keep(frame)
        self._end(context)
        if not samples:
            self.report(
                {"WARNING"},
                f"{self.bl_label} stopped before its first sample; earlier results kept",
            )
            return {"CANCELLED"}
        self.report({"INFO"}, f"stopped at {samples} samples; that pass is kept")
        return self._done(context, job, Result(pass_path=frame, report=Report(looks=samples)))

    def cancel(self, context):
        """Esc, or Blender ending the operator (a file loaded, the window closed)."""
        if self._worker is not None:
            self._worker.cancel()
        if self._timer is not None:
            self._end(context)

    def _end(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        self._timer = None
        wm.progress_end()
        context.workspace.status_text_set(None)

    def _done(self, context, job, result):
        pipeline.apply(context.scene, job, result)
        made = tree.pass_made(context.scene, result)
        msg = "camera hologram"
        if result.reused is not None and result.reused == result.pass_path:
            msg = "up to date"
        elif result.reused is not None:
            msg = f"a static shot: {result.reused.name} reused (only the frame changed)"
        elif job.holograms:
            what = "recorded" if result.recorded else "up to date"
            msg = f"hologram {what}: {plate_files(job.holograms[0])}"
        if made is not None:
            msg += f"; holographic pass: {made}{speckle(result.report)}"
        self.report({"INFO"}, msg)
        return self.finish(context)

    def finish(self, context):
        return {"FINISHED"}


def speckle(report) -> str:
    """What a pass's report says of its speckle: the contrast between its looks, where it
    has two or more (one look has no spread to measure; the looks' limit has none)."""
    looks, contrast = report.looks, report.speckle_contrast
    if not looks:
        return ""
    if contrast is None:  # one look has no spread to measure (the view's NaN)
        return " (1 look: its speckle is not measured; two or more looks are)" if looks == 1 else ""
    if looks == 1 and contrast == 0:
        return " (the looks' limit: no speckle)"
    return f" ({looks} samples, speckle contrast {contrast:.3f})"


class HOLO_OT_record_hologram(_PipelineOperator, bpy.types.Operator):
    """Record the plate's hologram of the holographic objects (again only after a change)"""

    bl_idname = "holo.record_hologram"
    bl_label = "Record Hologram"
    bl_options = {"REGISTER"}
    render = False

    @classmethod
    def poll(cls, context):
        if context.scene is not None and context.scene.holo.mode == "CAMERA":
            cls.poll_message_set("Camera holograms are recorded with each render of the pass")
            return False
        return super().poll(context)


class HOLO_OT_render_pass(_PipelineOperator, bpy.types.Operator):
    """Render this frame's holographic pass from the scene camera (image and depth)"""

    bl_idname = "holo.render_pass"
    bl_label = "Render Holographic Pass"
    bl_options = {"REGISTER"}


class HOLO_OT_setup_compositing(bpy.types.Operator):
    """Add the holographic pass to the compositor: it fills the holes Blender's render leaves
    where holographic objects are the nearest surface"""

    bl_idname = "holo.setup_compositing"
    bl_label = "Set Up Compositing"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        try:
            tree.setup(context.scene, pipeline.output_dir(context.scene))
        except USER_ERRORS as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report(
            {"INFO"},
            "compositor: the holographic pass fills the holes Blender's "
            "render leaves for holographic objects",
        )
        return {"FINISHED"}


class HOLO_OT_render(_PipelineOperator, bpy.types.Operator):
    """Render the holographic pass, composite it and render the image to the output path"""

    bl_idname = "holo.render"
    bl_label = "Render with Hologram"
    bl_options = {"REGISTER"}

    def finish(self, context):
        if bpy.ops.holo.setup_compositing() != {"FINISHED"}:
            return {"CANCELLED"}
        scene = context.scene
        if viewport_matches_render(scene):  # the pass is fresh: the render composites it
            session.made_for_render(scene.name, scene.frame_current)
        if bpy.app.background:
            bpy.ops.render.render(write_still=True)
        else:
            bpy.ops.render.render("INVOKE_DEFAULT", write_still=True)
        return {"FINISHED"}


class HOLO_OT_cancel_pass(bpy.types.Operator):
    """Stop the holographic pass the render is making; the frame shows the raster alone"""

    bl_idname = "holo.cancel_pass"
    bl_label = "Cancel Pass"

    @classmethod
    def poll(cls, context):
        return session.running.frame is not None

    def execute(self, context):
        self.report({"INFO"}, f"cancelling the holographic pass of frame {session.cancel_pass()}")
        return {"FINISHED"}


class HOLO_OT_report(bpy.types.Operator):
    """Put an error or a warning in Blender's reports (for what happens outside an operator)"""

    bl_idname = "holo.report"
    bl_label = "Holo Report"
    bl_options = {"INTERNAL"}

    message: bpy.props.StringProperty()
    level: bpy.props.EnumProperty(
        items=[("ERROR", "Error", ""), ("WARNING", "Warning", "")], default="ERROR"
    )

    def execute(self, context):
        self.report({self.level}, self.message)
        return {"FINISHED"}


class HOLO_OT_remove_compositing(bpy.types.Operator):
    """Take the holographic pass out of the compositor and put back the user's own nodes"""

    bl_idname = "holo.remove_compositing"
    bl_label = "Remove Holo Compositing"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        if not tree.remove(context.scene):
            self.report({"INFO"}, "the compositor has no holographic pass")
            return {"CANCELLED"}
        self.report({"INFO"}, "compositor: the holographic pass removed, the user's nodes restored")
        return {"FINISHED"}


CLASSES = (
    HOLO_OT_record_hologram,
    HOLO_OT_render_pass,
    HOLO_OT_setup_compositing,
    HOLO_OT_render,
    HOLO_OT_cancel_pass,
    HOLO_OT_report,
    HOLO_OT_remove_compositing,
)

register, unregister = bpy.utils.register_classes_factory(CLASSES)
