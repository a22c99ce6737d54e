"""The interface paths a headless Blender never takes: the operators' modal run (events pass
through, progress and messages as they arrive, Esc, Enter) driven event by event, and the
panels' draw code against the real properties and operators.

``bpy`` in background mode has no window, so the window manager, workspace and events are
stand-ins that record what the operator asks of them; the worker, the scene and the files are
real."""

import time
from types import SimpleNamespace

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _plate_camera_cube  # noqa: E402


class _WindowManager:
    def __init__(self):
        self.timers, self.progress, self.handler = [], [], None

    def event_timer_add(self, step, window=None):
        self.timers.append(object())
        return self.timers[-1]

    def event_timer_remove(self, timer):
        self.timers.remove(timer)

    def progress_begin(self, low, high):
        pass

    def progress_update(self, value):
        self.progress.append(value)

    def progress_end(self):
        pass

    def modal_handler_add(self, op):
        self.handler = op


class _Workspace:
    def __init__(self):
        self.status = []

    def status_text_set(self, text):
        self.status.append(text)


def _event(kind, value="PRESS", timer=None):
    return SimpleNamespace(type=kind, value=value, timer=timer)


@pytest.fixture
def interface(monkeypatch):
    """(operator, context) as Blender's interface would drive them: not in background."""
    from holo_addon.ui import operators

    monkeypatch.setattr(operators, "bpy", SimpleNamespace(app=SimpleNamespace(background=False)))

    class RenderPass(operators._PipelineOperator):
        bl_label = operators.HOLO_OT_render_pass.bl_label

        def __init__(self):
            self.reports = []

        def report(self, kind, text):
            self.reports.append((next(iter(kind)), text, time.monotonic()))

    context = SimpleNamespace(
        scene=bpy.context.scene,
        window=None,
        window_manager=_WindowManager(),
        workspace=_Workspace(),
        evaluated_depsgraph_get=bpy.context.evaluated_depsgraph_get,
    )
    return RenderPass(), context


def _camera_scene(scene, samples):
    _plate_camera_cube(scene)
    scene.holo.mode = "CAMERA"
    scene.holo.speckle = "LOOKS"  # progressive looks, which a running pass can keep
    scene.holo.samples = samples
    scene.render.resolution_x, scene.render.resolution_y = 64, 48


def _tick(op, context, until, limit=300.0):
    """Timer events every 0.1 s, as Blender sends them, until ``until()`` or the operator
    ends; the operator's last answer."""
    end = time.monotonic() + limit
    while time.monotonic() < end:
        answer = op.modal(context, _event("TIMER", "NOTHING", context.window_manager.timers[0]))
        if answer != {"PASS_THROUGH"} or until():
            return answer
        time.sleep(0.1)
    raise AssertionError("the worker gave no sign in time")


def test_the_interface_stays_usable_and_esc_cancels_within_a_second(empty_scene, interface):
    """While the worker runs, every other event passes through to Blender; Esc kills the
    worker within a second, ends the operator's timer, progress and status text, and the
    earlier pass is kept."""
    from holo_addon.render import pipeline

    op, context = interface
    _camera_scene(empty_scene, samples=256)
    earlier = pipeline.pass_file(pipeline.output_dir(empty_scene), empty_scene.frame_current)
    earlier.parent.mkdir(parents=True)
    earlier.write_bytes(b"the earlier pass")
    assert op.invoke(context, _event("LEFTMOUSE")) == {"RUNNING_MODAL"}
    assert context.window_manager.handler is op and "Esc to cancel" in context.workspace.status[-1]
    for kind in ("MOUSEMOVE", "LEFTMOUSE", "A", "WHEELUPMOUSE"):
        assert op.modal(context, _event(kind)) == {"PASS_THROUGH"}
    other_timer = _event("TIMER", "NOTHING", object())  # another operator's timer
    assert op.modal(context, other_timer) == {"PASS_THROUGH"}
    _tick(op, context, lambda: op._worker.partial > 0)  # mid-run: samples are being made
    process = op._worker.process
    assert process.poll() is None, "the worker ended before Esc"
    start = time.monotonic()
    assert op.modal(context, _event("ESC")) == {"CANCELLED"}
    while process.poll() is None and time.monotonic() - start < 5:
        time.sleep(0.01)
    took = time.monotonic() - start
    print(f"Esc to the worker's end: {took * 1000:.0f} ms")
    assert process.poll() is not None and took < 1.0
    assert context.window_manager.timers == [] and context.workspace.status[-1] is None
    assert any("cancelled; earlier results kept" in text for _, text, _ in op.reports)
    assert earlier.read_bytes() == b"the earlier pass"


