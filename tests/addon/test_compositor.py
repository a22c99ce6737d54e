"""The pass in Blender's render (holo_addon/compositor): each frame's pass made from that frame's
scene by the frame handlers, the user's nodes kept, the layers written beside the frame, a
failed or cancelled pass never composited."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from test_addon import _camera_columns, _plate_camera_cube, _read_exr  # noqa: E402
from test_export import _emitter_meshes  # noqa: E402


def _moving_cube(scene, tmp_path, margin=0.01):
    """A cube that moves between frames 1-3 before a pinhole camera and a plate whose zone
    reaches ``margin`` [m] around the camera (the plate sends light only into its zone)."""
    cube, cam, plate = _plate_camera_cube(scene, cube_size=0.4)
    plate.holo.zone_margin = margin
    bpy.ops.object.light_add(type="SUN", rotation=(np.radians(60), 0, 0))  # lights its front
    bpy.context.object.data.energy = 3.0
    scene.render.resolution_x, scene.render.resolution_y = 48, 36
    scene.render.resolution_percentage = 100
    scene.render.engine = "CYCLES"  # Workbench draws every object: emitters too
    scene.cycles.samples = 4
    scene.render.film_transparent = False
    scene.holo.mode = "PLATE"
    scene.holo.iterations = 1
    for frame, x in ((1, -0.15), (2, 0.15), (3, -0.05)):
        cube.location.x = x
        cube.keyframe_insert("location", frame=frame)
    return cube, cam


def _middle(path):
    """The middle [px, from the image's left edge] of the pass's silhouette across: between
    the columns where its coverage (the alpha's greatest down each column) crosses 0.5, each
    found between the pixel centres either side (a whole pixel's steps moved it by half a
    pixel where a soft edge lay near 0.5)."""
    cover = _read_exr(path)["ViewLayer.Combined.A"].max(0)
    inside = np.nonzero(cover > 0.5)[0]
    first, last = inside.min(), inside.max()

    def crossing(a, b):  # from centre a (coverage <= 0.5) to centre b (> 0.5): where 0.5 lies
        return a + (b - a) * (0.5 - cover[a]) / (cover[b] - cover[a]) + 0.5

    left = crossing(first - 1, first) if first > 0 else 0.0
    right = crossing(last + 1, last) if last + 1 < len(cover) else float(len(cover))
    return (left + right) / 2


def test_an_animation_started_away_from_the_timeline_frame_uses_each_frames_geometry(
    empty_scene, tmp_path
):
    """The timeline rests on frame 1; frames 2-3 are rendered (a farm chunk): each pass shows
    its own frame's cube, where the camera projects it (within half a pixel)."""
    from holo_addon.blender import compat
    from holo_addon.render import pipeline

    scene = empty_scene
    cube, cam = _moving_cube(scene, tmp_path)
    scene.frame_set(1)
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    compat.set_png_output(scene)
    scene.render.filepath = str(tmp_path / "frame_")
    scene.frame_start, scene.frame_end = 2, 3
    bpy.ops.render.render(animation=True)
    out = pipeline.output_dir(scene)
    corners = np.array([(x, y, z) for x in (-0.2, 0.2) for y in (-0.2, 0.2) for z in (-0.2, 0.2)])
    for frame, x in ((2, 0.15), (3, -0.05)):
        got = _middle(out / f"holo_pass_{frame:04d}.exr")
        cols = _camera_columns(scene, cam, corners + (x, 0, 0))
        want = (min(cols) + max(cols)) / 2
        print(f"frame {frame}: silhouette middle {got} px, projected {want:.2f} px")
        assert abs(got - want) <= 0.5, (frame, got, want)


def _render_range(scene, start, end, folder, tmp_path):
    from holo_addon.blender import compat

    scene.holo.output_dir = str(folder) + "/"
    compat.set_exr_output(scene, multilayer=False)
    scene.render.filepath = str(tmp_path / folder.name / "frame_")
    scene.frame_start, scene.frame_end = start, end
    bpy.ops.render.render(animation=True)


def test_three_frames_as_one_animation_or_separate_frames_give_identical_passes(
    empty_scene, tmp_path, monkeypatch
):
    """A cube and the camera both move; ``-a`` over frames 1-3 and three single-frame runs
    (as a farm splits them) give bit-identical passes, each where the camera projects that
    frame's cube (within half a pixel), and each frame's composite shows its own pass. The
    animation's frames share one worker process, which holds the plate between them (so the
    identical passes also say that the plate held equals the plate read), and it ends with
    the render."""
    from holo_addon.render import pipeline
    from holo_core import worker

    started = []
    process = worker._Process.__init__
    monkeypatch.setattr(
        worker._Process, "__init__", lambda self, env: (started.append(1), process(self, env))[-1]
    )
    scene = empty_scene
    # a zone that holds the camera's 10 cm move with room for its pinhole pupil (the widest
    # its defocus allows, 34 cm here)
    cube, cam = _moving_cube(scene, tmp_path, margin=0.25)
    for frame, dx in ((1, 0.0), (2, 0.05), (3, 0.1)):
        cam.location.x = dx
        cam.keyframe_insert("location", frame=frame)
    scene.frame_set(1)
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    started.clear()
    _render_range(scene, 1, 3, tmp_path / "all", tmp_path)
    assert started == [1] and worker._resident is None, "the frames did not share a worker"
    for frame in (3, 1, 2):  # separate runs, in any order, from wherever the timeline rests
        _render_range(scene, frame, frame, tmp_path / "single", tmp_path)
    corners = np.array([(x, y, z) for x in (-0.2, 0.2) for y in (-0.2, 0.2) for z in (-0.2, 0.2)])
    for frame, x in ((1, -0.15), (2, 0.15), (3, -0.05)):
        a, b = (_read_exr(pipeline.pass_file(tmp_path / run, frame)) for run in ("all", "single"))
        assert all(np.array_equal(a[k], b[k]) for k in a), f"frame {frame}: passes differ"
        scene.frame_set(frame)
        cols = _camera_columns(scene, cam, corners + (x, 0, 0))
        want, got = (
            (min(cols) + max(cols)) / 2,
            _middle(pipeline.pass_file(tmp_path / "all", frame)),
        )
        image = _read_exr(tmp_path / "all" / f"frame_{frame:04d}.exr")
        rgb = np.stack([image[c] for c in "RGB"], -1)
        shown = np.nonzero((np.abs(rgb - rgb[0, 0]).max(-1) > 0.05).any(0))[0]
        composite = (shown.min() + shown.max() + 1) / 2
        print(f"frame {frame}: pass middle {got}, composite {composite}, projected {want:.2f} px")
        assert abs(got - want) <= 0.5 and abs(composite - got) <= 0.5


def test_compositing_keeps_the_users_nodes_and_links(empty_scene, tmp_path):
    """A user's Render Layers → Glare → output chain (and a Viewer) survives the setup: every
    node and link stays, the chain's result is the raster the pass fills, the composite goes
    out."""
    from holo_addon.blender import compat
    from holo_addon.compositor import tree as compositing
    from holo_addon.render import pipeline
    from holo_core.io.view import write_view
    from holo_core.view import RenderResult

    scene = empty_scene
    _plate_camera_cube(scene)
    tree = compat.compositor_tree(scene)
    rl = tree.nodes.new("CompositorNodeRLayers")
    glare = tree.nodes.new("CompositorNodeGlare")
    viewer = tree.nodes.new("CompositorNodeViewer")
    tree.links.new(rl.outputs["Image"], glare.inputs[0])
    tree.links.new(glare.outputs[0], compat.output_socket(tree))
    tree.links.new(rl.outputs["Image"], viewer.inputs[0])

    def links():
        return {
            (l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
            for l in tree.links
        }

    before, nodes = links(), {n.name for n in tree.nodes}
    out = pipeline.output_dir(scene)
    write_view(
        RenderResult(rgb=np.ones((24, 32, 3)), alpha=np.ones((24, 32)), depth=np.ones((24, 32))),
        pipeline.pass_file(out, scene.frame_current),
    )
    for _ in range(2):  # again: only the add-on's nodes are rebuilt
        compositing.setup(scene, out)
    raster = tree.nodes[compositing.NODE_PREFIX + "Raster"]
    combine = tree.nodes[compositing.NODE_PREFIX + "Composite"]
    output_link = next(l for l in before if l[0] == glare.name)
    assert before - links() == {output_link}, "only the link into the output is re-routed"
    assert nodes <= {n.name for n in tree.nodes}
    assert raster.inputs[0].links[0].from_node == glare
    assert compat.output_socket(tree).links[0].from_node == combine
    assert sum(n.name == compositing.NODE_PREFIX + "Composite" for n in tree.nodes) == 1


def _scene_with_pass(scene, tmp_path):
    from holo_addon.blender import compat

    _moving_cube(scene, tmp_path)
    scene.frame_set(1)
    assert bpy.ops.holo.render_pass() == {"FINISHED"}
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    compat.set_exr_output(scene, multilayer=False)


def _shown_columns(path):
    image = _read_exr(path)
    rgb = np.stack([image[c] for c in "RGB"], -1)
    return np.nonzero((np.abs(rgb - rgb[0, 0]).max(-1) > 0.05).any(0))[0]


def _read_parts(path):
    """Every channel of every part (Blender 5 writes a multilayer EXR as one part per layer)."""
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        return {k: v.pixels.copy() for part in f.parts for k, v in part.channels.items()}


def test_each_rendered_frame_gets_its_holographic_layers_beside_it(empty_scene, tmp_path):
    """Beside the frame ``shot_0001.exr`` a multilayer ``holo_shot_0001.exr``: the composite
    (equal to the frame), the pass alone (equal to the pass file), its depth, and the
    composite's depth (the nearer of the pass's and the raster's), depths in ``.Z`` channels
    as Blender's own passes (Blender's File Output names them ``.V``)."""
    from holo_addon.render import pipeline

    scene = empty_scene
    _scene_with_pass(scene, tmp_path)
    scene.render.filepath = str(tmp_path / "out" / "shot_####")
    assert bpy.ops.holo.setup_compositing() == {"FINISHED"}
    scene.frame_start = scene.frame_end = 1
    bpy.ops.render.render(animation=True)
    layers = _read_parts(tmp_path / "out" / "holo_shot_0001.exr")
    frame = _read_exr(tmp_path / "out" / "shot_0001.exr")
    holo = _read_exr(pipeline.pass_file(pipeline.output_dir(scene), 1))
    for c in "RGBA":
        np.testing.assert_allclose(layers[f"Composite.{c}"], frame[c], atol=1e-6)
        np.testing.assert_allclose(layers[f"Holo.{c}"], holo[f"ViewLayer.Combined.{c}"], atol=1e-6)
    assert not [k for k in layers if k.endswith(".V")], "depth channels are named .Z"
    np.testing.assert_allclose(layers["HoloDepth.Z"], holo["ViewLayer.Depth.Z"], rtol=1e-6)
    shown = holo["ViewLayer.Combined.A"] > 0.5
    assert shown.any() and (layers["Depth.Z"] <= layers["HoloDepth.Z"]).all()
    np.testing.assert_allclose(layers["Depth.Z"][shown], layers["HoloDepth.Z"][shown], rtol=1e-6)


def test_a_failed_pass_never_composites_a_stale_one(empty_scene, tmp_path, monkeypatch):
    """In the interface a handler cannot cancel the render: the failed frame shows the raster
    alone (the stale pass set aside, kept), and the next good pass shows again."""
    from holo_addon.compositor.session import session
    from holo_addon.render import pipeline
    from holo_core.worker import WorkerError

    scene = empty_scene
    _scene_with_pass(scene, tmp_path)
    monkeypatch.setattr(session, "exit_on_failure", False)
    original = pipeline.run

    def broken(job, progress=None, on_log=None, **_):
        raise WorkerError("a crash in native code")

    monkeypatch.setattr(pipeline, "run", broken)
    assert pipeline.pass_file(pipeline.output_dir(scene), 1).is_file()  # the stale pass
    scene.render.filepath = str(tmp_path / "failed.exr")
    bpy.ops.render.render(write_still=True)
    assert _shown_columns(tmp_path / "failed.exr").size == 0, "a stale pass was composited"
    assert (pipeline.output_dir(scene) / "holo_pass_0001.stale.exr").is_file()
    monkeypatch.setattr(pipeline, "run", original)
    scene.render.filepath = str(tmp_path / "good.exr")
    bpy.ops.render.render(write_still=True)
    assert _shown_columns(tmp_path / "good.exr").size > 0


def test_an_output_folder_that_cannot_be_written_fails_the_frame(
    empty_scene, tmp_path, monkeypatch
):
    """An Output Folder under a file: the render's frame fails, naming the setting (a
    background render exits with status 1 there), and it composites no pass of the folder
    before."""
    from holo_addon.compositor import handlers
    from holo_addon.compositor.session import session

    scene = empty_scene
    _scene_with_pass(scene, tmp_path)
    monkeypatch.setattr(session, "exit_on_failure", False)
    said = []
    original = handlers.failed
    monkeypatch.setattr(handlers, "failed", lambda s, m: (said.append(m), original(s, m)))
    (tmp_path / "a file").write_text("")
    scene.holo.output_dir = str(tmp_path / "a file" / "holo") + "/"
    scene.render.filepath = str(tmp_path / "failed.exr")
    bpy.ops.render.render(write_still=True)
    assert said and all("Output Folder" in m and "a file" in m for m in said), said
    assert _shown_columns(tmp_path / "failed.exr").size == 0, "the earlier folder's pass showed"


def test_after_save_as_a_failed_pass_never_composites_the_old_folders(
    empty_scene, tmp_path, monkeypatch
):
    """A .blend with its pass in its folder's holo/, saved as another .blend in another
    folder: the compositor's image follows the new folder (Blender kept the old folder's
    file), so a failed pass there shows the raster alone, not the old folder's pass; the next
    good pass shows."""
    from holo_addon.compositor.session import session
    from holo_addon.render import pipeline
    from holo_core.worker import WorkerError

    scene = empty_scene
    scene.holo.output_dir = "//holo/"
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "a" / "shot.blend"))
    scene = bpy.context.scene
    _scene_with_pass(scene, tmp_path)
    assert (tmp_path / "a" / "holo" / "holo_pass_0001.exr").is_file()
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "b" / "shot.blend"))
    scene = bpy.context.scene
    (image,) = [i for i in bpy.data.images if i.source == "SEQUENCE"]
    assert bpy.path.abspath(image.filepath) == str(tmp_path / "b" / "holo" / "holo_pass_0001.exr")
    monkeypatch.setattr(session, "exit_on_failure", False)
    original = pipeline.run

    def broken(job, progress=None, on_log=None, **_):
        raise WorkerError("a crash in native code")

    monkeypatch.setattr(pipeline, "run", broken)
    scene.render.filepath = str(tmp_path / "failed.exr")
    bpy.ops.render.render(write_still=True)
    assert _shown_columns(tmp_path / "failed.exr").size == 0, "the old folder's pass showed"
    assert (tmp_path / "a" / "holo" / "holo_pass_0001.exr").is_file(), "the old file is kept"
    monkeypatch.setattr(pipeline, "run", original)
    scene.render.filepath = str(tmp_path / "good.exr")
    bpy.ops.render.render(write_still=True)
    assert _shown_columns(tmp_path / "good.exr").size > 0
    assert (tmp_path / "b" / "holo" / "holo_pass_0001.exr").is_file()


