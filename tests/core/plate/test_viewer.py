"""A plate held for a moving camera (holo_core.plate.viewer.PlateViewer): its full view is
render_view's (render_set_view's for a set) of the same looks and settings, while the camera
wanders and returns (the plans it keeps change nothing); its coarse view is close to the full
one; it says in words where a camera's pupil leaves the zone and refuses a view from there;
it refuses a plate of another scene by name and reads a file again when it changes.

The plate scene (tests/plate_scene.py) at 160x90, a 6 cm plate halfway, two coded looks for a
zone 1 cm around the centre camera's pupil (the set: two parts along a 6 cm dolly).
"""

import dataclasses
import os
import warnings

import numpy as np
import plate_scene as ps
import pytest

from holo_core import PlateViewer
from holo_core.io.hologram import HologramFileError, write_hologram
from holo_core.plate.looks import record_looks
from holo_core.plate.parts import record_set
from holo_core.plate.path import parts_along
from holo_core.plate.view import OutsideZoneWarning, render_set_view, render_view
from holo_core.plate.viewer import OutsideZoneError
from holo_core.scene.plate import Plate
from holo_core.validate import InputError

PLATE = Plate(matrix_world=np.eye(4), width=0.06, height=0.06)
SCALE = 0.25  # 160x90
DIGEST = "0123abcd"


def psnr_db(a, b, inside) -> float:
    """PSNR [dB] of ``a`` against ``b`` over ``inside``, peak: ``b``'s brightest there."""
    err = a[inside] - b[inside]
    return float(20 * np.log10(b[inside].max() / max(np.sqrt(np.mean(err**2)), 1e-30)))


@pytest.fixture(scope="module")
def looks():
    """Two coded looks of the plate, named by a recording digest."""
    return record_looks(
        ps.meshes(),
        looks=2,
        plate=PLATE,
        camera=ps.camera("centre", scale=SCALE),
        zone_margin=0.01,
        recording=DIGEST,
    )


def wandering():
    """Cameras inside the zone: sideways, up, nearer, the aim turned, and back again."""
    eyes = [(0.0, 0.0, 0.3), (0.004, 0.0, 0.3), (0.0, -0.003, 0.3), (0.002, 0.002, 0.295)]
    cams = [ps.camera(e, scale=SCALE) for e in eyes]
    turned = ps.look_at(np.array(eyes[0]), ps.TARGET + [0.01, 0.005, 0.0], up=(0, 1, 0))
    cams.append(dataclasses.replace(cams[0], matrix_world=turned))
    return cams + cams[:2]


def test_full_views_are_render_views_while_the_camera_wanders(looks):
    """Each full view is render_view's of the same looks and settings within 50 dB PSNR of
    colour and alpha (the viewer's sizes, rounded up with slack, hold the same light; the
    non-uniform FFT's own accuracy is about 1e-4), first visits and revisits alike."""
    with PlateViewer(looks, scene=DIGEST, supersample=2) as viewer:
        for cam in wandering():
            assert viewer.contains(cam), viewer.where(cam)
            ours = viewer.view(cam)
            theirs = render_view(looks, cam, supersample=2)
            assert_same_view(ours, theirs)


def assert_same_view(ours, theirs):
    """Colour and alpha within 50 dB PSNR of ``theirs``, depth within 1e-3 of itself where
    both see a surface (0.6 mm at 0.6 m: the two-wavelength phase's depth is the finest of the
    three)."""
    everywhere = np.ones(theirs.alpha.shape, bool)
    for name in ("rgb", "alpha"):
        q = psnr_db(getattr(ours, name), getattr(theirs, name), everywhere)
        assert q >= 50, (name, q)
    seen = (ours.alpha > 0.5) & (theirs.alpha > 0.5)
    gap = (np.abs(ours.depth[seen] - theirs.depth[seen]) / theirs.depth[seen]).max()
    assert gap <= 1e-3, gap


