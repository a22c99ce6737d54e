"""The holographic display (Blender → plain data): a plane marked as a phase SLM, its preset
or custom panel, its lasers, the volume the scene is shown in and its eye box
(:class:`DisplaySpec`), the scene checked against it before any work (:func:`check`), and
each laser's recording as a plate job (:func:`read`).

Scale. The scene is shown in the display's volume scaled by ``scale`` (display metres per
scene metre) about the display's origin: the emitters are scaled so, and their wave is
recorded in the display's own metres, at its wavelengths, on a plate of its size seen from
its eye box. The lit radiance (Cycles) is rendered from the eye box in the scene as it
stands (the eye box's place scaled by 1 / scale: a pinhole sees the same image of a scene
scaled about a point when its own place is scaled alike).

Geometry (the display's frame, physical metres: the pattern in z = 0, viewers on +Z, the
eye box centred at (0, 0, D)): objects sit behind the display (z < 0) down to ``behind``, or
in front of it up to ``front``; in front, the wave is recorded on a plane at z = front and
carried back to the display by the angular spectrum (the plate planner needs its objects
behind its plate). The display is lit by a plane wave along its normal: a sample diffracts
light within sin θ = λ / 2p of it, and the display's 4f filter passes band·λ / 2p of that
(:data:`BAND`).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path

import bpy
import numpy as np

from holo_core.io.plate_paths import plate_current
from holo_core.job import Job, Output, PlateRoute
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.plate import Plate, ViewingZone

from . import radiance
from .job import Prepared, Settings, digest, output_dir
from .scene import ExportError, NoEmitters, SceneData, emitters, evaluated, scale, world_matrix

# key: (label, (cols, rows), pitch [m], bit depth); phase SLMs as their data sheets give them
PRESETS = {
    "FHD_8": ("1920 × 1080, 8 µm", (1920, 1080), 8.0e-6, 8),
    "FHD_6_4": ("1920 × 1080, 6.4 µm", (1920, 1080), 6.4e-6, 8),
    "UHD_3_74": ("3840 × 2160, 3.74 µm", (3840, 2160), 3.74e-6, 8),
    "UHD_3_6": ("3840 × 2160, 3.6 µm", (3840, 2160), 3.6e-6, 8),
}
COLOURS = ("red", "green", "blue")  # the lasers, each shown on its own (field-sequential)
FORMATS = {"PNG8": 8, "PNG16": 16, "PACKED10": 10}  # the pattern file, and the bits it holds
PHASE_RANGES = {"2PI": 2 * math.pi, "3PI": 3 * math.pi}
# A point is shown at its depth only where the samples that form it, seen through the pupil,
# are at least this many across (Nyquist): fewer, and the eye sees one sample's blur at the
# display's plane, whatever depth the wave was recorded for
MIN_FOOTPRINT_SAMPLES = 2
# The fraction of the Nyquist frequency the display's Fourier filter passes: the 4f filter
# double-phase needs (holo_core.phase.slm.SLMSetup's band)
BAND = 0.5
# Samples of the radiance's image across (Lighting: Scene): a texture's detail finer than
# the display's pupil resolves is not needed
RADIANCE_PIXELS = 512


@dataclass(frozen=True, slots=True, kw_only=True)
class Laser:
    """One colour of a field-sequential display: ``name`` (red, green, blue), ``wavelength``
    [m], ``power`` [W] (written into the layout; the contact sheet is mixed by it) and
    ``channel``: which of the recording's colour channels (R, G, B) it shows; ``table``: its
    phase table's file ('' for the display's linear response)."""

    name: str
    wavelength: float
    power: float
    channel: int
    table: str = ""


@dataclass(frozen=True, slots=True, kw_only=True)
class DisplaySpec:
    """A display object's settings as plain values, lengths in metres (physical: the
    display's own, never the scene's).

    name : the object's name (its files' stem)
    preset : a key of :data:`PRESETS`, or 'CUSTOM'
    resolution : (cols, rows) samples
    pitch : sample spacing [m]
    bit_depth : phase levels 2^bit_depth the SLM resolves
    pattern_format : a key of :data:`FORMATS`: how its driver takes the pattern
    phase_range : the phase [rad] the code range spans (2π, or 3π for SLMs driven beyond a wave)
    inverted : the SLM's phase falls as its code rises
    lasers : (:class:`Laser`, ...)
    front, behind : [m] how far in front of (towards the viewer) and behind the display the
        scene may reach
    scale : display metres per scene metre
    eye_distance : [m] the eye box's centre from the display, along its normal
    eye_box : [m] the eye box's width and height (square)
    pupil : [m] the eye's or camera's pupil in the eye box (the focal stack is seen through it)
    method : the encoding ('double-phase', 'gradient-descent', 'gerchberg-saxton');
        iterations : the iterative ones' steps
    slices : focal slices simulated over the volume's depth
    phases : the emitters' phases in the recorded wave, 'smooth' (one phase: the eye's pupil
        sees a picture, as display holograms are made) or 'random' (a diffuse surface:
        speckle through the pupil)
    """

    name: str
    preset: str
    resolution: tuple
    pitch: float
    bit_depth: int
    pattern_format: str
    phase_range: float
    inverted: bool
    lasers: tuple
    front: float
    behind: float
    scale: float
    eye_distance: float
    eye_box: float
    pupil: float
    method: str = "double-phase"
    iterations: int = 100
    slices: int = 5
    phases: str = "smooth"

    @property
    def size(self) -> tuple[float, float]:
        """(width, height) [m] of the display's active area."""
        return self.resolution[0] * self.pitch, self.resolution[1] * self.pitch

    def sin_diffraction(self, wavelength: float) -> float:
        """sin θ of the widest angle a sample diffracts ``wavelength`` [m] to: λ / 2p."""
        return wavelength / (2 * self.pitch)

    def sin_passed(self, wavelength: float) -> float:
        """sin θ of the widest angle the display's Fourier filter passes: band·λ / 2p."""
        return BAND * self.sin_diffraction(wavelength)

    def recorded_at(self) -> float:
        """Where [m, the display's frame] the wave is recorded: the volume's front, or the
        display itself."""
        return self.front


