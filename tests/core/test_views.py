"""Live views through the worker (holo_core.worker.Views): a picture that crosses the process
and the shared memory is the view the core makes in this process, exposure applied; a burst of
requests is answered with the newest and the ones queued behind it skipped; a camera outside
the zone gets the viewer's sentence and no picture; a killed worker is started again at the
next request with the same plate and settings; closing unlinks the shared segment.

The plate scene (tests/plate_scene.py) at 80x45, a 6 cm plate, two coded looks for a zone
1 cm around the centre camera's pupil, written to files as a render keeps them.
"""

import dataclasses
import os
import signal

import numpy as np
import plate_scene as ps
import pytest

from holo_core import PlateViewer
from holo_core.io.hologram import write_hologram
from holo_core.io.shared_view import SharedView
from holo_core.plate.looks import record_looks
from holo_core.scene.plate import Plate
from holo_core.validate import InputError
from holo_core.worker import Views

PLATE = Plate(matrix_world=np.eye(4), width=0.06, height=0.06)
SCALE = 0.125  # 80x45
DIGEST = "0123abcd"
EXPOSURE = 2.0


@pytest.fixture(scope="module")
def plate_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("plate")
    looks = record_looks(
        ps.meshes(),
        looks=2,
        plate=PLATE,
        camera=ps.camera("centre", scale=SCALE),
        zone_margin=0.01,
        recording=DIGEST,
    )
    return [write_hologram(folder / f"plate.{i}.exr", h) for i, h in enumerate(looks)]


@pytest.fixture(scope="module")
def here(plate_files):
    """The same plate viewed in this process, as the worker views it."""
    with PlateViewer(plate_files, scene=DIGEST, supersample=1) as viewer:
        yield viewer


def cameras():
    eyes = [
        (0.0, 0.0, 0.3),
        (0.003, 0.0, 0.3),
        (0.0, -0.003, 0.3),
        (0.002, 0.002, 0.297),
        (-0.003, 0.001, 0.3),
        (0.001, -0.002, 0.302),
        (-0.002, -0.002, 0.3),
        (0.003, 0.003, 0.3),
    ]
    return [ps.camera(e, scale=SCALE) for e in eyes]


def expected(viewer, camera, coarse=False):
    view = viewer.view(camera, coarse=coarse)
    return (
        np.concatenate([view.rgb * EXPOSURE, view.alpha[..., None]], -1).astype(np.float32),
        view.depth.astype(np.float32),
    )


# the views are made in two processes: the same float32 arithmetic, but a process that loaded
# other native libraries (bpy, when the add-on's tests share the session) may sum in another
# order, a few ulps apart (9.5e-7 seen); a picture torn or misplaced differs by O(1)
RTOL = 1e-5


def assert_same(picture, want):
    rgba, depth = want
    assert picture.rgba is not None, picture.where or picture.error
    assert picture.rgba.shape == rgba.shape
    err = float(np.abs(picture.rgba - rgba).max())
    assert err <= RTOL * float(np.abs(rgba).max()), (
        f"the picture differs from this process's view by {err}"
    )
    np.testing.assert_allclose(picture.depth, depth, rtol=RTOL)
    assert np.asarray(rgba[..., 3]).max() == 1.0, "the objects are missing from the view"


@pytest.fixture
def views(plate_files):
    with Views(plate_files, recording=DIGEST, supersample=1, exposure=EXPOSURE) as v:
        yield v


def test_a_served_picture_is_the_view_made_in_this_process(views, here):
    """Full and coarse: every RGBA value (exposure applied) and depth, within RTOL; latest()
    never waits (None before the first answer)."""
    cam = cameras()[1]
    assert views.latest() is None
    n = views.ask(cam)
    picture = views.wait(n, timeout=120)
    assert picture.request == n and not picture.coarse and picture.seconds > 0
    assert_same(picture, expected(here, cam))
    n = views.ask(cam, coarse=True)
    picture = views.wait(n, timeout=60)
    assert picture.coarse
    assert_same(picture, expected(here, cam, coarse=True))
    assert views.opened == DIGEST


def test_a_burst_of_requests_is_answered_with_the_newest(views, here):
    """Eight cameras asked at once: the answer shown is the eighth's view, and the worker
    rendered fewer than eight (those queued behind a newer one are skipped)."""
    views.wait(views.ask(cameras()[0]), timeout=120)  # the worker started and the plate read
    before = views.answered
    numbers = [views.ask(cam) for cam in cameras()]
    picture = views.wait(numbers[-1], timeout=60)
    assert picture.request == numbers[-1]
    assert_same(picture, expected(here, cameras()[-1]))
    rendered = views.answered - before
    assert rendered < len(numbers), f"{rendered} of {len(numbers)} requests were rendered"


def test_outside_the_zone_says_why_and_shows_no_picture(views, here):
    """A camera 2 cm to the side (the zone reaches 1 cm): the viewer's sentence, no picture;
    back inside, a picture again."""
    views.wait(views.ask(cameras()[0]), timeout=120)
    outside = ps.camera((0.02, 0.0, 0.3), scale=SCALE)
    picture = views.wait(views.ask(outside), timeout=60)
    assert picture.rgba is None and picture.where == here.where(outside)
    assert "outside" in picture.where and "mm" in picture.where, picture.where
    picture = views.wait(views.ask(cameras()[2]), timeout=60)
    assert_same(picture, expected(here, cameras()[2]))


def test_a_killed_worker_restarts_at_the_next_request_with_its_settings(views, here):
    """The worker killed (SIGKILL, as the system kills a process out of memory): the next
    request starts another, which holds the same plate with the same exposure."""
    views.wait(views.ask(cameras()[0]), timeout=120)
    first = views.process
    os.killpg(first.pid, signal.SIGKILL)
    first.wait()
    picture = views.wait(views.ask(cameras()[3]), timeout=120)
    assert views.starts == 2 and views.process.pid != first.pid
    assert_same(picture, expected(here, cameras()[3]))


def test_closing_unlinks_the_shared_segment_and_refuses_more(plate_files):
    views = Views(plate_files, recording=DIGEST, supersample=1)
    views.wait(views.ask(dataclasses.replace(cameras()[0])), timeout=120)
    name = views.shared_name
    views.close()
    with pytest.raises(InputError, match=name):
        SharedView.attach(name)
    with pytest.raises(RuntimeError, match="closed"):
        views.ask(cameras()[0])


def test_a_plate_of_another_recording_is_refused_by_name(plate_files):
    """Views that expect another scene's recording: the answer is the worker's refusal,
    naming the file, and no picture."""
    with Views(plate_files, recording="ffff0000", supersample=1) as views:
        picture = views.wait(views.ask(cameras()[0]), timeout=120)
        assert picture.rgba is None and "ffff0000" in picture.error, picture
        assert str(plate_files[0]) in picture.error
