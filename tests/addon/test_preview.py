"""The holographic result in the viewport: the drawing's alignment on the camera's frame,
the preview pass made by the worker (never OpenCL in Blender's process, never waited for)
and the picture the texture is made from, through the scene's view transform (bpy
in-process: headless Blender draws nothing, so the drawing's inputs are what is tested)."""

import time

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _plate_camera_cube, _read_exr  # noqa: E402


def _perspective(scene, cam, size):
    """The 4x4 matrix of a view through ``cam`` that fills a region of ``size`` exactly, as
    Blender computes a camera's projection (what region_3d.perspective_matrix is in camera
    view with the frame filling the region)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    projection = cam.calc_matrix_camera(depsgraph, x=size[0], y=size[1])
    return np.array(projection) @ np.array(cam.matrix_world.inverted())


@pytest.mark.parametrize(
    "fit, shift, size", [("AUTO", (0.0, 0.0), (64, 48)), ("VERTICAL", (0.1, -0.05), (40, 60))]
)
def test_the_pass_is_drawn_exactly_on_the_cameras_frame(empty_scene, fit, shift, size):
    """Through a view whose projection is the camera's own, the frame lands on the region's
    edges (within 1e-3 px); a region zoomed 2x about a point moves it there; a render
    cropped to a region draws its pass on that region's pixels."""
    from holo_addon.ui.preview import camera_frame, frame_rect

    scene = empty_scene
    _, cam, _ = _plate_camera_cube(scene)
    cam.data.sensor_fit, (cam.data.shift_x, cam.data.shift_y) = fit, shift
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    bpy.context.view_layer.update()
    w, h = size
    view = _perspective(scene, cam, size)
    rect = frame_rect(view, size, camera_frame(scene, cam))
    np.testing.assert_allclose(rect, (0, 0, w, h), atol=1e-3)
    zoom = np.diag([2.0, 2.0, 1.0, 1.0])
    zoom[:2, 3] = (-0.5, 0.25)  # NDC: x → 2x − 0.5, y → 2y + 0.25 (w = 1 after the divide)
    rect = frame_rect(zoom @ view, size, camera_frame(scene, cam))
    np.testing.assert_allclose(
        rect,
        (
            (-2 - 0.5 + 1) / 2 * w,
            (-2 + 0.25 + 1) / 2 * h,
            (2 - 0.5 + 1) / 2 * w,
            (2 + 0.25 + 1) / 2 * h,
        ),
        atol=1e-3,
    )
    r = scene.render
    r.use_border = r.use_crop_to_border = True
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = 0.25, 0.75, 0.5, 1.0
    rect = frame_rect(view, size, camera_frame(scene, cam))
    np.testing.assert_allclose(rect, (0.25 * w, 0.5 * h, 0.75 * w, h), atol=1e-3)


def test_a_preview_pass_is_made_by_the_worker_and_becomes_the_picture(empty_scene, monkeypatch):
    """With OpenCL made unusable in Blender's process: *start* returns at once with the
    worker running, the pass at a quarter of the render's resolution arrives in the output
    folder's preview/, and the picture the texture is made from is its PNG: the pass's alpha
    (within 1/255, bottom row first as textures are) and its colours through the scene's view
    transform (AgX: the object's pixels differ from plain sRGB by more than 0.05, as the
    AgX curve does; Standard: plain sRGB within 1/255; the pass up to date, shown again at
    once). A change that leaves the pass as it is starts nothing; moving the object starts
    a new preview."""
    from holo_addon.render import pipeline
    from holo_addon.ui import preview
    from holo_core.io.image import srgb
    from holo_core.opencl import runtime

    def refuse(*_, **__):
        raise AssertionError("Blender's process must not touch OpenCL")

    monkeypatch.setattr(runtime, "choose_device", refuse)
    monkeypatch.setattr(runtime, "get_runtime", refuse)
    scene = empty_scene
    cube, _, _ = _plate_camera_cube(scene)
    scene.holo.lighting = "ALBEDO"
    scene.render.resolution_x, scene.render.resolution_y = 256, 192
    scene.render.resolution_percentage = 100
    pictures = {}
    for transform in ("AgX", "Standard"):
        scene.view_settings.view_transform = transform
        preview.state().key = ""  # the same pass, shown again through this transform
        begun = time.perf_counter()
        assert preview.start(scene, bpy.context.evaluated_depsgraph_get())
        running = preview.state().worker
        if transform == "AgX":
            assert running is not None and not running.finished, "start waits for nothing"
        else:  # the same pass, up to date: shown at once through the new transform
            assert running is None
        while preview.poll(scene):
            time.sleep(0.05)
        shown = preview.state()
        print(
            f"{transform}: preview {shown.picture.shape[1]}x{shown.picture.shape[0]} "
            f"in {time.perf_counter() - begun:.2f} s"
        )
        pictures[transform] = shown.picture.copy()
        path = pipeline.pass_file(pipeline.output_dir(scene) / "preview", 1)
        assert shown.source == str(path)
    view = _read_exr(path)
    alpha = view["ViewLayer.Combined.A"][::-1]
    rgb = np.stack([view[f"ViewLayer.Combined.{c}"] for c in "RGB"], -1)[::-1]
    straight = rgb / np.maximum(alpha, 1e-6)[..., None]
    assert pictures["AgX"].shape == (48, 64, 4)
    np.testing.assert_allclose(pictures["AgX"][..., 3], alpha, atol=1 / 255 + 1e-6)
    solid = alpha > 0.99
    assert solid.sum() > 20
    np.testing.assert_allclose(
        pictures["Standard"][..., :3][solid], srgb(straight)[solid], atol=1 / 255 + 1e-6
    )
    agx = np.abs(pictures["AgX"][..., :3][solid] - srgb(straight)[solid]).max()
    assert agx > 0.05, f"AgX changes the object's pixels by {agx:.3f} at most"
    assert not preview.start(scene, bpy.context.evaluated_depsgraph_get()), "nothing changed"
    cube.location.x += 0.05
    bpy.context.view_layer.update()
    assert preview.start(scene, bpy.context.evaluated_depsgraph_get())
    while preview.poll(scene):
        time.sleep(0.05)