# a background Blender's script (argv: the repository, tests/addon, a folder): the add-on
# registered and the scene's holographic output in the folder; BACKGROUND_SCENE adds a moving
# cube whose pass is composited, rendered into the folder by what follows
BACKGROUND = """
import sys
sys.path[:0] = [sys.argv[1], sys.argv[2]]
import bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
import holo_addon
holo_addon.register()
scene = bpy.context.scene
scene.holo.output_dir = sys.argv[3] + "/holo/"
"""
BACKGROUND_SCENE = (
    BACKGROUND
    + """import test_compositor
test_compositor._scene_with_pass(scene, None)
"""
)


def in_background(script: str, tmp_path, *args):
    """``script`` (:data:`BACKGROUND` and what follows) run by a Python of its own, on
    ``tmp_path`` (its ``sys.argv[3]``; ``args`` follow): the ended process."""
    here = Path(__file__).resolve()
    return subprocess.run(
        [
            sys.executable,
            "-c",
            script,
            str(here.parents[2]),
            str(here.parent),
            str(tmp_path),
            *map(str, args),
        ],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )


FAILING_FARM_RENDER = (
    BACKGROUND_SCENE
    + """from holo_addon.render import pipeline
def broken(job, progress=None, on_log=None, **_):
    raise RuntimeError("the worker failed")
pipeline.run = broken
scene.render.filepath = sys.argv[3] + "/frame_"
bpy.ops.render.render(animation=True)
print("rendered")
"""
)