@dataclass(frozen=True, eq=False)
class DisplayPrepared:
    """A frame read for the display: each laser's plate job (``colours``: (Laser,
    :class:`holo_addon.export.job.Prepared`), the plate recorded at λ / scale) and what the
    frame's stage needs beside them."""

    spec: DisplaySpec
    colours: tuple
    frame: int
    folder: Path
    distance: float  # [m] the scene's mean signed depth (negative: behind), physical
    digest: str  # of everything the frame's files depend on
    warnings: tuple = field(default=())


def scene_display(scene):
    """The scene's one display object, or None."""
    found = [o for o in scene.objects if o.type == "MESH" and o.holo.is_display]
    if len(found) > 1:
        raise ExportError(
            f"one holographic display per scene; found {', '.join(o.name for o in found)}"
        )
    return found[0] if found else None


def _given(value: float, factor: float = 1.0) -> float:
    """A setting as the user typed it, in metres: Blender keeps single precision, whose
    0.01 is 0.0099999998; seven digits are what it holds."""
    return float(f"{value:.7g}") * factor


def display_from_object(obj) -> DisplaySpec:
    """The display's settings (``Object.holo.display``) as a :class:`DisplaySpec`."""
    d = (obj.original if obj.is_evaluated else obj).holo.display
    if d.preset == "CUSTOM":
        resolution, pitch, bits = tuple(d.resolution), _given(d.pitch, 1e-6), int(d.bit_depth)
    else:
        _, resolution, pitch, bits = PRESETS[d.preset]
    tables = (d.table_red, d.table_green, d.table_blue)
    lasers = tuple(
        Laser(
            name=n,
            wavelength=_given(w, 1e-9),
            power=_given(p, 1e-3),
            channel=i,
            table=bpy.path.abspath(t) if t else "",
        )
        for i, (n, w, p, t) in enumerate(zip(COLOURS, d.wavelengths, d.powers, tables))
        if d.colours[i]
    )
    if any(x.table for x in lasers) and not all(x.table for x in lasers):
        bare = ", ".join(x.name for x in lasers if not x.table)
        raise ExportError(
            f"display '{obj.name}': phase tables are given for some lasers but "
            f"not for {bare}: give one per laser, or none (the display's "
            f"linear response)"
        )
    if not lasers:
        raise ExportError(f"display '{obj.name}': no laser is on (Lasers: tick red, green or blue)")
    if FORMATS[d.pattern_format] < bits:
        raise ExportError(
            f"display '{obj.name}': its {bits}-bit phase does not fit the "
            f"{d.pattern_format} pattern file ({FORMATS[d.pattern_format]} bits): "
            f"choose a pattern file of {bits} bits or more"
        )
    return DisplaySpec(
        name=obj.name,
        preset=d.preset,
        resolution=resolution,
        pitch=pitch,
        bit_depth=bits,
        pattern_format=d.pattern_format,
        phase_range=PHASE_RANGES[d.phase_range],
        inverted=d.inverted,
        lasers=lasers,
        front=_given(d.front, 1e-3),
        behind=_given(d.behind, 1e-3),
        scale=_given(d.scene_scale),
        eye_distance=_given(d.eye_distance, 1e-3),
        eye_box=_given(d.eye_box, 1e-3),
        pupil=_given(d.pupil, 1e-3),
        method=d.method,
        iterations=d.iterations,
        slices=d.slices,
        phases=d.phases.lower(),
    )


