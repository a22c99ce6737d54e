"""Settings a .blend holds outside their properties' ranges (a script that sets the stored
value, another version's file, a damaged one) are refused before any work, named as the panel
names them, with its range in its units (holo_addon/export/ranges)."""

import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _plate_camera_cube  # noqa: E402
from test_compositor import BACKGROUND, in_background  # noqa: E402

STORED = [  # (settings, property, value the file holds, what the refusal says)
    (
        "scene",
        "iterations",
        10**9,
        r"Iterations \(Render Properties ▸ Holo\) must be within 0 … 64; got 1000000000",
    ),
    (
        "scene",
        "supersample",
        16,
        r"Supersample \(Render Properties ▸ Holo\) must be within 0 … 4; got 16",
    ),
    (
        "scene",
        "plate_memory",
        -1.0,
        r"Memory Budget \(Render Properties ▸ Holo\) must be at least 0.1 GiB; got -1 GiB",
    ),
    (
        "scene",
        "wavelength",
        float("nan"),
        r"Wavelength \(Render Properties ▸ Holo\) must be within 0 m … 1 m; got nan",
    ),
    (
        "scene",
        "exposure",
        1000.0,
        r"Exposure \(Render Properties ▸ Holo\) must be within -64 stops … 64 stops; got 1000 "
        r"stops",
    ),
    (
        "scene",
        "mode",
        7,
        r"Hologram \(Render Properties ▸ Holo\) must be one of Camera, Plate; the file holds "
        r"none of them",
    ),
    (
        "plate",
        "zone_margin",
        -0.5,
        r"Zone Margin \(Object Properties ▸ Holo, object 'Plane'\) must be at least 0 m; got "
        r"-0.5 m",
    ),
]


@pytest.mark.parametrize(
    ("owner", "name", "value", "said"), STORED, ids=[f"{o}.{n}" for o, n, _, _ in STORED]
)
def test_a_stored_setting_outside_its_range_is_refused_by_its_panel_name(
    empty_scene, owner, name, value, said
):
    from holo_addon.export.scene import ExportError
    from holo_addon.render import pipeline

    scene = empty_scene
    plate = _plate_camera_cube(scene)[2]
    scene.holo.mode = "PLATE"
    settings = scene.holo if owner == "scene" else plate.holo
    pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get())  # in range: read
    settings[name] = value  # what the panel cannot set, as a script or a damaged file holds it
    with pytest.raises(ExportError, match=said):
        pipeline.prepare(scene, bpy.context.evaluated_depsgraph_get())


DAMAGED_FARM_RENDER = (
    BACKGROUND
    + """sys.path.insert(0, sys.argv[2])
import test_addon
test_addon._plate_camera_cube(scene)
scene.holo.mode = "PLATE"
bpy.ops.holo.setup_compositing()
scene.holo["iterations"] = 10**9
scene.render.filepath = sys.argv[3] + "/frame_"
scene.frame_end = 1
bpy.ops.render.render(animation=True)
print("rendered")
"""
)


def test_a_damaged_setting_fails_a_background_render_before_any_work(tmp_path):
    """``blender -b ... -a`` of a scene whose Iterations is 10⁹ (it asked for 10 GB in 163 s):
    status 1 at once, the setting named as the panel names it, no frame and no hologram."""
    run = in_background(DAMAGED_FARM_RENDER, tmp_path)
    assert run.returncode == 1, run.stdout[-2000:] + run.stderr[-2000:]
    assert (
        "Iterations (Render Properties ▸ Holo) must be within 0 … 64; got 1000000000" in run.stderr
    ), run.stderr[-2000:]
    assert "rendered" not in run.stdout and not list(tmp_path.glob("frame_*"))
    assert not list(tmp_path.glob("holo/*hologram*")), "a hologram was recorded"