def test_a_failed_pass_fails_a_background_animation(tmp_path):
    """``blender -b ... -a``: the process ends with status 1 and the error, before writing the
    frame."""
    run = in_background(FAILING_FARM_RENDER, tmp_path)
    assert run.returncode == 1, run.stdout[-2000:] + run.stderr[-2000:]
    assert "the holographic pass of frame 1 failed: the worker failed" in run.stderr
    assert "rendered" not in run.stdout and not list(tmp_path.glob("frame_*"))


UNWRITABLE_FARM_RENDER = (
    BACKGROUND_SCENE
    + """open(sys.argv[3] + "/a file", "w").close()
scene.holo.output_dir = sys.argv[3] + "/a file/holo/"
scene.render.filepath = sys.argv[3] + "/frame_"
bpy.ops.render.render(animation=True)
print("rendered")
"""
)


def test_an_unwritable_output_folder_fails_a_background_animation(tmp_path):
    """``blender -b ... -a`` with an Output Folder under a file: status 1 and the error naming
    the setting, before any frame is written (Blender's handlers printed a traceback and
    rendered on)."""
    run = in_background(UNWRITABLE_FARM_RENDER, tmp_path)
    assert run.returncode == 1, run.stdout[-2000:] + run.stderr[-2000:]
    assert "cannot be written: the Output Folder" in run.stderr, run.stderr[-2000:]
    assert "rendered" not in run.stdout and not list(tmp_path.glob("frame_*"))


