"""Plates as scene assets in Blender: the viewing zone (set around the camera's pupil at the
first recording, drawn in the viewport), a cache key without the camera (moving, aiming or
refocusing it, its f-stop or the render's size never record again inside the zone; outside,
a frame renders whole as a camera hologram, or with Warn a warning names the zone), the
planner in the panel, and File ▸ Import ▸ Hologram."""

from dataclasses import replace

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _plate_camera_cube, _read_exr  # noqa: E402

from holo_core.io.hologram import read_hologram, write_hologram  # noqa: E402
from holo_core.scene.hologram import Hologram  # noqa: E402
from holo_core.scene.plate import ViewingZone  # noqa: E402

RESOLUTION = (240, 180)  # with DEEP, a camera whose cube asks Auto more than the coded pair
DEEP = 2.5  # the cube's scale: 1 m across at 3 m


def _plate_scene(scene):
    cube, cam, plate = _plate_camera_cube(scene, cube_size=0.4)
    cam.data.dof.use_dof = True
    cam.data.dof.aperture_fstop = 2.8
    cam.data.dof.focus_distance = 3.0
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.holo.mode = "PLATE"
    scene.holo.iterations = 1
    plate.holo.zone_margin = 0.2
    return cube, cam, plate


def test_camera_moves_inside_the_zone_never_record_again(empty_scene):
    """Recorded once: the zone is set around the camera's pupil and kept on the plate. Then
    the camera moves 10 cm and turns, refocuses, changes its f-stop, and the render changes
    size: the hologram is current for each. A camera beyond the zone is warned, the zone
    named, and a changed margin sets a new zone (a new recording)."""
    from holo_addon.export.scene import ExportError
    from holo_addon.render import pipeline

    scene = empty_scene
    _, cam, plate = _plate_scene(scene)
    assert bpy.ops.holo.record_hologram() == {"FINISHED"}
    assert plate.holo.zone_set
    zone = ViewingZone(
        centre=tuple(plate.holo.zone_centre), half_extents=tuple(plate.holo.zone_half)
    )
    assert zone.half_extents[0] == pytest.approx(0.05 / 2.8 / 2 + 0.2, rel=1e-6)
    assert read_hologram(plate.holo.hologram).zone is not None

    def job():
        return pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get(), render=False)

    first = job()
    # Iterations 1 by hand is said to lose against Auto (test_auto_iterations_...); nothing else
    assert not first.records and not [w for w in first.warnings if "set by hand" not in w], (
        first.warnings
    )
    cam.location.x += 0.1
    cam.rotation_euler.z += 0.02
    cam.data.dof.focus_distance = 2.5
    cam.data.dof.aperture_fstop = 4.0
    scene.render.resolution_x = 48
    bpy.context.view_layer.update()
    moved = job()
    assert not moved.records and moved.fingerprint == first.fingerprint
    cam.location.x += 0.5
    bpy.context.view_layer.update()
    outside = job()
    said = [w for w in outside.warnings if "viewing zone" in w]
    assert said and "beyond the viewing zone of plate 'Plane' (the box centred at" in said[0], (
        outside.warnings
    )
    assert "Fit Zone to Shot" in said[0]
    scene.holo.outside_zone = "FAIL"  # a farm's frame the plate was not made for: it fails
    with pytest.raises(
        ExportError,
        match=r"beyond the viewing zone of plate 'Plane' .*\(Outside "
        r"Zone: Fail\)",
    ):
        job()
    scene.holo.outside_zone = "WARN"
    plate.holo.zone_margin = 0.3
    assert not plate.holo.zone_set
    assert job().fingerprint != first.fingerprint