def test_progress_and_messages_arrive_while_the_worker_runs(empty_scene, interface):
    """Progress reaches the progress bar and the status text as it is made, the worker's
    messages become reports before the run ends, and the run ends with the pass written."""
    from holo_addon.render import pipeline

    op, context = interface
    _camera_scene(empty_scene, samples=8)
    assert op.invoke(context, _event("LEFTMOUSE")) == {"RUNNING_MODAL"}
    answer = _tick(op, context, lambda: False)
    ended = time.monotonic()
    assert answer == {"FINISHED"}
    progress = context.window_manager.progress
    assert len(set(progress)) >= 3 and progress == sorted(progress), progress
    assert any(text and text.endswith("% (Esc to cancel)") for text in context.workspace.status)
    early = [text for kind, text, at in op.reports if at < ended - 0.05]
    assert early, "no message arrived before the end"
    frame = pipeline.pass_file(pipeline.output_dir(empty_scene), empty_scene.frame_current)
    assert frame.is_file() and "holographic pass" in op.reports[-1][1]


def test_enter_keeps_the_samples_made_so_far(empty_scene, interface):
    """Enter during a camera hologram's samples ends the run with the samples so far as the
    frame's pass."""
    from holo_addon.render import pipeline
    from holo_core.io.image import exr_attribute

    op, context = interface
    _camera_scene(empty_scene, samples=256)
    assert op.invoke(context, _event("LEFTMOUSE")) == {"RUNNING_MODAL"}
    _tick(op, context, lambda: op._worker.partial >= 2)
    assert op.modal(context, _event("RET")) == {"FINISHED"}
    frame = pipeline.pass_file(pipeline.output_dir(empty_scene), empty_scene.frame_current)
    assert frame.is_file() and exr_attribute(frame, "holo")
    assert any("stopped at" in text for _, text, _ in op.reports)
    assert context.window_manager.timers == []


class _Layout:
    """Records what a panel draws, checking each property and operator it names exists."""

    def __init__(self, drawn):
        self.drawn = drawn

    def prop(self, data, name, **_):
        assert name in data.bl_rna.properties, f"no property {name}"
        self.drawn.append(("prop", name))

    def operator(self, idname, **_):
        group, name = idname.split(".")
        assert getattr(getattr(bpy.ops, group), name).idname(), idname
        self.drawn.append(("operator", idname))

    def label(self, text="", **_):
        self.drawn.append(("label", text))

    def column(self, **_):
        return self

    box = row = column


def _draw(panel, context):
    drawn = []
    panel.draw(SimpleNamespace(layout=_Layout(drawn)), context)
    return drawn


def test_the_panels_draw_every_state(empty_scene):
    """Render ▸ Holo in both modes and while a render makes its pass (progress and Cancel
    Pass), Object ▸ Holo for an emitter and a plate: every property and operator they show
    exists."""
    from holo_addon.compositor.session import session
    from holo_addon.ui import panels as ui

    cube, _, plate = _plate_camera_cube(empty_scene)
    context = SimpleNamespace(scene=empty_scene, object=cube)
    for mode in ("CAMERA", "PLATE"):
        empty_scene.holo.mode = mode
        drawn = _draw(ui.HOLO_PT_scene, context)
        assert ("prop", "speckle" if mode == "CAMERA" else "iterations") in drawn
    session.pass_started(7)
    session.running.fraction = 0.42
    try:
        drawn = _draw(ui.HOLO_PT_scene, context)
    finally:
        session.pass_ended()
    assert ("label", "Pass of frame 7: 42%") in drawn and ("operator", "holo.cancel_pass") in drawn
    assert ("prop", "emitter") in _draw(ui.HOLO_PT_object, context)
    context.object = plate
    assert ("label", "Hologram: not recorded yet") in _draw(ui.HOLO_PT_object, context)


