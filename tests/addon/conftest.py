"""bpy in-process, isolated from the user's Blender configuration; the add-on registered from
the source tree. Skips cleanly where the bpy module is not installed."""

import os
import tempfile

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="holo-blender-"))
bpy = pytest.importorskip("bpy")


@pytest.fixture(scope="session")
def addon():
    import holo_addon
    from holo_addon.compositor.session import session

    holo_addon.register()
    # a failed pass in a render ends a background Blender (os._exit): not pytest's process
    session.exit_on_failure = False
    yield holo_addon
    holo_addon.unregister()


@pytest.fixture
def empty_scene(addon, tmp_path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.holo.output_dir = str(tmp_path / "holo") + os.sep
    scene.render.filepath = str(tmp_path / "render") + os.sep
    return scene


@pytest.fixture
def worker_frames(monkeypatch):
    """The frames of the worker processes started while the test runs, in order (a pass that
    is reused starts none)."""
    from holo_core import worker

    started = []
    original = worker.Worker.__init__

    def counting(self, job, *args, **kwargs):
        started.append(job.output.frame)
        original(self, job, *args, **kwargs)

    monkeypatch.setattr(worker.Worker, "__init__", counting)
    return started
