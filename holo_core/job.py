"""The typed job both sides of the worker share, and its result.

A :class:`Job` is what Blender's side (or a script, a bench, a test) asks of the pipeline: the
scene's nouns (emitter meshes in world metres, the camera), a route with its settings
(:class:`CameraRoute`: a camera hologram made for this view; :class:`PlateRoute`: the plate's
holograms recorded, or read when current, and viewed; :class:`SetRoute`: a plate set's parts
along the camera's path, likewise), the :class:`Output` (the frame's pass)
and, with Lighting: Scene, the renderer that colours the emitters (:class:`Radiance`). A
:class:`Result` is what comes back: the view, the files written and a :class:`Report` of
what the renderer said. Each is a frozen dataclass checked when it is made
(:class:`~holo_core.validate.InputError` naming the field and what it may be);
``to_dict``/``from_dict`` carry them across the process boundary as plain data (strings,
numbers, lists, dicts and NumPy arrays), and ``from_dict`` refuses what it does not know.

Importing this module loads no OpenCL driver: the parent's handle (:mod:`holo_core.worker`)
builds and sends jobs, the child (:mod:`holo_core.runner`) runs them.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import validate
from .scene.camera import Camera
from .scene.mesh import Mesh
from .scene.plate import Plate, ViewingZone
from .scene.plate_set import PathPart
from .validate import MAX_SAMPLES, MAX_SUPERSAMPLE, InputError, shown
from .view import RenderResult

MAX_FRAME = 1048574  # Blender's last frame
SPECKLE = {"EXACT": "incoherent", "LOOKS": "object_wave"}  # the camera hologram's way per setting


def pass_file(folder, frame: int) -> Path:
    """Frame ``frame``'s holographic pass in ``folder``: ``holo_pass_NNNN.exr``, one file per
    frame and nothing shared between frames (farm workers never write the same file)."""
    return Path(folder) / f"holo_pass_{frame:04d}.exr"


# --- the route: how the pass is made ----------------------------------------------------------


@dataclass(frozen=True, slots=True, kw_only=True)
class _Route:
    """What both routes take: ``supersample`` (fine pixels per pixel per axis), ``exposure``
    (a linear factor on the radiance, > 0) and ``seed`` (the random phases)."""

    supersample: int = 2
    exposure: float = 1.0
    seed: int = 0

    def __post_init__(self):
        _set(
            self,
            "supersample",
            validate.integer("supersample", self.supersample, 1, MAX_SUPERSAMPLE),
        )
        _set(self, "exposure", validate.exposure(_real("exposure", self.exposure)))
        _set(self, "seed", validate.seed(self.seed))


@dataclass(frozen=True, slots=True, kw_only=True)
class CameraRoute(_Route):
    """A camera hologram recorded for the job's camera (:mod:`holo_core.camera`): no plate and
    no hologram file, made again for every pass.

    samples : looks averaged against speckle (the progressive looks' count, 'LOOKS')
    speckle : 'EXACT' (the looks' limit in one pass) or 'LOOKS' (random-phase looks)
    supersample, exposure, seed : as every route (the seed: the looks' random phases)
    """

    samples: int = 16
    speckle: str = "EXACT"

    def __post_init__(self):
        _Route.__post_init__(self)
        _set(self, "samples", validate.integer("samples", self.samples, 1, MAX_SAMPLES))
        validate.choice("speckle", self.speckle, tuple(SPECKLE))


@dataclass(frozen=True, slots=True, kw_only=True)
class PlateRoute(_Route):
    """The plate's holograms (one file per iteration), recorded unless they are current, and
    the view of them from the job's camera (:func:`holo_core.plate.view.render_view`).

    plate : the :class:`~holo_core.scene.plate.Plate`; with its viewing zone it is a scene
        asset (its samples follow the zone and its views' sharpness, the camera sizing
        nothing)
    holograms : the iterations' files [paths]: coded looks of one seed where their count
        allows, else seeds ``seed``, ``seed + 1``, ...
    record : record them (False: they are current, and are read)
    memory_budget, disk_budget : [bytes] what the recording may hold in memory and its files
        on disk, or None (no limit): a plate that needs more is refused before any work, with
        its sizes
    scheduler : a Dask scheduler's address (``tcp://host:8786``) for a plate recorded tile
        by tile, or None (``DASK_SCHEDULER_ADDRESS``, else a local cluster); a plate is
        recorded so, into NAME.zarr beside each NAME.exr, when one look of it exceeds the
        memory budget or the host's memory
    wavelength : the recording's wavelength [m], or None (chosen by the planner)
    composition : 'mean' or 'max' of the iterations' views
    opacity_threshold : the view's coverage taken as opaque, in [0, 1]
    recording : the digest of the recording the holograms are (the name the caller knows
        them by), written into them when they are recorded and checked when they are read:
        another recording's plate under their names is refused, never viewed; '' (none: an
        imported plate, read as it is)
    phases : 'random' or 'smooth': the emitters' phases
        (:func:`holo_core.plate.recording.prepare_plate`; smooth: a display hologram's)
    supersample, exposure, seed : as every route (the seed: the recording's random phases; a
        supersampling below the view's speckle Nyquist rate is said in the log, not raised)
    """

    plate: Plate
    holograms: tuple
    record: bool = True
    memory_budget: float | None = None
    disk_budget: float | None = None
    scheduler: str | None = None
    wavelength: float | None = None
    composition: str = "mean"
    opacity_threshold: float = 0.5
    recording: str = ""
    phases: str = "random"

    def __post_init__(self):
        _Route.__post_init__(self)
        _set(self, "phases", validate.choice("phases", self.phases, ("random", "smooth")))
        if not isinstance(self.plate, Plate):
            raise InputError(f"plate must be a Plate; got {type(self.plate).__name__}")
        _set(self, "holograms", _paths("holograms", self.holograms))
        if not self.holograms:
            raise InputError("holograms must name at least one file (one per iteration)")
        _set(self, "record", _flag("record", self.record))
        for name in ("memory_budget", "disk_budget"):
            value = getattr(self, name)
            if value is not None and not validate.finite(name, _real(name, value), "bytes") > 0:
                raise InputError(f"{name} must be > 0 [bytes] or None; got {shown(value)}")
        if self.scheduler is not None and not (
            isinstance(self.scheduler, str) and self.scheduler.strip()
        ):
            raise InputError(
                f"scheduler must be a Dask scheduler's address (tcp://host:port) "
                f"or None; got {self.scheduler!r}"[:200]
            )
        if self.wavelength is not None:
            _set(
                self,
                "wavelength",
                validate.length("wavelength", _real("wavelength", self.wavelength)),
            )
        _check_composition(self)
        validate.digest("recording", self.recording)


@dataclass(frozen=True, slots=True, kw_only=True)
class SetRoute(_Route):
    """A plate set along the camera's path (:mod:`holo_core.plate.parts`): its parts recorded
    into one folder unless they are there, and the view of the job's camera from the part
    whose zone holds its pupil (:func:`holo_core.plate.view.render_set_view`).

    parts : the set's :class:`~holo_core.scene.plate_set.PathPart` (each a plate with its
        zone, its stretch of path [m] and frames; :func:`holo_core.plate.path.parts_along`)
    folder : the set's folder (:mod:`holo_core.io.plate_set`: ``plate_set.json`` and each
        part's looks); a recording that stopped resumes there, and a folder of another
        recording is refused
    looks : coded looks a part (the iterations)
    record : record the parts the folder lacks (False: they are all there, and are read)
    memory_budget, disk_budget : [bytes] what one part's recording may hold in memory and the
        whole set on disk, or None (no limit): a set that needs more is refused before any
        work, with its sizes
    composition, opacity_threshold : as :class:`PlateRoute`'s
    outside : a camera whose pupil lies outside every part: 'warn' (viewed from the nearest
        part) or 'fail'
    recording : the digest the caller names the set by, written into its manifest when it is
        recorded and checked when it is read ('' none: the digest of its inputs)
    supersample, exposure, seed : as every route (the seed: the set's random phases)
    """

    parts: tuple
    folder: Path
    looks: int = 2
    record: bool = True
    memory_budget: float | None = None
    disk_budget: float | None = None
    composition: str = "mean"
    opacity_threshold: float = 0.5
    outside: str = "warn"
    recording: str = ""

    def __post_init__(self):
        _Route.__post_init__(self)
        parts = self.parts
        if (
            isinstance(parts, PathPart)
            or not isinstance(parts, (list, tuple))
            or not parts
            or not all(isinstance(p, PathPart) for p in parts)
        ):
            raise InputError("parts must be a non-empty list of PathPart (parts_along)")
        _set(self, "parts", tuple(parts))
        _set(self, "folder", _path("folder", self.folder))
        _set(self, "looks", validate.integer("looks", self.looks, 1, MAX_SAMPLES))
        _set(self, "record", _flag("record", self.record))
        for name in ("memory_budget", "disk_budget"):
            value = getattr(self, name)
            if value is not None and not validate.finite(name, _real(name, value), "bytes") > 0:
                raise InputError(f"{name} must be > 0 [bytes] or None; got {shown(value)}")
        _check_composition(self)
        validate.choice("outside", self.outside, ("warn", "fail"))
        validate.digest("recording", self.recording)


ROUTES = {"camera": CameraRoute, "plate": PlateRoute, "set": SetRoute}


# --- what is written, and who colours the emitters --------------------------------------------


@dataclass(frozen=True, slots=True, kw_only=True)
class Output:
    """Where the frame's pass goes.

    folder : the output folder (the pass and, for a plate, nothing else is written there)
    frame : the frame number, in [0, 1048574]: the pass is :func:`pass_file` (folder, frame)
    render : make the pass (False: a plate's holograms are recorded, nothing is viewed)
    depth_unit : metres per unit of the pass's depth (Blender's ``scale_length``), > 0
    border : Blender's uncropped render region (left, top, right, bottom) [px from the
        top-left corner]: the pass is cleared outside it; None without one
    pass_key : a digest of everything the pass depends on, written into its header
    shot_key : the same digest with the frame left out: the frames of a static shot share it
    """

    folder: Path
    frame: int = 1
    render: bool = True
    depth_unit: float = 1.0
    border: tuple | None = None
    pass_key: str = ""
    shot_key: str = ""

    def __post_init__(self):
        _set(self, "folder", _path("folder", self.folder))
        _set(self, "frame", validate.integer("frame", self.frame, 0, MAX_FRAME))
        _set(self, "render", _flag("render", self.render))
        _set(
            self,
            "depth_unit",
            validate.length("depth_unit", _real("depth_unit", self.depth_unit), "m per unit"),
        )
        if self.border is not None:
            try:
                left, top, right, bottom = (validate.integer("border", v, 0) for v in self.border)
            except (TypeError, ValueError):
                left = top = right = bottom = -1
            if not (0 <= left <= right and 0 <= top <= bottom):
                raise InputError(
                    f"border must be four integers (left, top, right, bottom) [px], "
                    f"0 <= left <= right, 0 <= top <= bottom; got {self.border!r}"[:300]
                )
            _set(self, "border", (left, top, right, bottom))
        for name in ("pass_key", "shot_key"):
            if not isinstance(getattr(self, name), str):
                raise InputError(f"{name} must be a string; got {getattr(self, name)!r}"[:300])

    @property
    def pass_path(self) -> Path:
        """The frame's pass: ``folder/holo_pass_NNNN.exr``."""
        return pass_file(self.folder, self.frame)


@dataclass(frozen=True, slots=True, kw_only=True)
class Radiance:
    """A renderer's radiance of the emitters (Lighting: Scene): ``command`` (its argument
    list) writes ``image``, an RGBA OpenEXR of the emitters alone, premultiplied, as
    ``camera`` sees them (and may print ``HOLO_PROGRESS <fraction>`` lines); it runs in
    ``folder``, its scratch folder, removed afterwards."""

    command: tuple
    image: Path
    folder: Path
    camera: Camera

    def __post_init__(self):
        command = self.command
        if (
            isinstance(command, (str, bytes))
            or not isinstance(command, (list, tuple))
            or not command
            or not all(isinstance(a, str) for a in command)
        ):
            raise InputError(
                f"radiance command must be a list of strings (a program and its "
                f"arguments); got {command!r}"[:300]
            )
        _set(self, "command", tuple(command))
        _set(self, "image", _path("radiance image", self.image))
        _set(self, "folder", _path("radiance folder", self.folder))
        if not isinstance(self.camera, Camera):
            raise InputError(f"radiance camera must be a Camera; got {type(self.camera).__name__}")


# --- the job ----------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class Job:
    """One pass (or a plate's recording): the emitters ``points`` and ``triangles`` (meshes in
    world metres, recorded as point emitters and as triangles), the ``camera``, the ``route``
    (:class:`CameraRoute` or :class:`PlateRoute`), the ``output`` and, with Lighting: Scene,
    the ``radiance`` that colours the emitters (only where something is recorded)."""

    camera: Camera
    route: CameraRoute | PlateRoute | SetRoute
    output: Output
    points: tuple = ()
    triangles: tuple = ()
    radiance: Radiance | None = None

    def __post_init__(self):
        if not isinstance(self.camera, Camera):
            raise InputError(f"camera must be a Camera; got {type(self.camera).__name__}")
        if not isinstance(self.route, tuple(ROUTES.values())):
            raise InputError(
                f"route must be a CameraRoute, a PlateRoute or a SetRoute; got "
                f"{type(self.route).__name__}"
            )
        if not isinstance(self.output, Output):
            raise InputError(f"output must be an Output; got {type(self.output).__name__}")
        for name in ("points", "triangles"):
            meshes = getattr(self, name)
            if (
                isinstance(meshes, Mesh)
                or not isinstance(meshes, (list, tuple))
                or not all(isinstance(m, Mesh) for m in meshes)
            ):
                raise InputError(f"{name} must be a list of Mesh; got {meshes!r}"[:300])
            _set(self, name, tuple(meshes))
        camera = isinstance(self.route, CameraRoute)
        records = camera or self.route.record
        if records and not self.points + self.triangles:
            raise InputError("points and triangles hold no emitters: there is nothing to record")
        if camera and not self.output.render:
            raise InputError(
                "output render must be true for a camera hologram (it is made for its pass)"
            )
        if self.radiance is not None and not isinstance(self.radiance, Radiance):
            raise InputError(
                f"radiance must be a Radiance or None; got {type(self.radiance).__name__}"
            )
        if self.radiance is not None and not records:
            raise InputError(
                "radiance colours emitters to record: a plate whose holograms "
                "are current takes none"
            )
        border = self.output.border
        w, h = self.camera.resolution
        if border is not None and (border[2] > w or border[3] > h):
            raise InputError(f"border must lie within the camera's {w}x{h} pixels; got {border}")

    def to_dict(self) -> dict:
        """The job as plain data (:meth:`from_dict` makes it again)."""
        route = _plain(self.route)
        return {
            "camera": _plain(self.camera),
            "route": {"kind": _kind(self.route), **route},
            "output": _plain(self.output),
            "points": [_plain(m) for m in self.points],
            "triangles": [_plain(m) for m in self.triangles],
            "radiance": None if self.radiance is None else _plain(self.radiance),
        }

    @classmethod
    def from_dict(cls, data) -> Job:
        """The job of :meth:`to_dict`'s plain data, every field checked
        (:class:`~holo_core.validate.InputError` naming it)."""
        d = _fields(cls, data, "job")
        route = _fields(None, _needed(d, "route", "job"), "route")
        kind = validate.choice("route kind", route.pop("kind", None), tuple(ROUTES))
        if "plate" in route:
            route["plate"] = _noun(Plate, route["plate"], "plate")
        if kind == "set" and isinstance(route.get("parts"), list):
            route["parts"] = tuple(
                _noun(PathPart, p, f"parts[{i}]") for i, p in enumerate(route["parts"])
            )
        radiance = d.get("radiance")
        if radiance is not None:
            radiance = _noun(Radiance, radiance, "radiance")
        return _made(
            cls,
            "job",
            camera=_noun(Camera, _needed(d, "camera", "job"), "camera"),
            route=_noun(ROUTES[kind], route, "route"),
            output=_noun(Output, _needed(d, "output", "job"), "output"),
            points=_meshes(d.get("points", ()), "points"),
            triangles=_meshes(d.get("triangles", ()), "triangles"),
            radiance=radiance,
        )


# --- the result -------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True, kw_only=True)
class Plan:
    """The optics a view was made with: the pupil's ``aperture`` and ``focus`` [m] (None: a
    pinhole), the ``wavelengths`` [m], the resolution limit λ/D in pixels
    (``resolution_limit_px``), the pupil's samples (rows, cols) and, for a camera hologram,
    its depth ``layers``."""

    aperture: float
    focus: float | None = None
    wavelengths: tuple = ()
    resolution_limit_px: float = 0.0
    pupil_samples: tuple | None = None
    layers: int | None = None

    def __post_init__(self):
        _set(self, "wavelengths", tuple(map(float, self.wavelengths)))
        if self.pupil_samples is not None:
            _set(self, "pupil_samples", tuple(map(int, self.pupil_samples)))

    @classmethod
    def of(cls, info: dict) -> Plan | None:
        """The plan a view's ``info`` records, or None when it holds none."""
        if "aperture_m" not in info:
            return None
        pupil = info.get("pupil_samples")
        return cls(
            aperture=float(info["aperture_m"]),
            focus=_number(info.get("focus_m")),
            wavelengths=tuple(map(float, info.get("wavelengths_m", ()))),
            resolution_limit_px=float(info.get("resolution_limit_px", 0.0)),
            pupil_samples=None if pupil is None else tuple(map(int, pupil)),
            layers=None if info.get("layers") is None else int(info["layers"]),
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class Report:
    """What the renderer reported: its ``warnings`` (each once, in order), the ``seconds``
    the run took in the worker and the renderer's radiance of them (``radiance_seconds``,
    Lighting: Scene), the ``looks`` averaged and the running mean's ``speckle_contrast``, and
    the view's :class:`Plan`."""

    warnings: tuple = ()
    seconds: float | None = None
    radiance_seconds: float | None = None
    looks: int | None = None
    speckle_contrast: float | None = None
    plan: Plan | None = None

    def __post_init__(self):
        _set(self, "warnings", tuple(map(str, self.warnings)))

    @classmethod
    def of(cls, view: RenderResult | None, **report) -> Report:
        """The report of ``view`` (its ``info``), with ``report``'s fields."""
        info = {} if view is None else view.info
        looks = info.get("samples")
        return cls(
            looks=None if looks is None else int(looks),
            speckle_contrast=_number(info.get("speckle_contrast")),
            plan=Plan.of(info),
            **report,
        )


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class Result:
    """What a job made: the ``view`` (in the process that rendered it; None across the
    process boundary, where the pass file holds it, and for a recording alone), the hologram
    files ``recorded`` (none where they were current), the frame's pass ``pass_path`` (None:
    nothing viewed), ``reused``: the pass file that was reused instead of rendering (the
    frame's own, up to date, or another frame's of the same static shot), and the
    :class:`Report`."""

    recorded: tuple = ()
    pass_path: Path | None = None
    reused: Path | None = None
    report: Report = field(default_factory=Report)
    view: RenderResult | None = None

    def to_dict(self) -> dict:
        """The result as plain data, the view left out (the pass file holds it)."""
        return {
            "recorded": [str(p) for p in self.recorded],
            "pass_path": None if self.pass_path is None else str(self.pass_path),
            "reused": None if self.reused is None else str(self.reused),
            "report": _plain(self.report),
        }

    @classmethod
    def from_dict(cls, data) -> Result:
        d = _fields(cls, data, "result")
        return cls(
            recorded=_paths("recorded", d.get("recorded", ())),
            pass_path=_path("pass_path", d.get("pass_path"), optional=True),
            reused=_path("reused", d.get("reused"), optional=True),
            report=_noun(Report, d.get("report", {}), "report"),
        )


# the nouns inside nouns that from_dict makes of their dicts: (owner, field) -> type
NESTED = {
    (Plate, "zone"): ViewingZone,
    (Radiance, "camera"): Camera,
    (Report, "plan"): Plan,
    (PathPart, "plate"): Plate,
}


# --- plain data -------------------------------------------------------------------------------


def _plain(obj):
    """A dataclass as a dict of its fields, nested dataclasses too; paths as strings, tuples as
    lists, arrays as they are."""
    if dataclasses.is_dataclass(obj):
        return {
            f.name: _plain(getattr(obj, f.name))
            for f in dataclasses.fields(obj)
            if f.init and (f.name != "view")
        }
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, tuple):
        return [_plain(v) for v in obj]
    return obj


def _kind(route) -> str:
    return next(k for k, cls in ROUTES.items() if isinstance(route, cls))


def _fields(cls, data, name: str) -> dict:
    """``data`` as a dict whose keys are ``cls``'s fields (any keys when ``cls`` is None)."""
    if not isinstance(data, dict):
        raise InputError(f"{name} must be a dict of its fields; got {type(data).__name__}")
    if cls is not None:
        known = {f.name for f in dataclasses.fields(cls) if f.init}
        unknown = sorted(map(str, set(data) - known))
        if unknown:
            raise InputError(
                f"{name} has no field {', '.join(map(repr, unknown))} (its "
                f"fields: {', '.join(sorted(known))})"[:300]
            )
    return dict(data)


def _noun(cls, data, name: str):
    """``cls`` made of the dict ``data`` (or ``data`` itself when it is one), its nested
    nouns too (:data:`NESTED`)."""
    if isinstance(data, cls):
        return data
    fields = _fields(cls, data, name)
    for (owner, key), kind in NESTED.items():
        if owner is cls and isinstance(fields.get(key), dict):
            fields[key] = _noun(kind, fields[key], f"{name} {key}")
    return _made(cls, name, **fields)


def _named(cls, data, what: str):
    """``cls`` of the dict ``data`` whose fields include ``name`` (which :func:`_made`'s own
    parameter would take)."""
    fields = _fields(cls, data, what)
    try:
        return cls(**fields)
    except TypeError as e:
        raise InputError(f"{what}: {e}"[:300]) from None


def _needed(data: dict, key: str, name: str):
    if key not in data:
        raise InputError(f"{name} lacks '{key}'")
    return data[key]


def _made(cls, name: str, **fields):
    """``cls(**fields)``; a field it needs and lacks is an InputError naming it."""
    try:
        return cls(**fields)
    except TypeError as e:
        text = str(e)
        if "required" in text:  # missing 1 required keyword-only argument: 'plate'
            raise InputError(f"{name} lacks {text.split(': ', 1)[-1]}"[:300]) from None
        raise InputError(f"{name}: {text}"[:300]) from None


def _meshes(data, name: str) -> tuple:
    if not isinstance(data, (list, tuple)):
        raise InputError(f"{name} must be a list of meshes; got {type(data).__name__}")
    return tuple(_noun(Mesh, m, f"{name}[{i}]") for i, m in enumerate(data))


def _check_composition(route) -> None:
    """A plate or set route's composition of its looks ('mean' or 'max') and its opacity
    threshold (a fraction in [0, 1]), checked and the threshold kept as a float."""
    validate.choice("composition", route.composition, ("mean", "max"))
    threshold = validate.finite(
        "opacity_threshold", _real("opacity_threshold", route.opacity_threshold)
    )
    if not 0 <= threshold <= 1:
        raise InputError(f"opacity_threshold must be in [0, 1]; got {route.opacity_threshold!r}")
    _set(route, "opacity_threshold", threshold)


def _set(obj, name: str, value) -> None:
    object.__setattr__(obj, name, value)


def _path(name: str, value, *, optional=False) -> Path | None:
    if value is None and optional:
        return None
    if not isinstance(value, (str, Path)) or not str(value) or "\0" in str(value):
        raise InputError(f"{name} must be a path; got {shown(value)}"[:300])
    return Path(value)


def _paths(name: str, values) -> tuple:
    if isinstance(values, (str, Path)) or not isinstance(values, (list, tuple)):
        raise InputError(f"{name} must be a list of paths; got {values!r}"[:300])
    return tuple(_path(name, v) for v in values)


def _flag(name: str, value) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise InputError(f"{name} must be true or false; got {shown(value)}"[:300])
    return bool(value)


def _real(name: str, value):
    """``value`` when it is a number (a string or a flag is not, whatever it spells)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)):
        raise InputError(f"{name} must be a number; got {shown(value)}"[:300])
    return value


def _number(value) -> float | None:
    return None if value is None or not math.isfinite(float(value)) else float(value)


# --- a holographic display's frame ------------------------------------------------------------

PATTERN_PACKINGS = ("grey8", "grey16", "packed10")  # holo_core.io.slm's, as the driver reads
DISPLAY_METHODS = ("double-phase", "gradient-descent", "gerchberg-saxton")


@dataclass(frozen=True, slots=True, kw_only=True)
class FrameLaser:
    """One laser of a display's frame: ``name`` (a word: red, green, blue), ``wavelength``
    [m], ``power`` [W], the plate ``hologram`` recorded for it [path], the ``channel`` of it
    that holds its colour (R, G, B: 0, 1, 2) and its phase ``table`` [path] ('' for the
    display's linear response)."""

    name: str
    wavelength: float
    power: float
    hologram: str
    channel: int
    table: str = ""

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise InputError(
                f"laser name must be a word (red, green, blue); got {self.name!r}"[:200]
            )
        _set(
            self,
            "wavelength",
            validate.length("laser wavelength", _real("laser wavelength", self.wavelength)),
        )
        power = validate.finite("laser power", _real("laser power", self.power), "W")
        if not power > 0:
            raise InputError(f"laser power must be > 0 [W]; got {shown(self.power)}")
        _set(self, "power", power)
        _set(self, "hologram", str(_path("laser hologram", self.hologram)))
        _set(self, "channel", validate.integer("laser channel", self.channel, 0, 2))
        if not isinstance(self.table, str):
            raise InputError(f"laser table must be a path or ''; got {shown(self.table)}")


@dataclass(frozen=True, slots=True, kw_only=True)
class DisplayFrame:
    """Frame ``frame`` of the display ``name`` (:mod:`holo_core.phase.display_frame` makes
    it), its files written into ``folder``.

    resolution : (cols, rows) samples; pitch [m]; bit_depth; phase_range [rad] in [2π, 4π];
        inverted : the display (:class:`holo_core.phase.display.Display`)
    packing : one of :data:`PATTERN_PACKINGS`: the pattern image as the driver reads it
    lasers : (:class:`FrameLaser`, ...), one pattern each (field-sequential colour)
    scale : display metres per scene metre the scene is shown at (for the layouts: the
        waves are recorded as the display shows the scene, in its metres)
    front : [m] where in front of the display the waves were recorded (0: on it); carried
        back to it by the angular spectrum
    behind : [m] how far behind the display the volume reaches
    eye_distance, eye_box, pupil : [m] the eye box's distance, width (square) and the pupil
    distance : [m] the scene's mean signed depth (negative: behind), for the layouts
    method : one of :data:`DISPLAY_METHODS`; iterations : the iterative methods' steps
    slices : the focal stack's planes over the volume, from −behind to front
    digest : what the frame is made from (written into its layout: a frame whose layout
        holds it is up to date)
    """

    name: str
    frame: int
    folder: str
    resolution: tuple
    pitch: float
    bit_depth: int
    phase_range: float
    inverted: bool
    packing: str
    lasers: tuple
    scale: float
    front: float
    behind: float
    eye_distance: float
    eye_box: float
    pupil: float
    distance: float
    method: str = "double-phase"
    iterations: int = 100
    slices: int = 5
    digest: str = ""

    def __post_init__(self):
        lasers = self.lasers
        if (
            isinstance(lasers, (FrameLaser, dict))
            or not isinstance(lasers, (list, tuple))
            or not lasers
        ):
            raise InputError("lasers must be one or more FrameLaser")
        _set(
            self,
            "lasers",
            tuple(
                x if isinstance(x, FrameLaser) else _named(FrameLaser, x, "laser") for x in lasers
            ),
        )
        if len({x.name for x in self.lasers}) != len(self.lasers):
            raise InputError(
                f"lasers must have distinct names; got {[x.name for x in self.lasers]}"
            )
        _set(self, "frame", validate.integer("frame", self.frame, 0, MAX_FRAME))
        _set(self, "folder", str(_path("folder", self.folder)))
        try:
            cols, rows = self.resolution
        except (TypeError, ValueError):
            raise InputError(
                f"resolution must be (cols, rows); got {shown(self.resolution)}"
            ) from None
        rows, cols = validate.shape2d("resolution", (rows, cols))
        _set(self, "resolution", (cols, rows))
        _set(self, "pitch", validate.pitch("pitch", _real("pitch", self.pitch)))
        _set(self, "bit_depth", validate.integer("bit_depth", self.bit_depth, 1, 16))
        _set(
            self,
            "phase_range",
            validate.finite("phase_range", _real("phase_range", self.phase_range), "rad"),
        )
        validate.choice("packing", self.packing, PATTERN_PACKINGS)
        validate.choice("method", self.method, DISPLAY_METHODS)
        _set(self, "iterations", validate.integer("iterations", self.iterations, 0, 100000))
        _set(self, "slices", validate.integer("slices", self.slices, 1, 1000))
        _set(self, "inverted", _flag("inverted", self.inverted))
        for name in ("scale", "eye_distance", "eye_box", "pupil"):
            value = validate.finite(name, _real(name, getattr(self, name)))
            if not value > 0:
                raise InputError(f"{name} must be > 0; got {shown(getattr(self, name))}")
            _set(self, name, value)
        for name in ("front", "behind"):
            value = validate.finite(name, _real(name, getattr(self, name)), "m")
            if value < 0:
                raise InputError(f"{name} must be >= 0 [m]; got {shown(getattr(self, name))}")
            _set(self, name, value)
        _set(self, "distance", validate.finite("distance", _real("distance", self.distance), "m"))
        validate.digest("digest", self.digest)

    def to_dict(self) -> dict:
        return _plain(self)

    @classmethod
    def from_dict(cls, data) -> DisplayFrame:
        """The frame of :meth:`to_dict`'s plain data, every field checked."""
        return _named(cls, data, "display frame")

    def stem(self) -> str:
        """The frame's files' common name: ``frame_NNNN``."""
        return f"frame_{self.frame:04d}"


# --- views of a held plate (the live viewport's messages) -------------------------------------


@dataclass(frozen=True, slots=True, kw_only=True)
class ViewOpen:
    """The plate a view-serving worker holds, and how its views are rendered: the settings a
    :class:`holo_core.worker.Views` keeps, so that a worker started again gets them again.

    plates : the kept plate's files [paths]: its looks' hologram files, or a plate set's
        manifest
    recording : the digest of the recording they must be ('' : none checked); a plate of
        another recording under these names is refused by name
    supersample : fine pixels per pixel per axis (an integer >= 1), or 'auto'
    composition : 'mean' or 'max' of the looks' views
    opacity_threshold : the view's coverage taken as opaque, in [0, 1]
    exposure : a linear factor on the radiance (> 0)
    """

    plates: tuple
    recording: str = ""
    supersample: int | str = "auto"
    composition: str = "mean"
    opacity_threshold: float = 0.5
    exposure: float = 1.0

    def __post_init__(self):
        paths = self.plates
        if isinstance(paths, (str, Path)):
            paths = (paths,)
        _set(self, "plates", tuple(str(p) for p in _paths("plates", paths)))
        if not self.plates:
            raise InputError("plates must name one or more plate files; got none")
        if self.recording:
            validate.digest("recording", self.recording)
        if self.supersample != "auto":
            _set(
                self,
                "supersample",
                validate.integer("supersample", self.supersample, 1, MAX_SUPERSAMPLE),
            )
        _check_composition(self)
        _set(self, "exposure", validate.exposure(_real("exposure", self.exposure)))

    def options(self) -> dict:
        """The render options a viewer takes (:class:`holo_core.PlateViewer`'s keywords)."""
        return {
            "supersample": self.supersample,
            "composition": self.composition,
            "opacity_threshold": self.opacity_threshold,
        }

    def to_dict(self) -> dict:
        return {
            "plates": list(self.plates),
            "recording": self.recording,
            "supersample": self.supersample,
            "composition": self.composition,
            "opacity_threshold": self.opacity_threshold,
            "exposure": self.exposure,
        }

    @classmethod
    def from_dict(cls, data) -> ViewOpen:
        """The settings of :meth:`to_dict`'s plain data, every field checked."""
        return _made(cls, "view open", **_fields(cls, data, "view open"))


@dataclass(frozen=True, slots=True, kw_only=True)
class ViewRequest:
    """One view asked of a view-serving worker: request ``id`` (larger is newer: a newer
    request supersedes older ones still queued), the ``camera``, ``coarse`` (a quick
    picture while the camera moves) and ``shared`` (the name of the
    :class:`holo_core.io.shared_view.SharedView` its picture goes to)."""

    id: int
    camera: Camera
    shared: str
    coarse: bool = False

    def __post_init__(self):
        _set(self, "id", validate.integer("id", self.id, 1))
        if not isinstance(self.camera, Camera):
            raise InputError(f"camera must be a Camera; got {type(self.camera).__name__}")
        if not isinstance(self.shared, str) or not self.shared or len(self.shared) > 200:
            raise InputError(f"shared must name a shared view; got {shown(self.shared)}")
        _set(self, "coarse", _flag("coarse", self.coarse))

    def to_dict(self) -> dict:
        """Plain data that JSON holds (the camera's matrix as nested lists)."""
        camera = _plain(self.camera)
        camera["matrix_world"] = np.asarray(camera["matrix_world"]).tolist()
        return {"id": self.id, "camera": camera, "shared": self.shared, "coarse": self.coarse}

    @classmethod
    def from_dict(cls, data) -> ViewRequest:
        d = _fields(cls, data, "view request")
        camera = d.get("camera")
        if isinstance(camera, dict):
            camera = _noun(
                Camera,
                {
                    k: tuple(v)
                    if k in ("resolution", "pixel_aspect") and isinstance(v, list)
                    else v
                    for k, v in camera.items()
                },
                "camera",
            )
        return _made(cls, "view request", **{**d, "camera": camera})


@dataclass(frozen=True, slots=True, kw_only=True)
class ViewReply:
    """A view-serving worker's answer to request ``id``: how long it took [s]; ``where``,
    why the camera is outside the plate's zone ('' inside: the picture is in the shared view
    ``shared``); ``error``, what failed ('' : nothing); ``coarse`` as asked."""

    id: int
    seconds: float = 0.0
    where: str = ""
    shared: str = ""
    coarse: bool = False
    error: str = ""

    def to_dict(self) -> dict:
        return {
            "id": self.id,
            "seconds": self.seconds,
            "where": self.where,
            "shared": self.shared,
            "coarse": self.coarse,
            "error": self.error,
        }

    @classmethod
    def from_dict(cls, data) -> ViewReply:
        return _made(cls, "view reply", **_fields(cls, data, "view reply"))