def test_controls_show_only_where_they_apply(empty_scene):
    """Camera mode: no plate control (Max Hologram Size, Wavelength, Iterations, Composition,
    Opacity Threshold, Plate Coverage, Record Hologram, the object's Hologram Plate); Plate
    mode: no Samples; both: Lighting. Remove Holo Compositing only once it is set up."""
    from holo_addon.ui import panels as ui

    cube, _, plate = _plate_camera_cube(empty_scene)
    context = SimpleNamespace(scene=empty_scene, object=cube)
    plate_only = {
        ("prop", n)
        for n in (
            "plate_memory",
            "plate_disk",
            "wavelength",
            "iterations",
            "composition",
            "opacity_threshold",
            "show_coverage",
        )
    }
    plate_only |= {("operator", "holo.record_hologram")}
    for mode, hidden in (("CAMERA", plate_only), ("PLATE", {("prop", "samples")})):
        empty_scene.holo.mode = mode
        drawn = set(_draw(ui.HOLO_PT_scene, context))
        assert ("prop", "lighting") in drawn and not drawn & hidden, (mode, drawn & hidden)
        assert ("operator", "holo.remove_compositing") not in drawn
        assert (("prop", "is_plate") in _draw(ui.HOLO_PT_object, context)) == (mode == "PLATE")
    empty_scene.holo.mode = "CAMERA"
    context.object = plate
    assert _draw(ui.HOLO_PT_object, context) == [("label", "Hologram plate (used in Plate mode)")]


def test_a_renders_pass_shows_its_progress_in_the_status_bar(monkeypatch):
    """The interface timer puts the pass's progress in every window's status bar, redraws
    the Properties editors (the panel's progress and Cancel Pass), and clears both after."""
    from contextlib import nullcontext

    from holo_addon.compositor import handlers
    from holo_addon.compositor.session import Running, session

    redrawn = []
    area = SimpleNamespace(type="PROPERTIES", tag_redraw=lambda: redrawn.append(1))
    window = SimpleNamespace(
        workspace=_Workspace(),
        screen=SimpleNamespace(areas=[area, SimpleNamespace(type="VIEW_3D")]),
    )
    context = SimpleNamespace(
        window_manager=SimpleNamespace(windows=[window]), temp_override=lambda **_: nullcontext()
    )
    monkeypatch.setattr(handlers, "bpy", SimpleNamespace(context=context))
    monkeypatch.setattr(session, "shown", None)
    for frame, fraction in ((12, 0.0), (12, 0.25), (12, 0.25), (None, 0.25)):
        session.running = Running(frame=frame, fraction=fraction)
        assert handlers._show_progress() == 0.25  # the timer runs again in 0.25 s
    status = window.workspace.status
    assert status[:2] == [
        f"Holo: holographic pass of frame 12: {p} (Render Properties ▸ Holo ▸ Cancel Pass)"
        for p in ("0%", "25%")
    ]
    assert status[2:] == [None] and len(redrawn) == 3  # unchanged text: not set again


def test_a_pass_of_one_look_reports_no_nan_contrast():
    """A plate view of one look has no spread to measure: said in words, not "nan"; the
    looks' limit has no speckle; several looks give their contrast."""
    from holo_addon.ui.operators import speckle
    from holo_core.job import Report
    from holo_core.view import RenderResult

    one = speckle(
        Report.of(
            RenderResult(
                rgb=0, alpha=0, depth=0, info={"samples": 1, "speckle_contrast": float("nan")}
            )
        )
    )
    assert "nan" not in one and "not measured" in one, one
    assert "no speckle" in speckle(Report(looks=1, speckle_contrast=0.0))
    assert (
        speckle(Report(looks=4, speckle_contrast=0.1234)) == " (4 samples, speckle contrast 0.123)"
    )