def display_matrix(obj, unit: float) -> np.ndarray:
    """The display's pose [scene metres], its scale removed."""
    return world_matrix(obj.matrix_world, unit, normalise=True)


def check(spec: DisplaySpec, depths: np.ndarray) -> None:
    """Refuse, before any work, a scene the display cannot show, with the numbers and what
    to change (:class:`ExportError`): ``depths`` [m, physical] are the emitters' surface
    points' signed distances from the display along its normal (negative: behind it).

    - the eye box beyond the diffraction angle: the steepest ray from the display's corner
      to the eye box's far corner, tan α = hypot(W/2 + E/2, H/2 + E/2) / D, needs
      sin α <= band·λ / 2p for the shortest wavelength (the light the display's filter
      passes; as :func:`holo_core.phase.slm.check_scene` holds it, which the frame's stage
      runs again);
    - the scene outside the volume: the depths must lie in [−behind, front];
    - too close for the pitch: a point at depth z is formed, through the pupil a at D, by the
      samples within a·|z| / (D − z) of its line of sight; they must be
      :data:`MIN_FOOTPRINT_SAMPLES` or more across (z_min = N·p·D / (a + N·p) behind).
    """
    name, p, d_eye, eye = spec.name, spec.pitch, spec.eye_distance, spec.eye_box
    if not d_eye > spec.front:
        raise ExportError(
            f"display '{name}': the eye box ({d_eye * 1e3:.4g} mm away) must lie "
            f"beyond the volume's front ({spec.front * 1e3:.4g} mm): move it "
            f"farther or bring the front in"
        )
    hx, hy = (v / 2 for v in spec.size)
    lam = min(laser.wavelength for laser in spec.lasers)
    sin_limit = spec.sin_passed(lam)
    lateral = math.hypot(hx + eye / 2, hy + eye / 2)  # the display's corner to the far edge
    tan_needed = lateral / d_eye
    sin_needed = tan_needed / math.hypot(1, tan_needed)
    if sin_needed > sin_limit:
        reach = d_eye * sin_limit / math.sqrt(1 - sin_limit**2)  # lateral reach allowed
        b = hx + hy  # hypot(hx + e, hy + e) = reach, e the eye box's half width
        root = b * b - 2 * (hx * hx + hy * hy - reach * reach)
        widest = 2 * (-b + math.sqrt(root)) / 2 if root >= 0 else 0.0
        nearest = lateral * math.sqrt(1 - sin_limit**2) / sin_limit
        finest = BAND * lam / (2 * sin_needed)
        shrink = f"an eye box of at most {widest * 1e3:.3g} mm, " if widest > 0 else ""
        raise ExportError(
            f"display '{name}': its eye box ({eye * 1e3:.3g} mm wide, {d_eye * 1e3:.4g} mm "
            f"away) is beyond the display's diffraction angle: seen from its far corner the "
            f"display's corner is {math.degrees(math.asin(sin_needed)):.3g}° off its normal, "
            f"and a {p * 1e6:.3g} µm sample sends {lam * 1e9:.4g} nm light through the "
            f"display's filter at most {math.degrees(math.asin(sin_limit)):.3g}° off it "
            f"(sin θ = band·λ/2p, band {BAND:g}); use {shrink}an eye distance of at least "
            f"{nearest * 1e3:.4g} mm, or a pitch of at most {finest * 1e6:.3g} µm"
        )
    if not len(depths):
        return
    deepest, nearest_front = float(depths.min()), float(depths.max())
    if deepest < -spec.behind * (1 + 1e-9) or nearest_front > spec.front * (1 + 1e-9) + 1e-12:
        extent = nearest_front - deepest
        fits = min(
            spec.behind / max(-deepest, 1e-300) if deepest < 0 else math.inf,
            spec.front / nearest_front if nearest_front > 0 else math.inf,
        )
        fit = f"a Scene Scale of at most {spec.scale * fits:.4g}, or " if 0 < fits < 1 else ""
        raise ExportError(
            f"display '{name}': the scene reaches from {deepest * 1e3:.4g} mm to "
            f"{nearest_front * 1e3:.4g} mm off the display ({extent * 1e3:.4g} mm deep at "
            f"Scene Scale {spec.scale:g}), outside its volume of {spec.behind * 1e3:.4g} mm "
            f"behind and {spec.front * 1e3:.4g} mm in front: use {fit}a volume reaching "
            f"{max(-deepest, 0) * 1e3:.4g} mm behind and {max(nearest_front, 0) * 1e3:.4g} mm "
            f"in front, or move the objects"
        )
    n = MIN_FOOTPRINT_SAMPLES
    behind_min = n * p * d_eye / (spec.pupil + n * p)  # a·z / (D + z) = n·p, z behind
    front_min = n * p * d_eye / (spec.pupil - n * p) if spec.pupil > n * p else math.inf
    closest = depths[np.argmin(np.abs(depths))]
    limit = behind_min if closest <= 0 else front_min
    if abs(closest) < limit:
        side = "behind" if closest <= 0 else "in front of"
        across = spec.pupil * abs(closest) / (d_eye - closest) / p
        raise ExportError(
            f"display '{name}': an object is {abs(closest) * 1e3:.3g} mm {side} it, too close "
            f"for its {p * 1e6:.3g} µm pitch: seen through the {spec.pupil * 1e3:.3g} mm pupil "
            f"{d_eye * 1e3:.4g} mm away, a point there is formed by {across:.2g} samples "
            f"across (it needs {n}); keep the scene at least {limit * 1e3:.3g} mm {side} the "
            f"display (move the objects or the display, or raise the Scene Scale), or use a "
            f"wider pupil or a finer pitch"
        )