def test_render_passes_of_a_recorded_plate_share_the_worker_that_holds_it(empty_scene):
    """Recorded once, then Render Holographic Pass twice, the camera moved 5 cm between (a
    new pass, the same plate): both passes are made by the one worker kept between them (the
    plate it read held for the second); the pass differs, so it was made again; a render's
    end ends that worker."""
    from holo_addon.render import pipeline
    from holo_core import worker

    scene = empty_scene
    _, cam, _ = _plate_scene(scene)
    assert bpy.ops.holo.record_hologram() == {"FINISHED"}
    assert worker._resident is None  # a recording runs in a worker of its own
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    kept = worker._resident
    assert kept is not None and kept.popen.poll() is None
    out = pipeline.pass_file(pipeline.output_dir(scene), scene.frame_current)
    first = _read_exr(out)["ViewLayer.Combined.A"]
    cam.location.x += 0.05
    bpy.context.view_layer.update()
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert worker._resident is kept and kept.popen.poll() is None, "a pass started a worker"
    second = _read_exr(out)["ViewLayer.Combined.A"]
    assert second.max() == 1.0 and not np.array_equal(first, second)
    pipeline.release()
    assert worker._resident is None and kept.popen.poll() is not None


def test_a_frame_beyond_the_zone_renders_whole_as_a_camera_hologram(empty_scene, tmp_path, caplog):
    """The plate recorded, the camera moved 0.5 m beyond its zone: by default (Outside Zone:
    Camera Hologram) the frame's job is a camera hologram of that frame, which names the
    distance and the plate, and its render composites opaque (no pixel with alpha < 0.99)
    with a log line naming the route; with Warn the plate's view is kept, with a warning that
    what it cannot send is left transparent, and the frame's log counts its transparent
    pixels."""
    import logging

    from holo_addon.blender import compat
    from holo_addon.render import pipeline
    from holo_core.job import CameraRoute, PlateRoute

    scene = empty_scene
    _, cam, _ = _plate_scene(scene)
    assert bpy.ops.holo.record_hologram() == {"FINISHED"}
    cam.location.x += 0.5
    bpy.context.view_layer.update()

    def job():
        return pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get())

    assert scene.holo.outside_zone == "CAMERA"
    whole = job()
    assert isinstance(whole.job.route, CameraRoute), whole.job.route
    assert "beyond the viewing zone of plate 'Plane'" in whole.instead, whole.instead
    assert whole.plate_name is None and not whole.holograms
    scene.holo.outside_zone = "WARN"
    cut = job()
    assert isinstance(cut.job.route, PlateRoute)
    assert any("left out of its view, transparent" in w for w in cut.warnings), cut.warnings
    scene.holo.outside_zone = "CAMERA"
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 4
    scene.render.film_transparent = False
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    compat.set_exr_output(scene, multilayer=False)
    scene.render.filepath = str(tmp_path / "frame.exr")
    with caplog.at_level(logging.INFO, logger="holo_addon.compositor.handlers"):
        bpy.ops.render.render(write_still=True)
    alpha = _read_exr(tmp_path / "frame.exr")["A"]
    assert (alpha < 0.99).sum() == 0, f"{(alpha < 0.99).sum()} pixels with alpha < 0.99"
    said = [r.getMessage() for r in caplog.records if "frame 1:" in r.getMessage()]
    assert any("as a camera hologram (the camera's pupil reaches" in m for m in said), said
    assert not [m for m in said if "transparent" in m], said
    scene.holo.outside_zone = "WARN"
    caplog.clear()
    with caplog.at_level(logging.INFO, logger="holo_addon.compositor.handlers"):
        bpy.ops.render.render(write_still=True)
    holes = int((_read_exr(tmp_path / "frame.exr")["A"] < 0.99).sum())
    said = [r.getMessage() for r in caplog.records if "frame 1:" in r.getMessage()]
    assert holes > 0, "the plate's view beyond its zone left nothing out"
    assert any(f"{holes} pixels of the composite are transparent" in m for m in said), said
    assert any("from plate 'Plane'" in m for m in said), said