def blocks(a, n=4):
    """The means of ``a``'s n×n pixel blocks (a low-pass that averages the speckle)."""
    h, w = (m - m % n for m in a.shape[:2])
    return a[:h, :w].reshape(h // n, n, w // n, n, *a.shape[2:]).mean((1, 3))


def test_a_coarse_view_is_close_to_the_full_one(looks):
    """The coarse view (one look, one sample a pixel) against the full (two looks,
    supersampled 2x): the silhouette (alpha > 0.5) agrees on IoU >= 0.9, the mean radiance
    inside both within 10 %, and their 4x4 blocks' colour within 12 dB PSNR, a loose bound:
    one look unsupersampled keeps its speckle (10.9 dB pixel by pixel here, 15.8 dB in
    blocks)."""
    cam = ps.camera("centre", scale=SCALE)
    with PlateViewer(looks, supersample=2) as viewer:
        full, quick = viewer.view(cam), viewer.view(cam, coarse=True)
    assert quick.info["coarse"] and quick.rgb.shape == full.rgb.shape
    a, b = quick.alpha > 0.5, full.alpha > 0.5
    iou = (a & b).sum() / (a | b).sum()
    assert iou >= 0.9, iou
    inside = (quick.alpha >= 1) & (full.alpha >= 1)
    ratio = quick.rgb[inside].mean() / full.rgb[inside].mean()
    assert abs(ratio - 1) <= 0.1, ratio
    both = blocks(inside.astype(float)) >= 1
    q = psnr_db(blocks(quick.rgb), blocks(full.rgb), both)
    assert q >= 12, q


def test_where_says_how_far_and_which_way_a_pupil_leaves_the_zone(looks):
    """Inside: None. Beside the zone (2 cm to its +x), nearer the plate, and behind it: a
    sentence naming the way and the distance; a view from there is refused with it."""
    viewer = PlateViewer(looks)
    zone = looks[0].zone
    assert viewer.where(ps.camera("centre", scale=SCALE)) is None
    pupil = ps.camera("centre", scale=SCALE).aperture_diameter
    x = zone.centre[0] + zone.half_extents[0] + 0.02  # 2 cm beyond the side, the pupil's rim
    beside = ps.camera((x - pupil / 2, 0.0, 0.3), scale=SCALE)
    why = viewer.where(beside)
    assert not viewer.contains(beside)
    assert "+x (right) side" in why and "20 mm" in why, why
    nearer = ps.camera((0.0, 0.0, 0.25), scale=SCALE)
    assert "nearer the plate" in viewer.where(nearer), viewer.where(nearer)
    behind = dataclasses.replace(
        beside, matrix_world=ps.look_at(np.array([0.0, 0.0, -0.5]), ps.TARGET, up=(0, 1, 0))
    )
    assert "in front of the hologram" in viewer.where(behind)
    with pytest.raises(OutsideZoneError, match="20 mm past its"):
        viewer.view(beside)
    viewer.close()
    with pytest.raises(InputError, match="closed"):
        viewer.view(ps.camera("centre", scale=SCALE))


def test_a_plate_of_another_scene_is_refused_by_name(looks, tmp_path):
    """In memory and as files: another recording's plate is refused, the file named."""
    with pytest.raises(InputError, match="not 9999"):
        PlateViewer(looks, scene="9999")
    paths = [tmp_path / f"look{k}.exr" for k in range(2)]
    for path, h in zip(paths, looks):
        write_hologram(path, h)
    assert PlateViewer(paths, scene=DIGEST).recording == DIGEST
    with pytest.raises(HologramFileError, match=r"look0\.exr.*not 9999"):
        PlateViewer(paths, scene="9999")
    with pytest.raises(InputError, match="no setting 'speed'"):
        PlateViewer(looks, speed=2)


def test_a_file_that_changes_is_read_again_and_one_that_vanishes_is_named(looks, tmp_path):
    """A look's file rewritten with another recording under the viewer: its next view
    refuses it naming the file; written again (its samples doubled), the view is render_view's
    of the new samples; removed: the
    view fails naming the file."""
    paths = [tmp_path / f"look{k}.exr" for k in range(2)]
    for path, h in zip(paths, looks):
        write_hologram(path, h)
    cam = ps.camera("centre", scale=SCALE)
    viewer = PlateViewer(paths, scene=DIGEST, supersample=1)
    first = viewer.view(cam)
    write_hologram(paths[1], dataclasses.replace(looks[1], recording="ffff"))
    with pytest.raises(HologramFileError, match=r"look1\.exr: holds recording ffff"):
        viewer.view(cam)
    scaled = dataclasses.replace(looks[1], object_wave=looks[1].object_wave * 2)
    write_hologram(paths[1], scaled)
    os.utime(paths[1], ns=(1, 1))  # another identity even on a coarse clock
    again = viewer.view(cam)
    theirs = render_view([looks[0], scaled], cam, supersample=1)
    assert_same_view(again, theirs)
    assert not np.array_equal(again.rgb, first.rgb)
    paths[0].unlink()
    with pytest.raises(HologramFileError, match=r"look0\.exr"):
        viewer.view(cam)


def test_a_plate_set_is_viewed_from_the_part_that_holds_the_pupil(tmp_path):
    """A set of two parts along a 6 cm dolly, in memory and from its folder: each end's view
    is render_set_view's (within 50 dB); a camera beyond the set's ends is said, naming the
    nearest part."""
    cams = [ps.camera((x, 0.0, 0.3), scale=SCALE) for x in (-0.03, 0.0, 0.03)]
    every = np.concatenate([m.vertices for m in ps.meshes()])
    parts = parts_along(
        cams, np.array([every.min(0), every.max(0)]), distance=0.32, stretch=0.04, margin=0.005
    )
    plates = record_set(ps.meshes(), parts, looks=2, seed=3, folder=tmp_path / "set")
    for source in (plates, tmp_path / "set"):
        with PlateViewer(source, scene=plates.recording, supersample=1) as viewer:
            for cam in (cams[0], cams[-1]):
                with warnings.catch_warnings():
                    warnings.simplefilter("error", OutsideZoneWarning)
                    ours = viewer.view(cam)
                assert_same_view(ours, render_set_view(plates, cam, supersample=1))
            far = ps.camera((0.2, 0.0, 0.3), scale=SCALE)
            assert "nearest, part 1" in viewer.where(far), viewer.where(far)


def test_the_widget_says_what_it_needs_and_its_moves_keep_the_camera(looks):
    """Without ipywidgets the widget is refused saying how to install it; the sliders' move
    (1 cm across, 5° of yaw) puts the camera 1 cm along its own x axis and turns its view
    axis by 5°."""
    from holo_core.plate.viewer_widget import moved

    cam = ps.camera("centre", scale=SCALE)
    try:
        import ipywidgets  # noqa: F401
    except ImportError:
        with pytest.raises(InputError, match="pip install ipywidgets"):
            PlateViewer(looks).widget(cam)
    there = moved(cam, across=0.01, yaw=5.0)
    assert np.allclose(there.position - cam.position, 0.01 * cam.rotation[:, 0], atol=1e-12)
    turn = np.degrees(np.arccos(np.clip(there.rotation[:, 2] @ cam.rotation[:, 2], -1, 1)))
    assert abs(turn - 5.0) < 1e-9, turn