READ_ONLY_FARM_RENDER = (
    BACKGROUND_SCENE
    + """scene.holo.output_dir = sys.argv[4] + "/"
scene.render.filepath = sys.argv[3] + "/frame_"
bpy.ops.render.render(animation=True)
print("rendered")
"""
)


@pytest.mark.parametrize("linked", [False, True], ids=["share", "link to it"])
def test_a_read_only_output_folder_fails_a_background_animation(tmp_path, linked):
    """``blender -b ... -a`` with an Output Folder that exists but takes no file (a read-only
    share on a farm node, or a link to one): status 1 and one error naming the setting and
    the folder, before any frame is written (it printed two tracebacks, rendered on and wrote
    the frames without their pass, status 0)."""
    from mounts import read_only_folder

    with read_only_folder(tmp_path / "share") as share:
        folder = share
        if linked:
            folder = tmp_path / "link"
            folder.symlink_to(share)
        run = in_background(READ_ONLY_FARM_RENDER, tmp_path, folder)
    assert run.returncode == 1, run.stdout[-2000:] + run.stderr[-2000:]
    said = [line for line in run.stderr.splitlines() if "Holo:" in line]
    assert (
        len(said) == 1
        and f"cannot be written: the Output Folder (Render Properties ▸ Holo) {folder}" in said[0]
        and "not writable" in said[0]
    ), run.stderr[-2000:]
    assert "Traceback" not in run.stderr, run.stderr[-2000:]
    assert "rendered" not in run.stdout and not list(tmp_path.glob("frame_*"))