def test_the_zone_is_drawn_as_its_box(empty_scene):
    """The overlay's zone: the box's 12 edges, at its centre and half widths in the world."""
    from holo_addon.export.plates import plate_from_object
    from holo_addon.ui.overlay import zone_edges

    scene = empty_scene
    _, _, plate = _plate_scene(scene)
    plate.holo.zone_centre, plate.holo.zone_half = (0.0, 0.0, 1.5), (0.3, 0.2, 0.1)
    plate.holo.zone_set = True
    edges = zone_edges(plate_from_object(plate, 1.0), 1.0)
    assert edges.shape == (24, 3)
    local = (edges - np.array(plate.matrix_world.translation)) @ np.array(
        plate.matrix_world.to_3x3().normalized()
    )
    assert np.allclose(np.abs(local - (0, 0, 1.5)).max(0), (0.3, 0.2, 0.1), atol=1e-6)


def test_planner_in_the_panel(empty_scene):
    """Plan Plate states, before recording, its verdict, the plate's samples, wavelength,
    disk, memory, time and what the camera's view of it resolves."""
    from holo_addon.ui import plates

    scene = empty_scene
    _, _, plate = _plate_scene(scene)
    bpy.context.view_layer.objects.active = plate
    assert bpy.ops.holo.plan_plate() == {"FINISHED"}
    lines = plates.plan_lines(plate)
    print("\n".join(lines))
    text = "\n".join(lines)
    for word in ("verdict", "Mpx", "µm apart", "wavelength", "GiB", "tile by tile", "per view"):
        assert word in text, word


def test_the_plan_samples_the_plate_the_recording_samples(empty_scene):
    """Plan Plate sizes the plate from the emitters' triangles, as the recording does, not
    from their bounding boxes: a turned sphere's box is up to √3 times wider than the sphere
    in the plate's frame (the demo's plan said 74 Mpx and 4.4 GB where the plate recorded
    46 Mpx and 2.7 GB)."""
    from holo_addon.render import pipeline
    from holo_addon.ui import plates
    from holo_core.plate.recording import plate_plan

    scene = empty_scene
    cube, _, plate = _plate_scene(scene)
    bpy.data.objects.remove(cube)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.2, rotation=(0.6, 0.4, 0.8))
    bpy.context.object.holo.emitter = "POINTS"
    bpy.context.view_layer.update()
    bpy.context.view_layer.objects.active = plate
    assert bpy.ops.holo.plan_plate() == {"FINISHED"}
    job = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get(), render=False).job
    p = plate_plan(
        list(job.points) + list(job.triangles),
        plate=job.route.plate,
        camera=job.camera,
        wavelength=job.route.wavelength,
    ).plan
    rows, cols = p.shape
    text = "\n".join(plates.plan_lines(plate))
    assert f": {cols} x {rows} samples" in text, (p.shape, text)


def test_import_a_hologram_and_keep_its_link(empty_scene, tmp_path, rng):
    """File ▸ Import ▸ Hologram: a plate hologram file becomes a plate object of its size where
    its metadata puts it, linked to its file; the link survives saving and reopening the
    .blend; the pass is rendered from it without recording (no emitter in the scene)."""
    scene = empty_scene
    bpy.ops.object.camera_add(location=(0.2, -0.1, 1.0), rotation=(0, 0, 0))
    scene.camera = bpy.context.object
    scene.render.resolution_x, scene.render.resolution_y = 24, 16
    pose = np.eye(4)
    pose[:3, 3] = (0.2, -0.1, 0.5)
    wave = rng.standard_normal((1, 64, 96)) + 1j * rng.standard_normal((1, 64, 96))
    h = Hologram(
        object_wave=wave.astype(np.complex64),
        encoding="complex",
        wavelengths=(2e-5,),
        pitch=5e-4,
        plate=pose,
        bounds=[[-0.02, -0.02, -0.3], [0.02, 0.02, -0.29]],
        zone=ViewingZone(centre=(0, 0, 0.5), half_extents=(0.1, 0.1, 0.1)),
    )
    path = write_hologram(tmp_path / "acquired.exr", h)
    blend = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    assert bpy.ops.holo.import_hologram(filepath=str(path)) == {"FINISHED"}
    obj = next(o for o in bpy.context.scene.objects if o.holo.is_plate)
    assert obj.holo.imported and obj.holo.hologram == "//acquired.exr"
    assert np.allclose(obj.matrix_world.translation, (0.2, -0.1, 0.5))
    assert np.allclose(obj.dimensions[:2], (96 * 5e-4, 64 * 5e-4))
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    obj = next(o for o in bpy.context.scene.objects if o.holo.is_plate)
    assert bpy.path.abspath(obj.holo.hologram) == str(path)
    bpy.context.scene.holo.output_dir = str(tmp_path / "holo") + "/"
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert (tmp_path / "holo" / "holo_pass_0001.exr").is_file()


