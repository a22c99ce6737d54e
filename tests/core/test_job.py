"""The typed job both sides of the worker share: checked when it is made, as the public API
is (one InputError naming the field and what it may be), carried across the process boundary
as plain data and made again there, and never a guess where a field is missing."""

import copy
import math
import sys

import numpy as np
import pytest

from holo_core.job import (
    CameraRoute,
    Job,
    Output,
    Plan,
    PlateRoute,
    Radiance,
    Report,
    Result,
    pass_file,
)
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.mesh import Mesh
from holo_core.scene.plate import Plate, ViewingZone
from holo_core.validate import InputError

TRIANGLE = Mesh(
    vertices=np.array([[0, 0, -1], [0.1, 0, -1], [0, 0.1, -1.0]]),
    triangles=np.array([[0, 1, 2]]),
    colours=np.ones((3, 3)),
)


def camera():
    return Camera(matrix_world=look_at((0, 0, 1), (0, 0, 0), up=(0, 1, 0)), resolution=(32, 24))


def plate_job(tmp_path, **route):
    plate = Plate(
        matrix_world=np.eye(4),
        width=0.2,
        height=0.2,
        zone=ViewingZone(centre=(0, 0, 1), half_extents=(0.05, 0.05, 0.05)),
    )
    return Job(
        camera=camera(),
        points=(TRIANGLE,),
        output=Output(folder=tmp_path, frame=3),
        route=PlateRoute(plate=plate, holograms=(tmp_path / "h.exr",), **route),
    )


def camera_job(tmp_path, **route):
    return Job(
        camera=camera(),
        triangles=(TRIANGLE,),
        output=Output(folder=tmp_path),
        route=CameraRoute(**route),
    )


def test_a_job_crosses_the_process_boundary_as_plain_data(tmp_path):
    """to_dict gives strings, numbers, lists, dicts and arrays only; from_dict makes the same
    job again (its plain data equal), for both routes."""
    radiance = Radiance(
        command=("blender", "-b"), image=tmp_path / "r.exr", folder=tmp_path, camera=camera()
    )
    for job in (
        plate_job(tmp_path, wavelength=2e-6, seed=4),
        Job(
            camera=camera(),
            triangles=(TRIANGLE,),
            radiance=radiance,
            output=Output(folder=tmp_path, border=(1, 2, 30, 20), depth_unit=0.01),
            route=CameraRoute(samples=4, speckle="LOOKS"),
        ),
    ):
        plain = job.to_dict()
        kinds = set()

        def walk(v, kinds=kinds):
            kinds.add(type(v).__name__)
            for w in v.values() if isinstance(v, dict) else v if isinstance(v, list) else ():
                walk(w, kinds)

        walk(plain)
        assert kinds <= {"dict", "list", "str", "int", "float", "bool", "NoneType", "ndarray"}, (
            kinds
        )
        again = Job.from_dict(copy.deepcopy(plain))
        assert type(again.route) is type(job.route)
        assert _same(again.to_dict(), plain)
    assert again.output.pass_path == pass_file(tmp_path, 1) == tmp_path / "holo_pass_0001.exr"


def _same(a, b):
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b)
    return a == b


def _set(*keys, value):
    """An edit of the job's plain data: ``keys`` lead to the field, ``value`` replaces it
    (the key is removed for value=DROP)."""

    def edit(d):
        for k in keys[:-1]:
            d = d[k]
        if value is DROP:
            del d[keys[-1]]
        else:
            d[keys[-1]] = value

    return edit


DROP = object()
NAN = math.nan

