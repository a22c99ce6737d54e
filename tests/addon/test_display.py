"""A holographic display in a Blender scene: Render Animation writes, per frame, one pattern
per laser as the SLM's driver takes it, the layout naming them and the focal stack the
display shows; a frame is the same file for file whether rendered in sequence or alone; a
cancelled frame leaves the earlier frames' files as they were; a scene the display cannot
show is refused before any work, with its numbers."""

import json
import math

import pytest

bpy = pytest.importorskip("bpy")

from holo_core.io.image import read_exr  # noqa: E402
from holo_core.io.slm import read_pattern  # noqa: E402

FRAMES = (1, 2, 3)


def _display_scene(scene, *, depth=1.0, colours=(True, True, False)):
    """A 0.2 m textured quad ``depth`` m behind a 256 x 256 custom display at 8 µm (Scene
    Scale 0.01: 10 mm behind it, 2 mm across), moving 2 cm a frame across it; the eye box
    1 mm wide at 200 mm."""
    scene.holo.lighting = "ALBEDO"
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.render.resolution_x = scene.render.resolution_y = 16
    scene.frame_start, scene.frame_end = FRAMES[0], FRAMES[-1]
    bpy.ops.object.camera_add(location=(0.0, 0.0, 3.0))
    scene.camera = bpy.context.object
    bpy.ops.mesh.primitive_plane_add(size=0.2, location=(0.0, 0.0, -depth))
    quad = bpy.context.object
    quad.holo.emitter = "TRIANGLES"
    mat = bpy.data.materials.new("colour")
    from holo_addon.blender import compat

    compat.enable_nodes(mat)
    bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Base Color"].default_value = (0.9, 0.6, 0.3, 1)
    quad.data.materials.append(mat)
    for frame in FRAMES:
        quad.location.x = 0.02 * (frame - 2)
        quad.keyframe_insert("location", frame=frame)
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0.0, 0.0, 0.0))
    shown = bpy.context.object
    shown.name = "Display"
    d = shown.holo.display
    d.preset = "CUSTOM"
    d.resolution = (256, 256)
    d.pitch = 8.0
    d.colours = colours
    d.scene_scale = 0.01
    d.behind, d.front = 20.0, 0.0
    d.eye_distance, d.eye_box, d.pupil = 200.0, 1.0, 1.0
    d.slices = 3
    shown.holo.is_display = True
    bpy.context.view_layer.update()
    return quad, shown


def _files(folder, frame):
    return sorted(p for p in folder.glob(f"frame_{frame:04d}*") if p.is_file())


def test_render_animation_writes_every_frame_and_a_frame_alone_is_the_same(empty_scene, tmp_path):
    """Render Animation over frames 1-3: each frame's patterns (8-bit grey PNG of the
    display's 256 x 256 codes, one per laser), its layout and its focal stack (EXR and
    contact sheet) are written, the sheet loaded as an image; the PSNR of each slice is in
    the layout. Frame 3 rendered alone into another folder is byte for byte the frame 3 of
    the sequence. A frame cancelled late in its stage leaves its earlier files unchanged
    and no temporary file."""
    from holo_addon.compositor import handlers
    from holo_addon.export.display import frame_folder, scene_display
    from holo_core import jobs

    scene = empty_scene
    quad, shown = _display_scene(scene)
    bpy.ops.render.render(animation=True)
    folder = frame_folder(scene, shown.name)
    for frame in FRAMES:
        names = [p.name for p in _files(folder, frame)]
        stem = f"frame_{frame:04d}"
        assert names == [
            f"{stem}.json",
            f"{stem}_520nm.json",
            f"{stem}_520nm.png",
            f"{stem}_638nm.json",
            f"{stem}_638nm.png",
            f"{stem}_stack.exr",
            f"{stem}_stack.png",
        ], names
        layout = json.loads((folder / f"{stem}.json").read_text())
        assert layout["frame"] == frame and [laser["name"] for laser in layout["lasers"]] == [
            "red",
            "green",
        ]
        for laser in layout["lasers"]:
            assert len(laser["psnr_db"]) == 3 and all(math.isfinite(v) for v in laser["psnr_db"])
        codes, pattern = read_pattern(folder / f"{stem}_638nm.json")
        assert (
            codes.shape == (256, 256)
            and codes.max() < 256
            and pattern["laser"]["wavelength"] == pytest.approx(638e-9)
        )
        image = bpy.data.images.load(str(folder / f"{stem}_638nm.png"))
        assert tuple(image.size) == (256, 256) and image.channels in (1, 4), image.channels
        bpy.data.images.remove(image)
    assert handlers.SHEET_IMAGE in bpy.data.images
    _, stack = read_exr(folder / "frame_0003_stack.exr")
    assert {"z00.R", "ref.z02.G"} <= set(stack), sorted(stack)[:6]
    # the quad moves: its frames differ
    assert (folder / "frame_0001_638nm.png").read_bytes() != (
        folder / "frame_0003_638nm.png"
    ).read_bytes()
    sequence = {p.name: p.read_bytes() for p in _files(folder, 3)}

    scene.holo.output_dir = str(tmp_path / "alone") + "/"
    scene.frame_set(3)
    bpy.ops.render.render(write_still=True)
    alone = {p.name: p.read_bytes() for p in _files(frame_folder(scene, shown.name), 3)}
    assert alone.keys() == sequence.keys()
    differ = [name for name in alone if alone[name] != sequence[name]]
    assert not differ, f"frame 3 alone differs from the sequence's in {differ}"

    # frame 2 of another state, cancelled in its stage: frame 2's files stay the sequence's
    scene.holo.output_dir = str(folder.parent.parent) + "/"
    before = {p.name: p.read_bytes() for p in _files(folder, 2)}
    scene.frame_set(2)
    quad.location.y += 0.01
    bpy.context.view_layer.update()

    def cancel_late(fraction):
        if fraction > 0.8:
            raise jobs.Cancelled()

    with pytest.raises(jobs.Cancelled):
        handlers.display_frame(
            scene, bpy.context.evaluated_depsgraph_get(), scene_display(scene), progress=cancel_late
        )
    after = {p.name: p.read_bytes() for p in _files(folder, 2)}
    assert after == before, "a cancelled frame changed frame 2's files"
    assert not [p.name for p in folder.iterdir() if p.name.startswith(".")]