def test_import_a_scan_and_composite_its_letter(empty_scene, tmp_path):
    """File ▸ Import ▸ Hologram of a peer's off-axis scan (tests/scans.py: a letter F with a
    dot on its right, 5 cm behind a 2048² sensor of 3.45 µm at 633 nm, a 16-bit PNG) with its
    pitch, wavelength and distance alone: the carrier found (reported), the
    object wave written as a Holo hologram and linked to a plate, a camera added that frames
    it, focused at the distance; Render with Hologram composites the pass over the raster,
    and the final frame shows the letter where the truth has it through the plate's window
    (the plate is a holdout for camera rays, the hole the pass fills; Cycles blurs its edge
    by the camera's depth of field, as the raster's wall around it), measured IoU 0.980."""
    import scans

    from holo_addon.blender import compat
    from holo_addon.export.scene import camera_from_object

    scene = empty_scene
    scan = scans.optical_scan(tmp_path)
    assert bpy.ops.holo.import_hologram(
        filepath=str(scan), pitch=3.45, wavelength=633.0, distance=0.05
    ) == {"FINISHED"}
    plate = next(o for o in scene.objects if o.holo.is_plate)
    assert plate.holo.imported and plate.holo.hologram.endswith("letter_scan_2048_holo.exr")
    assert scene.camera is not None and scene.camera.data.dof.use_dof
    assert abs(scene.camera.data.dof.focus_distance - 0.15) < 1e-6  # 2 x 5 cm + 5 cm
    # a grey wall behind the plate: the raster around the plate's window, hidden inside it
    bpy.ops.mesh.primitive_plane_add(size=0.05, location=(0, 0, -0.1))
    wall = bpy.context.object
    wall.data.materials.append(bpy.data.materials.new("wall"))
    wall.data.materials[0].diffuse_color = (0.2, 0.2, 0.2, 1)
    scene.world = bpy.data.worlds.new("grey")
    scene.world.color = (0.5, 0.5, 0.5)  # lights the wall
    scene.render.engine = "CYCLES"  # holdouts: Cycles and EEVEE
    scene.cycles.samples, scene.cycles.use_denoising = 4, False
    compat.set_exr_output(scene, multilayer=False)
    scene.render.filepath = str(tmp_path / "frame.exr")
    assert bpy.ops.holo.render() == {"FINISHED"}
    image = _read_exr(tmp_path / "frame.exr")
    luminance = np.mean([image[c] for c in "RGB"], 0)
    camera = camera_from_object(scene, scene.camera, 1.0)
    tx, ty = camera.pixel_tangents()
    rays = np.stack([tx, ty, -np.ones_like(tx)], -1) @ camera.rotation.T

    def meets(z):  # where each pixel's ray meets the plane z [m]
        t = (z - camera.position[2]) / rays[..., 2]
        return camera.position[0] + t * rays[..., 0], camera.position[1] + t * rays[..., 1]

    x, y = meets(-scans.DISTANCE)
    truth = scans.letter(x, y)
    px, py = meets(0.0)
    half = scans.SIZE * scans.PITCH / 2
    window = (np.abs(px) < 0.98 * half) & (np.abs(py) < 0.98 * half)
    around = (np.abs(px) > 1.02 * half) | (np.abs(py) > 1.02 * half)
    wall_seen = float(np.median(luminance[around]))
    shown = window & (luminance > float(np.median(luminance[truth])) / 2)
    iou = (shown & truth).sum() / (shown | truth).sum()
    cols = np.indices(shown.shape)[1]
    dot = (x - 0.25 * scans.LETTER_HEIGHT) ** 2 + (y + 0.3 * scans.LETTER_HEIGHT) ** 2 <= (
        0.09 * scans.LETTER_HEIGHT
    ) ** 2
    print(
        f"composite: IoU {iou:.4f}, dot {shown[dot].mean():.3f} shown, the wall around the "
        f"window {wall_seen:.3g}, inside it {float(np.median(luminance[window & ~truth])):.3g}"
    )
    assert iou >= 0.95, iou
    assert shown[dot].mean() >= 0.9 and cols[dot].mean() > cols[truth].mean()
    assert wall_seen > 0.01, "the raster around the plate's window is the wall"