def depths_of(meshes, display: np.ndarray, scene_scale: float) -> np.ndarray:
    """The meshes' vertices' signed depths [m, physical] along the display's normal
    (``display``: its pose, scene metres)."""
    if not meshes:
        return np.zeros(0)
    world = np.concatenate([m.vertices for m in meshes])
    local = (world - display[:3, 3]) @ display[:3, :3]
    return local[:, 2] * scene_scale


def read(scene, depsgraph, obj=None) -> DisplayPrepared:
    """The frame as ``depsgraph`` evaluates it, for the scene's display (or ``obj``): the
    emitters and, per laser, a plate job recording their wave at λ / scale on the display's
    plane (or the volume's front), seen from the eye box. Raises :class:`ExportError` for a
    scene the display cannot show, before any work."""
    obj = obj or scene_display(scene)
    if obj is None:
        raise ExportError(
            "no holographic display: mark a plane with Object ▸ Holo ▸ Holographic Display"
        )
    spec = display_from_object(obj)
    unit = scale(scene)
    lit = scene.holo.lighting == "SCENE"
    notes: list = []
    kinds, names = emitters(depsgraph, unit, notes, lit=lit)
    meshes = kinds["POINTS"] + kinds["TRIANGLES"]
    if not meshes:
        raise NoEmitters(
            "no holographic emitters in the frame: set Object ▸ Holo ▸ Emitter "
            "on a mesh that renders"
        )
    m = display_matrix(evaluated(obj, depsgraph), unit)
    depths = depths_of(meshes, m, spec.scale)
    check(spec, depths)
    s, origin = spec.scale, m[:3, 3]

    def shown(points):  # the scene as the display shows it: scaled by s about its origin
        return origin + s * (np.asarray(points, np.float64) - origin)

    physical = {
        kind: [
            replace(
                mesh,
                vertices=shown(mesh.vertices),
                motion=None if mesh.motion is None else shown(mesh.motion),
            )
            for mesh in kinds[kind]
        ]
        for kind in ("POINTS", "TRIANGLES")
    }
    # the plane the wave is recorded on: the display, or the volume's front (then carried
    # back), wide enough for the light the display's samples send to the eye box
    front = spec.recorded_at()
    plate_m = m.copy()
    plate_m[:3, 3] = origin + m[:3, 2] * front
    lam_max = max(laser.wavelength for laser in spec.lasers)
    sin_t = min(spec.sin_diffraction(lam_max), 0.99)
    reach = front * sin_t / math.sqrt(1 - sin_t**2)
    w, h = spec.size
    eye = plate_m[:3, :3] @ np.array([0.0, 0.0, spec.eye_distance - front]) + plate_m[:3, 3]
    every = np.concatenate([mesh.vertices for mesh in meshes])
    # the radiance is rendered from the eye box in the scene as it stands (its scale 1/s):
    # a pinhole sees a scene scaled about a point alike from that point scaled alike
    view = _eye_camera(
        origin + (eye - origin) / s, (every.min(0) + every.max(0)) / 2, m[:3, 1], every
    )
    eye_view = replace(view, matrix_world=_scaled_pose(view.matrix_world, origin, s))
    data = SceneData(
        points=physical["POINTS"],
        triangles=physical["TRIANGLES"],
        plate=None,
        plate_name=obj.name,
        camera=eye_view,
        warnings=tuple(dict.fromkeys(notes)),
        names=tuple(names),
        view=eye_view,
        unit=unit,
    )
    lighting = radiance.digest(scene, depsgraph) if lit else ""
    settings = Settings.from_scene(scene, unit)
    folder = frame_folder(scene, obj.name)
    colours, keys = [], []
    for laser in spec.lasers:
        zone = recording_zone(spec, laser.wavelength)
        plate = Plate(matrix_world=plate_m, width=w + 2 * reach, height=h + 2 * reach, zone=zone)
        data = replace(data, plate=plate)
        fingerprint = digest(
            data,
            laser.wavelength,
            1,
            settings.seed,
            scene.holo.lighting,
            lighting,
            spec.phases,
            camera=False,
        )
        path = folder / "waves" / f"{bpy.path.clean_name(obj.name)}_{laser.name}_{fingerprint}.exr"
        # a file there of another recording is recorded again, never shown as this scene's
        route = PlateRoute(
            plate=plate,
            holograms=(path,),
            record=not plate_current(path, fingerprint),
            recording=fingerprint,
            memory_budget=settings.memory_budget,
            disk_budget=settings.disk_budget,
            wavelength=laser.wavelength,
            seed=settings.seed,
            phases=spec.phases,
        )
        output = Output(
            folder=path.parent, frame=scene.frame_current, render=False, depth_unit=unit
        )
        job = Job(
            camera=eye_view,
            points=tuple(physical["POINTS"]),
            triangles=tuple(physical["TRIANGLES"]),
            route=route,
            output=output,
        )
        light = (
            partial(
                _radiance,
                scene,
                depsgraph.view_layer.name,
                view,
                meshes,
                tuple(names),
                settings.lighting_samples,
                origin,
                s,
            )
            if lit
            else None
        )
        colours.append(
            (
                laser,
                Prepared(
                    job=job,
                    fingerprint=fingerprint,
                    plate_name=obj.name,
                    warnings=data.warnings,
                    lighting=light,
                ),
            )
        )
        keys.append(fingerprint)
    key = hashlib.sha256(repr((keys, spec)).encode()).hexdigest()[:16]
    return DisplayPrepared(
        spec=spec,
        colours=tuple(colours),
        frame=scene.frame_current,
        folder=folder,
        distance=float(np.mean(depths)),
        digest=key,
        warnings=data.warnings,
    )