# Malformed jobs as the worker receives them: each must end in the project's error naming
# its field, never in another exception or a job accepted (exposure -1, depth unit -1, an
# unknown mode, supersample 0 and frame -1 once ran).
CAMERA = [
    ("exposure -1 (a negative pass)", _set("route", "exposure", value=-1.0), "exposure"),
    ("exposure 0", _set("route", "exposure", value=0.0), "exposure"),
    ("exposure nan", _set("route", "exposure", value=NAN), "exposure"),
    ("exposure a string", _set("route", "exposure", value="1"), "exposure"),
    ("depth unit -1 (negative depths)", _set("output", "depth_unit", value=-1.0), "depth_unit"),
    ("depth unit 0", _set("output", "depth_unit", value=0.0), "depth_unit"),
    ("an unknown mode (ran as plate)", _set("route", "kind", value="SPHERE"), "route kind"),
    ("no mode", _set("route", "kind", value=DROP), "route kind"),
    ("route null", _set("route", value=None), "route"),
    ("supersample 0", _set("route", "supersample", value=0), "supersample"),
    ("supersample 1.5", _set("route", "supersample", value=1.5), "supersample"),
    ("supersample 17", _set("route", "supersample", value=17), "supersample"),
    ("frame -1 (holo_pass_-001.exr)", _set("output", "frame", value=-1), "frame"),
    ("frame 1.5", _set("output", "frame", value=1.5), "frame"),
    ("frame a string", _set("output", "frame", value="1"), "frame"),
    ("samples 0", _set("route", "samples", value=0), "samples"),
    ("samples true", _set("route", "samples", value=True), "samples"),
    ("speckle unknown", _set("route", "speckle", value="FAST"), "speckle"),
    ("seed -1", _set("route", "seed", value=-1), "seed"),
    ("seed nan", _set("route", "seed", value=NAN), "seed"),
    (
        "a plate route's field on a camera",
        _set("route", "composition", value="mean"),
        "route has no field 'composition'",
    ),
    ("no camera", _set("camera", value=DROP), "job lacks 'camera'"),
    ("camera resolution 0", _set("camera", "resolution", value=[0, 10]), "resolution"),
    ("camera pose nan", _set("camera", "matrix_world", value=np.full((4, 4), NAN)), "matrix_world"),
    ("camera with an unknown field", _set("camera", "iso", value=100), "camera has no field 'iso'"),
    ("no output", _set("output", value=DROP), "job lacks 'output'"),
    ("output folder null", _set("output", "folder", value=None), "folder"),
    ("output render a string", _set("output", "render", value="no"), "render"),
    ("a camera hologram without its pass", _set("output", "render", value=False), "output render"),
    ("border left of its start", _set("output", "border", value=[10, 0, 5, 4]), "border"),
    ("border beyond the camera", _set("output", "border", value=[0, 0, 64, 24]), "border"),
    ("pass key a number", _set("output", "pass_key", value=7), "pass_key"),
    ("points a string", _set("points", value="cube"), "points"),
    ("triangles of nan", _set("triangles", 0, "vertices", value=np.full((3, 3), NAN)), "vertices"),
    (
        "a mesh without triangles",
        _set("triangles", 0, "triangles", value=DROP),
        r"triangles\[0\] lacks 'triangles'",
    ),
    ("no emitters", _set("triangles", value=[]), "points and triangles"),
    ("an unknown field", _set("crash", value=1), "job has no field 'crash'"),
    (
        "radiance command empty",
        _set("radiance", value={"command": [], "image": "r.exr", "folder": "/tmp", "camera": {}}),
        "radiance command",
    ),
    ("job not a dict", lambda d: d.clear() or d.update(job=[1]), "job has no field 'job'"),
]
PLATE = [
    ("memory budget 0", _set("route", "memory_budget", value=0), "memory_budget"),
    ("disk budget nan", _set("route", "disk_budget", value=float("nan")), "disk_budget"),
    ("wavelength -1", _set("route", "wavelength", value=-1.0), "wavelength"),
    ("composition unknown", _set("route", "composition", value="median"), "composition"),
    ("opacity threshold 2", _set("route", "opacity_threshold", value=2.0), "opacity_threshold"),
    ("no holograms", _set("route", "holograms", value=[]), "holograms"),
    ("holograms a string", _set("route", "holograms", value="h.exr"), "holograms"),
    ("a hologram path a number", _set("route", "holograms", value=[3]), "holograms"),
    ("record a string", _set("route", "record", value="yes"), "record"),
    ("no plate", _set("route", "plate", value=DROP), "route lacks 'plate'"),
    ("plate width -1", _set("route", "plate", "width", value=-1.0), "plate width"),
    (
        "a zone behind the plate",
        _set("route", "plate", "zone", "centre", value=[0, 0, -1]),
        "viewing zone must lie in front",
    ),
    (
        "radiance for a current plate",
        lambda d: (
            d["route"].update(record=False)
            or d.update(
                radiance={
                    "command": ["blender"],
                    "image": "r.exr",
                    "folder": "/tmp",
                    "camera": d["camera"],
                }
            )
        ),
        "radiance",
    ),
]