def test_renders_use_render_modifier_levels(empty_scene, tmp_path, monkeypatch):
    """Subdivision at level 0 in the viewport and 2 in renders: the pass of an F12 render is
    made from level 2 (a cube's 12 triangles become 192)."""
    from holo_addon.render import pipeline

    scene = empty_scene
    _scene_with_pass(scene, tmp_path)
    cube = next(o for o in scene.objects if o.holo.emitter == "POINTS")
    sub = cube.modifiers.new("subdivision", "SUBSURF")
    sub.levels, sub.render_levels = 0, 2
    seen = []
    original = pipeline.run

    def run(job, progress=None, on_log=None, **kw):
        seen.append(sum(len(m.triangles) for m in job.job.points))
        return original(job, progress, on_log, **kw)

    monkeypatch.setattr(pipeline, "run", run)
    scene.render.filepath = str(tmp_path / "f12.exr")
    bpy.ops.render.render(write_still=True)
    assert seen == [192], seen
    assert len(_emitter_meshes(scene)[0].triangles) == 12  # the viewport's level


def test_the_pass_of_a_render_can_be_cancelled(empty_scene, tmp_path, monkeypatch):
    """Cancel Pass while a render makes its pass: the worker stops, the frame shows the raster
    alone (the stale pass set aside) and the panel's state is cleared."""
    from holo_addon.compositor.session import session
    from holo_addon.render import pipeline

    scene = empty_scene
    _scene_with_pass(scene, tmp_path)
    scene.holo.exposure = 1.0  # the pass is out of date: the worker runs
    original, clicked = pipeline.run, []

    def run(job, progress=None, on_log=None, **kw):
        def user(fraction):
            if not clicked:  # the user clicks while it runs
                clicked.append(bpy.ops.holo.cancel_pass())
            progress(fraction)

        return original(job, user, on_log, **kw)

    monkeypatch.setattr(pipeline, "run", run)
    scene.render.filepath = str(tmp_path / "cancelled.exr")
    bpy.ops.render.render(write_still=True)
    assert clicked == [{"FINISHED"}]
    assert _shown_columns(tmp_path / "cancelled.exr").size == 0
    assert (pipeline.output_dir(scene) / "holo_pass_0001.stale.exr").is_file()
    assert session.running.frame is None and not bpy.ops.holo.cancel_pass.poll()