def test_a_scene_too_close_for_the_pitch_is_refused_with_its_numbers(empty_scene):
    """The quad 5 cm (scene) behind the display, 0.5 mm at Scene Scale 0.01: through the
    1 mm pupil 200 mm away a point there is formed by 1 mm·0.5 / 200.5 / 8 µm = 0.31
    samples across, fewer than 2: refused before any work, naming the depth, the pitch and
    the nearest depth it can show (2·8 µm·200 mm / (1 mm + 16 µm) = 3.15 mm). Export Display
    Frame reports it."""
    from holo_addon.export.display import read
    from holo_addon.export.scene import ExportError

    scene = empty_scene
    _display_scene(scene, depth=0.05)
    with pytest.raises(ExportError) as refused:
        read(scene, bpy.context.evaluated_depsgraph_get())
    text = str(refused.value)
    for number in ("0.5 mm behind", "8 µm pitch", "0.31 samples", "at least 3.15 mm"):
        assert number in text, text
    with pytest.raises(RuntimeError, match="too close for its 8 µm pitch"):
        bpy.ops.holo.export_display()  # an operator's error report, raised to a script


def test_an_eye_box_beyond_the_diffraction_angle_is_refused_with_what_to_change(empty_scene):
    """A 20 mm eye box 200 mm from the 2.048 mm display: its far corner sees the display's
    corner at atan(√2·11.024/200) = 4.46°, beyond the 0.931° the display's filter passes of
    8 µm at 520 nm (asin(0.5·λ/2p)): refused, with the largest eye box there
    (2·(200·tan 0.931°/√2 − 1.024) = 2.55 mm) and the nearest eye distance for this one
    (√2·11.024 / tan 0.931° = 959 mm)."""
    from holo_addon.export.display import read
    from holo_addon.export.scene import ExportError

    scene = empty_scene
    _, shown = _display_scene(scene, colours=(False, True, False))
    shown.holo.display.eye_box = 20.0
    with pytest.raises(ExportError) as refused:
        read(scene, bpy.context.evaluated_depsgraph_get())
    text = str(refused.value)
    tan_limit = math.tan(math.asin(0.5 * 520e-9 / 16e-6))
    widest = 2 * (200 * tan_limit / math.sqrt(2) - 1.024)
    nearest = math.sqrt(2) * 11.024 / tan_limit
    for said in ("4.46°", "0.931°", f"at most {widest:.3g} mm", f"at least {nearest:.4g} mm"):
        assert said in text, (said, text)


def test_a_scene_outside_the_volume_names_the_scale_that_fits(empty_scene):
    """The quad 1 m behind at Scene Scale 0.01 reaches 10 mm; a volume of 5 mm behind
    refuses it, with the Scene Scale that fits (0.005)."""
    from holo_addon.export.display import read
    from holo_addon.export.scene import ExportError

    scene = empty_scene
    _, shown = _display_scene(scene)
    shown.holo.display.behind = 5.0
    with pytest.raises(ExportError) as refused:
        read(scene, bpy.context.evaluated_depsgraph_get())
    assert "Scene Scale of at most 0.005" in str(refused.value), str(refused.value)


def test_the_display_panel_draws_its_controls_and_sizes_the_plane(empty_scene):
    """Object ▸ Holo on a display: its preset, lasers, volume, eye box and Export Display
    Frame (each drawn control exists), the custom fields only for Custom, Iterations only
    for an iterative encoding, and its lines: 256 x 256 at 8 µm is 2.05 x 2.05 mm, 0.205 m
    in the scene at Scene Scale 0.01, the plane drawn that size."""
    from types import SimpleNamespace

    from test_interface import _draw

    from holo_addon.ui import panels as ui

    _, shown = _display_scene(empty_scene)
    context = SimpleNamespace(scene=empty_scene, object=shown)
    drawn = _draw(ui.HOLO_PT_object, context)
    for name in (
        "preset",
        "resolution",
        "pitch",
        "wavelengths",
        "powers",
        "scene_scale",
        "behind",
        "front",
        "eye_distance",
        "eye_box",
        "pupil",
        "table_red",
    ):
        assert ("prop", name) in drawn, name
    assert ("operator", "holo.export_display") in drawn and ("prop", "iterations") not in drawn
    assert ("label", "256 x 256 at 8 µm: 2.05 x 2.05 mm, 8-bit") in drawn, drawn
    assert tuple(round(v, 4) for v in shown.dimensions[:2]) == (0.2048, 0.2048)
    shown.holo.display.preset = "FHD_8"
    shown.holo.display.method = "gradient-descent"
    drawn = _draw(ui.HOLO_PT_object, context)
    assert ("prop", "resolution") not in drawn and ("prop", "iterations") in drawn
    bpy.context.view_layer.update()
    assert tuple(round(v, 4) for v in shown.dimensions[:2]) == (1.536, 0.864)
