"""A plate made a set of parts along the camera's path in Blender: Fit Zone to Shot over a
dolly longer than the plate's Part Length places the parts (kept on the plate, drawn in the
viewport), Plan Plate states the set, Record Hologram records it once into one folder, and
Render Animation renders every frame from the part that holds its camera, recording nothing
more. The scene: a 0.4 m cube 3 m before the camera, a 30 cm dolly over frames 1-3, parts of
20 cm, 32x24 pixels."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _camera_columns, _plate_camera_cube  # noqa: E402
from test_compositor import _middle  # noqa: E402

DOLLY = ((1, -0.15), (2, 0.0), (3, 0.15))  # (frame, camera x [m])


def _dolly_scene(scene):
    cube, cam, plate = _plate_camera_cube(scene, cube_size=0.4)
    cam.data.dof.use_dof = True
    cam.data.dof.aperture_fstop = 2.8
    cam.data.dof.focus_distance = 3.0
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.render.resolution_percentage = 100
    scene.holo.mode = "PLATE"
    scene.holo.iterations = 1
    plate.holo.zone_margin = 0.01
    plate.holo.part_length = 0.2
    for frame, x in DOLLY:
        cam.location.x = x
        cam.keyframe_insert("location", frame=frame)
    scene.frame_start, scene.frame_end = 1, 3
    scene.frame_set(2)
    bpy.context.view_layer.objects.active = plate
    return cube, cam, plate


def test_a_long_dolly_makes_a_set_that_each_frame_renders_from_its_part(
    empty_scene, tmp_path, worker_frames
):
    """Fit Zone to Shot: two parts (a 30 cm path, parts of 20 cm overlapping by a pupil),
    each facing its stretch 1.5 m from the cube, together holding every frame's pupil; the
    timeline left where it was; the overlay draws both parts. Plan Plate's verdict names the
    set and its lines each part. Record Hologram records the set (its manifest the plate's
    file); then every frame's job records nothing, and Render Animation makes each frame's
    pass from the part that holds its camera (the pass says which: the ends from different
    parts), the cube's silhouette centred where the frame's camera projects it (within
    half a pixel)."""
    from holo_addon.export.plates import nearest_part, plate_parts
    from holo_addon.render import pipeline
    from holo_addon.ui import overlay, plates
    from holo_core.io.plate_set import MANIFEST
    from holo_core.job import SetRoute

    scene = empty_scene
    _, cam, plate = _dolly_scene(scene)
    assert bpy.ops.holo.fit_zone_to_shot() == {"FINISHED"}
    assert scene.frame_current == 2
    parts = plate_parts(plate)
    assert parts is not None and len(parts) == 2, parts
    assert plates.part_count(plate.holo) == 2
    for part in parts:  # each plate 1.5 m from the cube's centre, facing its stretch
        assert np.linalg.norm(part.plate.matrix_world[:3, 3]) == pytest.approx(1.5, abs=0.05)
        assert part.plate.matrix_world[1, 2] < -0.99, part.plate.matrix_world[:3, 2]
    edges = overlay.coverage(scene, bpy.context.evaluated_depsgraph_get()).parts
    assert edges is not None and edges.shape == (16, 3), edges
    assert bpy.ops.holo.plan_plate() == {"FINISHED"}
    lines = plates.plan_lines(plate)
    assert lines[0].startswith("verdict     a set of 2 parts"), lines
    assert lines[1].startswith("set         2 part(s)"), lines
    assert sum(line.startswith("part ") for line in lines) == 2, lines
    chosen = {}
    for frame, _ in DOLLY:
        scene.frame_set(frame)
        job = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get(), render=False)
        assert isinstance(job.job.route, SetRoute) and job.records, job.job.route
        assert not [w for w in job.warnings if "beyond" in w], job.warnings
        k, beyond = nearest_part(parts, job.job.camera)
        assert beyond == 0, (frame, beyond)
        chosen[frame] = k
    assert chosen[1] != chosen[3], chosen
    scene.frame_set(1)
    assert bpy.ops.holo.record_hologram() == {"FINISHED"}
    assert plate.holo.hologram.endswith(MANIFEST), plate.holo.hologram
    for frame, _ in DOLLY:
        scene.frame_set(frame)
        job = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get(), render=False)
        assert not job.records, frame
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 1
    scene.render.filepath = str(tmp_path / "frame_")
    worker_frames.clear()
    bpy.ops.render.render(animation=True)
    assert worker_frames == [1, 2, 3], worker_frames
    corners = np.array([(x, y, z) for x in (-0.2, 0.2) for y in (-0.2, 0.2) for z in (-0.2, 0.2)])
    for frame, _ in DOLLY:
        path = pipeline.pass_file(pipeline.output_dir(scene), frame)
        assert pipeline._header(path).get("part") == chosen[frame], (frame, chosen)
        scene.frame_set(frame)
        cols = _camera_columns(scene, cam, corners)
        got = _middle(path)
        print(
            f"frame {frame}: part {chosen[frame]}, pass middle {got}, projected "
            f"{(min(cols) + max(cols)) / 2:.2f}"
        )
        assert abs(got - (min(cols) + max(cols)) / 2) <= 0.5, frame


def test_a_path_through_the_objects_is_refused_naming_its_frame(empty_scene):
    """A dolly that passes through the cube between frames 2 and 3: Fit Zone to Shot refuses
    it naming frames 2 and 3 (the timeline's numbers), and the plate keeps what it had."""
    scene = empty_scene
    _, cam, plate = _dolly_scene(scene)
    cam.location = (0.0, 0.0, 0.0)
    cam.location.y = 1.0
    cam.keyframe_insert("location", frame=3)
    bpy.context.view_layer.update()
    with pytest.raises(
        RuntimeError,
        match="frame 2: the path from its camera to frame 3's passes through the objects",
    ):
        bpy.ops.holo.fit_zone_to_shot()
    assert plate.holo.parts == ""
