"""The plate's live view in the viewport: the viewport's camera (in camera view the scene
camera's own conversion; an orbit moves the eye on its sphere around the view's centre, its
field of view Blender's 3D view's, its pupil and focus the scene camera's), the picture's
texture values, and the live view's course headless (bpy in-process has no screen: the
functions the draw handler and the timer call are what is tested, with the viewport's
region data as plain values)."""

import dataclasses
import math
import time
from types import SimpleNamespace

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _plate_camera_cube  # noqa: E402

F32 = 2e-6  # [m] positions of a few metres through Blender's single-precision matrices


def _view(location, rotation, distance):
    """A RegionView3D's data as Blender keeps it: ``view_matrix`` = T(0, 0, −distance) ·
    R(rotation)⁻¹ · T(−location) (``view_rotation`` is the view's rotation, its eye at
    location + R · (0, 0, distance))."""
    from mathutils import Matrix, Quaternion, Vector

    q = Quaternion(rotation)
    m = (
        Matrix.Translation((0, 0, -distance))
        @ q.to_matrix().to_4x4().inverted()
        @ Matrix.Translation(-Vector(location))
    )
    eye = Vector(location) + q @ Vector((0, 0, distance))
    return SimpleNamespace(view_matrix=m, view_perspective="PERSP", is_perspective=True), np.array(
        eye
    )


def test_in_camera_view_the_viewports_camera_is_the_scene_cameras(empty_scene):
    """Camera view: the scene camera's conversion (pose, lens, sensor, shift, f-stop and
    focus, at 1 Blender unit = 1 cm), at the live resolution (the render's aspect)."""
    from holo_addon.export.scene import camera_from_object, scale
    from holo_addon.export.viewport import viewport_camera

    scene = empty_scene
    scene.unit_settings.scale_length = 0.01
    _, cam, _ = _plate_camera_cube(scene)
    cam.data.lens, cam.data.shift_x = 40.0, 0.05
    cam.data.dof.use_dof, cam.data.dof.aperture_fstop = True, 2.8
    cam.data.dof.focus_distance = 3.0
    scene.render.resolution_x, scene.render.resolution_y = 1920, 1080
    rv3d = SimpleNamespace(view_perspective="CAMERA", is_perspective=True)
    ours = viewport_camera(scene, SimpleNamespace(lens=50.0), rv3d, (800, 600), 640)
    theirs = camera_from_object(scene, cam, scale(scene), crop=False)  # float32 0.01
    assert ours.resolution == (640, 360)
    np.testing.assert_array_equal(ours.matrix_world, theirs.matrix_world)
    for name in (
        "lens",
        "sensor_width",
        "sensor_height",
        "sensor_fit",
        "shift_x",
        "shift_y",
        "fstop",
        "focus_distance",
    ):
        assert getattr(ours, name) == getattr(theirs, name), name
    assert ours.focus_distance == pytest.approx(0.03)


def test_an_orbit_moves_the_eye_around_the_views_centre(empty_scene):
    """Orbiting 40° about the world's Z: the eye moves to the centre + Rz(40°)·(eye − centre),
    3 m from it, looking at it (within 2e-6: Blender's view matrix is single precision); the field of view is 2·atan(36 mm / lens)
    across a landscape region (Blender's 3D view: a 72 mm sensor); the pupil and the focus
    are the scene camera's (a focus object at the centre: the eye's distance to it)."""
    from mathutils import Euler, Quaternion

    from holo_addon.export.viewport import viewport_camera

    scene = empty_scene
    _, cam, _ = _plate_camera_cube(scene)
    focus = bpy.data.objects.new("focus", None)
    scene.collection.objects.link(focus)
    focus.location = (0.2, 0.1, 0.3)
    cam.data.dof.use_dof, cam.data.dof.aperture_fstop = True, 4.0
    cam.data.dof.focus_object = focus
    cam.data.lens = 50.0
    bpy.context.view_layer.update()
    centre, distance = (0.2, 0.1, 0.3), 3.0
    start = Euler((math.radians(70), 0, math.radians(20))).to_quaternion()
    space = SimpleNamespace(lens=35.0)
    rv3d, eye = _view(centre, start, distance)
    before = viewport_camera(scene, space, rv3d, (960, 540), 640)
    np.testing.assert_allclose(before.position, eye, atol=F32)
    turn = Quaternion((0, 0, 1), math.radians(40))
    rv3d, _ = _view(centre, turn @ start, distance)
    after = viewport_camera(scene, space, rv3d, (960, 540), 640)
    rz = np.array(turn.to_matrix())
    want = np.asarray(centre) + rz @ (eye - np.asarray(centre))
    np.testing.assert_allclose(after.position, want, atol=F32)
    assert np.linalg.norm(after.position - centre) == pytest.approx(distance, abs=F32)
    aim = -after.rotation[:, 2]
    np.testing.assert_allclose(aim, (centre - after.position) / distance, atol=F32)
    assert after.resolution == (640, 360)
    assert after.field_of_view()[0] == pytest.approx(2 * math.atan(36 / 35), rel=1e-9)
    assert after.aperture_diameter == pytest.approx(50e-3 / 4.0, rel=1e-12)
    assert after.focus_distance == pytest.approx(distance, abs=F32)
    ortho = SimpleNamespace(
        view_matrix=rv3d.view_matrix, view_perspective="ORTHO", is_perspective=False
    )
    from holo_addon.export.scene import ExportError

    with pytest.raises(ExportError, match="orthographic"):
        viewport_camera(scene, space, ortho, (960, 540), 640)