def recording_zone(spec: DisplaySpec, wavelength: float) -> ViewingZone:
    """The zone the wave is recorded for [m, the recording plane's frame]: centred on the
    eye box, as wide as the display's filter lets light reach there at ``wavelength``
    (2·D·tan θ − W across, the eye box at least: the eye box is a part of it, and an
    emitter's footprint on the plate then spans several of its samples) and as deep as
    the eye box is wide (the eye may sit nearer or farther)."""
    d = spec.eye_distance - spec.front
    sin_t = spec.sin_passed(wavelength)
    tan_t = sin_t / math.sqrt(1 - sin_t**2)
    w, h = spec.size
    half = [max(spec.eye_box, 2 * spec.eye_distance * tan_t - size) / 2 for size in (w, h)]
    return ViewingZone(
        centre=(0.0, 0.0, d), half_extents=(*half, spec.eye_box / 2), pupil=2 * min(half)
    )


def _scaled_pose(matrix, origin, s: float) -> np.ndarray:
    """A camera's pose in the scene scaled by ``s`` about ``origin``: its place scaled, its
    axes kept (what it sees is the same image)."""
    m = np.array(matrix, np.float64)
    m[:3, 3] = origin + s * (m[:3, 3] - origin)
    return m


def _radiance(scene, view_layer, view, meshes, names, samples, origin, s):
    """The emitters' radiance rendered by Cycles from the eye box in the scene as it stands
    (``view``, ``meshes``), its camera then placed in the scene as the display shows it."""
    r = radiance.request(scene, view_layer, view, meshes, names, samples=samples, own_lens=True)
    if r is None:
        return None
    return replace(
        r, camera=replace(r.camera, matrix_world=_scaled_pose(r.camera.matrix_world, origin, s))
    )


def _eye_camera(eye, target, up, points) -> Camera:
    """A pinhole at the eye box's centre looking at the objects, its field just holding them
    (the radiance's view: what Cycles renders the emitters' colours from)."""
    matrix = look_at(eye, target, up=up)
    local = (points - eye) @ matrix[:3, :3]
    depth = np.maximum(-local[:, 2], 1e-12)
    spread = float(np.max(np.abs(local[:, :2]) / depth[:, None]))
    sensor = 36.0
    lens = sensor / (2 * max(spread, 1e-6) * 1.1)
    return Camera(
        matrix_world=matrix,
        lens=lens,
        sensor_width=sensor,
        sensor_height=sensor,
        resolution=(RADIANCE_PIXELS, RADIANCE_PIXELS),
    )


def frame_folder(scene, name: str) -> Path:
    """Where the display's frames go: ``<Output Folder>/display/<name>/``."""
    return output_dir(scene) / "display" / bpy.path.clean_name(name)


def with_frame(prepared: DisplayPrepared, frame: int) -> DisplayPrepared:
    return replace(prepared, frame=frame)