def test_the_plate_coverage_overlay_follows_the_lines_of_sight(empty_scene):
    """Camera at y = -3, a 0.6 plate at y = -1.5 facing it, a 0.5 cube: the overlay's lines
    of sight pass through the plate's corners and end at the cube's far side (y = 0.25); the
    cube in the middle is covered (green), half out is partly (orange), far out not (red)."""
    from holo_addon.ui import overlay

    scene = empty_scene
    scene.holo.mode = "PLATE"
    cube, cam, plate = _plate_camera_cube(scene)
    found = overlay.coverage(scene, bpy.context.evaluated_depsgraph_get())
    assert found.state == "ALL"
    outline, sight, end = found.lines[:8], found.lines[8:16], found.lines[16:]
    corners = np.array(
        [(x, -1.5, z) for x, z in ((-0.3, -0.3), (0.3, -0.3), (0.3, 0.3), (-0.3, 0.3))]
    )
    np.testing.assert_allclose(np.sort(outline[::2], 0), np.sort(corners, 0), atol=1e-6)
    eye, far = sight[::2], sight[1::2]
    np.testing.assert_allclose(eye, [(0, -3, 0)] * 4, atol=1e-6)
    np.testing.assert_allclose(far[:, 1], 0.25, atol=1e-6)  # the cube's far side
    np.testing.assert_allclose(np.abs(far[:, [0, 2]]), 0.3 * 3.25 / 1.5, atol=1e-6)
    np.testing.assert_allclose(np.sort(end[::2], 0), np.sort(far, 0), atol=1e-6)
    for x, state in ((0.5, "PART"), (3.0, "NONE")):
        cube.location.x = x
        bpy.context.view_layer.update()
        assert overlay.coverage(scene, bpy.context.evaluated_depsgraph_get()).state == state
    scene.holo.mode = "CAMERA"
    assert overlay.coverage(scene, bpy.context.evaluated_depsgraph_get()) is None


def test_a_renders_warnings_reach_the_panel(empty_scene, tmp_path):
    """A render whose plate cuts the object: the warning is in Render ▸ Holo after the frame
    (a render's pass has no operator to report through)."""
    from test_compositor import _scene_with_pass

    from holo_addon.compositor.session import session
    from holo_addon.ui import panels as ui

    scene = empty_scene
    _scene_with_pass(scene, tmp_path)
    plate = next(o for o in scene.objects if o.holo.is_plate)
    plate.scale = (0.3, 0.3, 1)
    scene.render.filepath = str(tmp_path / "cut.exr")
    bpy.ops.render.render(write_still=True)
    assert session.warnings["frame"] == 1
    drawn = _draw(ui.HOLO_PT_scene, SimpleNamespace(scene=scene))
    (warning,) = [text for kind, text in drawn if kind == "label" and "cut from the pass" in text]
    assert "covers" in warning
    bpy.ops.wm.read_factory_settings(use_empty=True)  # another file: its own warnings only
    assert not any(
        "cut from the pass" in text
        for _, text in _draw(ui.HOLO_PT_scene, SimpleNamespace(scene=bpy.context.scene))
    )


def test_a_failed_render_pass_reaches_blenders_reports(addon, monkeypatch):
    """In the interface a failed render pass is put in Blender's reports (status bar, Info
    log) by the holo.report operator, and shown in a popup."""
    from holo_addon.compositor import handlers

    with pytest.raises(RuntimeError, match="Error: Holo: the pass of frame 3 failed"):
        bpy.ops.holo.report(message="Holo: the pass of frame 3 failed")
    shown = []
    monkeypatch.setattr(
        bpy.types.WindowManager,
        "popup_menu",
        lambda self, draw, title, icon: shown.append((title, icon)),
        raising=False,
    )
    handlers._show_error("Holo: the pass of frame 3 failed")
    assert shown == [("Holo", "ERROR")]