def test_a_shot_records_once_and_every_frame_renders_from_it(empty_scene):
    """Fit Zone to Shot: the camera dollies 10 cm over frames 1-3; the zone holds its pupil at
    every frame (the Zone Margin around it), the plate is recorded for the first frame and
    every later frame renders from it, recording nothing; the planner, run in Blender's
    process, gives its verdict first."""
    from holo_addon.render import pipeline
    from holo_addon.ui import plates

    scene = empty_scene
    _, cam, plate = _plate_scene(scene)
    plate.holo.zone_margin = 0.01
    for frame, x in ((1, -0.05), (3, 0.05)):
        cam.location.x = x
        cam.keyframe_insert("location", frame=frame)
    scene.frame_start, scene.frame_end = 1, 3
    scene.frame_set(2)
    bpy.context.view_layer.objects.active = plate
    assert bpy.ops.holo.fit_zone_to_shot() == {"FINISHED"}
    assert scene.frame_current == 2
    zone = ViewingZone(
        centre=tuple(plate.holo.zone_centre),
        half_extents=tuple(plate.holo.zone_half),
        pupil=plate.holo.zone_pupil,
    )
    pupil = 0.05 / 2.8
    assert zone.half_extents[0] == pytest.approx(0.05 + pupil / 2 + 0.01, rel=1e-4), zone
    assert zone.half_extents[1] == pytest.approx(pupil / 2 + 0.01, rel=1e-4), zone
    assert bpy.ops.holo.plan_plate() == {"FINISHED"}
    assert plates.plan_lines(plate)[0].startswith("verdict"), plates.plan_lines(plate)
    records = []
    for frame in (1, 2, 3):
        scene.frame_set(frame)
        job = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get(), render=False)
        records.append(job.records)
        assert not [w for w in job.warnings if "viewing zone" in w], job.warnings
        assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert records == [True, False, False], records


