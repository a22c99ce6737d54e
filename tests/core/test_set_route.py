"""A plate set as a job's route (holo_core.job.SetRoute, run by holo_core.runner): it crosses
the process boundary as plain data, records the set's parts into its folder once, views each
frame from the part whose zone holds its pupil, and refuses a damaged part by name. The plate
scene (tests/plate_scene.py) at 160x90, a 6 cm dolly served by two parts of 4 cm."""

import copy
import json

import numpy as np
import plate_scene as ps
import pytest

from holo_core import runner
from holo_core.io.hologram import HologramFileError
from holo_core.io.kept_plates import KeptPlates
from holo_core.io.plate_set import MANIFEST, read_plate_set
from holo_core.job import Job, Output, SetRoute
from holo_core.plate.path import part_for, parts_along
from holo_core.plate.view import render_view
from holo_core.validate import InputError

XS = (-0.03, 0.0, 0.03)  # [m] the dolly's ends and middle


def cameras():
    return [ps.camera((x, 0.0, 0.3), scale=0.25) for x in XS]


def parts():
    every = np.concatenate([m.vertices for m in ps.meshes()])
    return parts_along(
        cameras(), np.array([every.min(0), every.max(0)]), distance=0.32, stretch=0.04, margin=0.005
    )


def job(folder, cam, frame, **route):
    return Job(
        camera=cam,
        points=tuple(ps.meshes()),
        output=Output(folder=folder, frame=frame),
        route=SetRoute(parts=parts(), folder=folder / "set", looks=2, seed=3, **route),
    )


def test_a_set_job_crosses_the_process_boundary_as_plain_data(tmp_path):
    """to_dict gives plain data; from_dict makes the same route again, its parts' plates,
    zones, stretches and frames equal; a malformed part is refused naming it."""
    j = job(tmp_path, cameras()[0], 1, outside="fail", memory_budget=2.0**30)
    plain = j.to_dict()
    again = Job.from_dict(copy.deepcopy(plain))
    assert isinstance(again.route, SetRoute) and again.route.outside == "fail"
    assert len(again.route.parts) == len(j.route.parts) == 2
    for a, b in zip(again.route.parts, j.route.parts):
        assert np.array_equal(a.plate.matrix_world, b.plate.matrix_world)
        za, zb = a.plate.zone, b.plate.zone
        assert (za.centre, za.half_extents, za.pupil, za.pixel) == (
            zb.centre,
            zb.half_extents,
            zb.pupil,
            zb.pixel,
        )
        assert a.stretch == b.stretch and a.frames == b.frames
    bad = copy.deepcopy(plain)
    bad["route"]["parts"][1]["stretch"] = [0.03, 0.0]
    with pytest.raises(InputError, match="stretch must run forwards"):
        Job.from_dict(bad)
    bad = copy.deepcopy(plain)
    bad["route"]["parts"] = []
    with pytest.raises(InputError, match="parts must be a non-empty list"):
        Job.from_dict(bad)
    with pytest.raises(InputError, match="outside"):
        job(tmp_path, cameras()[0], 1, outside="maybe")


def test_each_frame_is_made_from_the_part_that_holds_its_pupil_and_recorded_once(tmp_path):
    """The first frame's job records the set (its manifest the job's recorded file); the
    others, record=False, read it; each frame's pass is its part's view bit for bit (that
    part holding the pupil wholly), and the two ends come from different parts; the pass
    file is written. Recording the
    set again (record=True, a second render) writes nothing."""
    cams = cameras()
    first = runner.run(job(tmp_path, cams[0], 1))
    assert first.recorded == (tmp_path / "set" / MANIFEST,)
    stamps = {f.name: f.stat().st_mtime_ns for f in (tmp_path / "set").glob("*.exr")}
    plates = read_plate_set(tmp_path / "set")
    kept = KeptPlates()
    chosen = []
    for frame, cam in enumerate(cams, 1):
        result = (
            first if frame == 1 else runner.run(job(tmp_path, cam, frame, record=False), kept=kept)
        )
        k, beyond = part_for(plates, cam)
        assert beyond == 0, beyond
        chosen.append(k)
        assert result.pass_path.is_file()
        ours = result.view
        theirs = render_view(list(plates.part_looks(k)), cam, supersample=2)
        assert np.array_equal(ours.rgb, theirs.rgb), np.abs(ours.rgb - theirs.rgb).max()
        assert np.array_equal(ours.alpha, theirs.alpha)
    assert chosen[0] != chosen[-1], chosen
    runner.run(job(tmp_path, cams[1], 2))
    assert {f.name: f.stat().st_mtime_ns for f in (tmp_path / "set").glob("*.exr")} == stamps


def test_a_damaged_part_is_refused_by_name_and_a_foreign_set_is_never_viewed(tmp_path):
    """A part's file changed on disk: the job fails naming the part and its file, never
    viewing zeros. A folder holding a set of other parts, or of another recording, under the
    job's name: refused."""
    cams = cameras()
    runner.run(job(tmp_path, cams[0], 1))
    manifest = json.loads((tmp_path / "set" / MANIFEST).read_text())
    name = manifest["parts"][1]["files"][0]["name"]
    path = tmp_path / "set" / name
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(HologramFileError, match=f"part 1 \\({name}\\) is damaged"):
        runner.run(job(tmp_path, cams[2], 3, record=False))
    other = job(tmp_path, cams[0], 1, record=False)
    fewer = SetRoute(parts=other.route.parts[:1], folder=other.route.folder, record=False)
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(HologramFileError, match="not this job's 1"):
        runner.run(Job(camera=cams[0], output=other.output, route=fewer))
    named = job(tmp_path, cams[0], 1, record=False, recording="cd34")
    with pytest.raises(HologramFileError, match="not cd34"):
        runner.run(named)


def test_a_set_recorded_under_the_callers_name_is_read_under_it(tmp_path):
    """A route's recording names the set in its manifest (set_current tells it whole), and
    resuming or reading matches that name, not the digest of the emitters."""
    from holo_core.io.plate_set import set_current

    cams = cameras()
    assert not set_current(tmp_path / "set", "ab12", 2)
    runner.run(job(tmp_path, cams[0], 1, recording="ab12"))
    assert set_current(tmp_path / "set", "ab12", 2)
    assert not set_current(tmp_path / "set", "ab12", 3)
    assert not set_current(tmp_path / "set", "cd34", 2)
    assert read_plate_set(tmp_path / "set").recording == "ab12"
    view = runner.run(job(tmp_path, cams[2], 3, record=False, recording="ab12")).view
    assert view.alpha.max() == 1