@pytest.mark.parametrize("what, edit, field", CAMERA + PLATE, ids=[c[0] for c in CAMERA + PLATE])
def test_a_malformed_job_is_refused_naming_its_field(tmp_path, what, edit, field):
    job = plate_job(tmp_path) if (what, edit, field) in PLATE else camera_job(tmp_path)
    plain = job.to_dict()
    edit(plain)
    with pytest.raises(InputError, match=field):
        Job.from_dict(plain)


def test_each_case_edits_a_job_that_is_accepted_unedited(tmp_path):
    """Each refusal above is its edit's own: the job unedited is accepted, and every edit
    changes its plain data."""
    for what, edit, field in CAMERA + PLATE:
        job = plate_job(tmp_path) if (what, edit, field) in PLATE else camera_job(tmp_path)
        plain = job.to_dict()
        Job.from_dict(plain)
        edited = copy.deepcopy(plain)
        edit(edited)
        assert repr(edited) != repr(plain), what


def test_the_same_refusals_hold_for_a_job_made_in_python(tmp_path):
    """The Python constructors check what from_dict checks: exposure -1, frame -1,
    supersample 0, depth unit -1 and a route that is neither."""
    for make, field in [
        (lambda: CameraRoute(exposure=-1.0), "exposure"),
        (lambda: Output(folder=tmp_path, frame=-1), "frame"),
        (lambda: CameraRoute(supersample=0), "supersample"),
        (lambda: Output(folder=tmp_path, depth_unit=-1.0), "depth_unit"),
        (
            lambda: Job(
                camera=camera(), route="PLATE", points=(TRIANGLE,), output=Output(folder=tmp_path)
            ),
            "route",
        ),
        (lambda: PlateRoute(plate=None, holograms=()), "plate"),
    ]:
        with pytest.raises(InputError, match=field):
            make()


def test_a_result_carries_its_report_and_leaves_the_view_to_the_pass_file(tmp_path):
    report = Report(
        warnings=["a", "b"],
        seconds=1.5,
        looks=16,
        speckle_contrast=0.01,
        plan=Plan(
            aperture=0.01,
            wavelengths=(1e-6, 1.01e-6),
            resolution_limit_px=0.5,
            pupil_samples=(64, 48),
            layers=2,
        ),
    )
    result = Result(
        recorded=(tmp_path / "h.exr",), pass_path=tmp_path / "p.exr", report=report, view=object()
    )
    plain = result.to_dict()
    assert "view" not in plain and plain["report"]["plan"]["layers"] == 2
    back = Result.from_dict(plain)
    assert back.view is None and back.report == report and back.recorded == result.recorded
    assert back.report.warnings == ("a", "b")


def test_importing_the_job_loads_no_opencl():
    """The parent (Blender's process) builds jobs: the contract pulls in no driver."""
    import subprocess

    code = (
        "import sys, holo_core.job, holo_core.worker; "
        "print([m for m in sys.modules if m.split('.')[0] in ('pyopencl', 'pyfftw') "
        "or m.startswith('holo_core.opencl')])"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "[]", out