def test_the_texture_holds_the_picture_bottom_row_first_at_the_scenes_exposure():
    """Rows from the bottom, RGB × 2^exposure, alpha as it is; the sRGB curve where the
    drawing takes display values (0.5 → 0.7354, 1.055·0.5^(1/2.4) − 0.055)."""
    from holo_addon.ui.live import texture_pixels

    rgba = np.zeros((2, 3, 4), np.float32)
    rgba[0, :, :3], rgba[1, :, :3], rgba[..., 3] = 0.25, 0.125, (0.5, 1.0, 0.0)
    out = texture_pixels(rgba, 1.0).reshape(2, 3, 4)
    np.testing.assert_array_equal(out[1, :, :3], 0.5)
    np.testing.assert_array_equal(out[0, :, :3], 0.25)
    np.testing.assert_array_equal(out[..., 3], rgba[::-1, :, 3])
    shown = texture_pixels(rgba, 1.0, linear=False).reshape(2, 3, 4)
    assert shown[1, 0, 0] == pytest.approx(1.055 * 0.5 ** (1 / 2.4) - 0.055, abs=1e-6)


def test_the_live_view_registers_and_unregisters_without_a_screen(empty_scene):
    """Headless Blender attaches no drawing; turned on without a plate it says why and
    starts no worker; unregistered, its state and timers are gone (registered again)."""
    from holo_addon.compositor.session import session
    from holo_addon.ui import live

    scene = empty_scene
    scene.holo.mode = "PLATE"
    scene.holo.live_plate = True
    p = live.state()
    assert p.views is None and "plate" in p.why, p.why
    assert "plate" in live.words(scene)
    scene.holo.live_plate = False
    assert live.state().views is None and live.state().source is None
    live.unregister()
    assert session.live is None and not live._handle
    assert not bpy.app.timers.is_registered(live._tick)
    live.register()


def _wait(until, timeout=120.0, clock=None):
    """Poll the live view until ``until(state)``; ``clock`` [s] () -> the time poll sees
    (a frozen clock keeps the full view from being asked, so a loaded machine's slow
    coarse view is not superseded before it is seen)."""
    from holo_addon.ui import live

    end = time.monotonic() + timeout
    while time.monotonic() < end:
        live.poll(None if clock is None else clock())
        if until(live.state()):
            return live.state()
        time.sleep(0.01)
    raise AssertionError(f"the live view did not answer in {timeout} s: {live.state()}")


def test_a_recorded_plate_is_seen_live_coarse_then_full_and_outside_its_zone_in_words(empty_scene):
    """The scene's recorded plate: the first look's full picture holds the cube (its coarse
    one superseded while the worker starts); a move asks a coarse picture, which arrives,
    and after STILL s of stillness the full one is asked and arrives; an eye 1 m aside
    gets the zone's sentence and no picture. The worker is its own (none in Blender's
    process), ended when the view is turned off."""
    from holo_addon.export.viewport import viewport_camera
    from holo_addon.ui import live

    scene = empty_scene
    _, cam, plate = _plate_camera_cube(scene)
    plate.holo.zone_margin = 0.05  # room to look around: the view moves 1 cm
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.holo.mode, scene.holo.iterations = "PLATE", 1
    assert bpy.ops.holo.record_hologram() == {"FINISHED"}
    scene.holo.live_pixels = 32
    scene.holo.live_plate = True
    p = live.state()
    assert p.views is not None, p.why
    try:
        camera = viewport_camera(
            scene,
            SimpleNamespace(lens=50.0),
            SimpleNamespace(view_perspective="CAMERA"),
            (64, 48),
            32,
        )
        first = live.look(1, camera)
        assert first and live.look(1, camera) == 0  # no move, no request
        p = _wait(lambda s: s.full and s.shown is not None and s.shown.request >= s.full)
        assert not p.shown.coarse and p.shown.where == "" and p.shown.error == "", p.shown
        assert p.shown.rgba.shape == (24, 32, 4) and p.shown.rgba[..., 3].max() == 1.0
        assert p.latency >= live.STILL  # the worker started: a coarse view was superseded
        moved = dataclasses.replace(camera, matrix_world=camera.matrix_world @ _shift(0.01))
        still = time.perf_counter()
        coarse = live.look(1, moved, now=still)
        p = _wait(lambda s: s.shown.request >= coarse, clock=lambda: still)
        assert p.shown.request == coarse and p.shown.coarse, p.shown
        assert p.shown.rgba[..., 3].max() == 1.0 and p.coarse is not None
        p = _wait(lambda s: s.full and s.shown.request >= s.full)
        assert not p.shown.coarse and p.latency >= live.STILL
        aside = SimpleNamespace(
            view_matrix=np.linalg.inv(np.array(cam.matrix_world) @ _shift(1.0)),
            view_perspective="PERSP",
            is_perspective=True,
        )
        live.look(1, viewport_camera(scene, SimpleNamespace(lens=50.0), aside, (64, 48), 32))
        p = _wait(lambda s: s.shown.where)
        assert p.shown.rgba is None and "zone" in p.shown.where, p.shown
        worker = p.views.process
    finally:
        scene.holo.live_plate = False
    assert live.state().views is None and worker.wait(timeout=10) is not None


def _shift(x):
    m = np.eye(4)
    m[0, 3] = x
    return m