def test_auto_iterations_and_supersample_take_the_plans_choice(empty_scene):
    """Iterations and Supersample default to 0 (Auto): a plate's job records the looks and
    views at the supersampling the plan chooses for the scene (holo_core.plate.quality), and
    Plan Plate says what it chose and why; a Camera-mode job takes two fine pixels. A user's
    Iterations 1 is kept, and both the job's warnings and Plan Plate say what it loses
    against Auto, in dB."""
    from holo_addon.render import pipeline
    from holo_addon.ui import plates
    from holo_core.plate.quality import choose

    scene = empty_scene
    _, cam, plate = _plate_scene(scene)
    scene.holo.property_unset("iterations")
    scene.holo.property_unset("supersample")
    assert (scene.holo.iterations, scene.holo.supersample) == (0, 0)
    bpy.context.view_layer.objects.active = plate
    prepared = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get(), render=False)
    route = prepared.job.route
    expected = choose(_route_plan(prepared), resolution=prepared.job.camera.resolution)
    assert len(route.holograms) == expected.looks and route.supersample == expected.supersample
    assert not [w for w in prepared.warnings if "set by hand" in w], prepared.warnings
    assert bpy.ops.holo.plan_plate() == {"FINISHED"}
    text = "\n".join(plates.plan_lines(plate))
    assert (
        f"quality     Auto chose {expected.looks} looks, supersample "
        f"{expected.supersample}: predicted {expected.psnr:.1f} dB" in text
    ), text
    scene.holo.iterations = 1
    mine = choose(_route_plan(prepared), resolution=prepared.job.camera.resolution, looks=1)
    assert mine.loss > 0.05, mine  # the scene's plan asks more than one look
    prepared = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get(), render=False)
    assert len(prepared.job.route.holograms) == 1
    said = [w for w in prepared.warnings if "Iterations 1 (set by hand) predict" in w]
    assert said and f"{mine.loss:.1f} dB less than Auto's" in said[0], prepared.warnings
    assert bpy.ops.holo.plan_plate() == {"FINISHED"}
    text = "\n".join(plates.plan_lines(plate))
    assert "warning     Iterations 1 (set by hand) predict" in text, text
    scene.holo.mode = "CAMERA"
    prepared = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get())
    assert prepared.job.route.supersample == 2


def test_auto_looks_fit_the_disk_budget(empty_scene):
    """Auto's looks fit the Disk Budget as the recording checks it: a budget between the
    plan's disk for fewer looks and for Auto's free choice holds the job's looks to the most
    it holds, and Plan Plate's budget line says so with what the free choice would reach."""
    from holo_addon.render import pipeline
    from holo_addon.ui import plates
    from holo_core.plate.quality import choose

    scene = empty_scene
    cube, cam, plate = _plate_scene(scene)
    cube.scale = (DEEP, DEEP, DEEP)  # its back out of focus when its front is sharp
    cam.data.dof.aperture_fstop = 1.4
    scene.render.resolution_x, scene.render.resolution_y = RESOLUTION
    bpy.context.view_layer.update()
    scene.holo.property_unset("iterations")
    scene.holo.property_unset("supersample")
    bpy.context.view_layer.objects.active = plate
    prepared = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get(), render=False)
    route = prepared.job.route
    p = _route_plan(prepared)
    free = choose(p, resolution=RESOLUTION)
    print(free.describe(), [replace(p, looks=n).disk_bytes() / 2**30 for n in (2, 4, 9)])
    assert free.looks > 2, free
    assert len(route.holograms) == free.looks
    fewer = 2 if free.looks == 4 else 4
    scene.holo.plate_disk = replace(p, looks=fewer).disk_bytes(tiled=True) / 2**30 * 1.02
    held = choose(
        p,
        resolution=RESOLUTION,
        budget=(scene.holo.plate_memory * 2**30, scene.holo.plate_disk * 2**30),
    )
    assert held.looks == fewer and held.capped(), held
    prepared = pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get(), render=False)
    assert len(prepared.job.route.holograms) == fewer
    assert bpy.ops.holo.plan_plate() == {"FINISHED"}
    text = "\n".join(plates.plan_lines(plate))
    assert f"budget      Auto chose {fewer} looks, the most the Disk Budget of " in text, text
    assert f"; {free.looks} would reach {free.psnr:.1f} dB" in text, text
    print(text)
    assert "refused" not in text, text


def _route_plan(prepared):
    """The plan of the prepared job's plate for its meshes, as the add-on's Auto plans it."""
    from holo_core.plate.plan import plan

    job = prepared.job
    route = job.route
    local = route.plate.to_plate(np.concatenate([m.vertices for m in job.points + job.triangles]))
    zone = route.plate.zone
    return plan(
        (route.plate.width, route.plate.height),
        [local.min(0), local.max(0)],
        zone=zone,
        pixel_angle=zone.pixel or job.camera.pixel_angle(),
    )
