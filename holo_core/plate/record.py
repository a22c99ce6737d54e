"""Recording: object wave, reference wave and the intensity hologram H = |O + R|² (Sect. V-B).

The hologram lies in the plane z = 0 of its own frame, objects at z < 0, light travelling +z.
One hologram is recorded per wavelength of the same scene (Sect. VII-B).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import numpy as np

from .. import jobs, memory, validate
from ..opencl.arrays import nonfinite_count, read
from ..optics.raster import CROSSING_BYTES, crossing_count
from ..propagation import grid
from ..scene.hologram import ENCODINGS, Hologram, HologramInfo
from ..scene.mesh import Mesh, facing, sample_points, visible_from
from ..scene.plate import DEFAULT_ZONE_MARGIN, Carrier, Plate, ViewingZone
from ..validate import InputError, shown
from .emitters import zone_emitters, zone_frame
from .plan import LAYERS, RIM, PlatePlan, plan
from .point_sources import cone_filter, point_bytes, point_wave
from .triangles import depth_texture, mesh_primitives, primitive_wave, surface_pitch
from .zone_sum import ZoneEmitters, ZoneSum, ZoneWindow

DEFAULT_WAVELENGTHS = (633e-9, 532e-9, 473e-9)  # HeNe red, Nd:YAG green, DPSS blue [m]
MIN_OBLIQUITY = 0.1  # a primitive seen more edge-on than this (cos) gets no brighter
ROTATION_SECONDS = 2e-7  # a primitive's rotation and propagation per padded hologram sample
                         # and wavelength (2-core CPU: 0.4-0.9 s at 1024²) ...
SLOW_TRIANGLES = 60.0    # ... and the estimate [s] above which the user is warned
MAX_INTENSITY = 1e12  # a point's colour, at most: the float32 hologram holds sums of millions
HOST_BYTES = 40  # per sample and wavelength: object and reference waves, H, the stored copy
log = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True, kw_only=True)
class Reference:
    """The plane reference wave of Eq. 4 on z = 0.

    angle : float
        ϑ [rad], between the reference's direction and the hologram normal (+z), in [0, π/2).
    azimuth : float
        φ [rad], direction of the tilt in the hologram plane, from +x towards +y.
    beam_ratio : float
        |R|² / mean |O|², > 0: the reference's intensity against the object wave's.
    allow_aliasing : bool
        Record even when the pitch violates Eq. 19 (the message names the largest safe angle).
    """

    angle: float = 0.0
    azimuth: float = 0.0
    beam_ratio: float = 4.0
    allow_aliasing: bool = False

    def __post_init__(self):
        a = validate.finite("reference angle", self.angle, "rad")
        if not 0 <= a < math.pi / 2:
            raise InputError(f"reference angle must be in [0, π/2) rad; got {shown(self.angle)}")
        validate.finite("reference azimuth", self.azimuth, "rad")
        validate.positive("reference beam_ratio", self.beam_ratio)

    def direction(self) -> np.ndarray:
        """Unit propagation direction (α, β, γ) (direction cosines of Eq. 4)."""
        s = math.sin(self.angle)
        return np.array([s * math.cos(self.azimuth), s * math.sin(self.azimuth),
                         math.cos(self.angle)])

    def check(self, wavelength: float, pitch: float) -> None:
        """Eq. 19: the carrier fringes need pitch <= λ / (2 sin ϑ)."""
        if self.angle == 0:
            return
        limit = wavelength / (2 * math.sin(self.angle))
        if pitch > limit:
            safe = math.asin(min(1.0, wavelength / (2 * pitch)))
            message = (f"reference angle {self.angle:.4g} rad needs a pitch <= {limit:.4g} m "
                       f"at λ = {wavelength:.4g} m (Eq. 19); with pitch {pitch:.4g} m the "
                       f"largest safe angle is {safe:.4g} rad")
            if not self.allow_aliasing:
                raise InputError(message)
            validate.warn_sampling(message)


def reference_wave(shape, *, wavelength, pitch, reference: Reference, amplitude=1.0):
    """R = A·exp(ik(α·x + β·y)) on the hologram's pixel centres (Eq. 4 on z = 0), complex64.

    ``shape`` (rows, cols); ``wavelength``, ``pitch`` [m]; ``amplitude`` A [field units].
    The phase is formed in float64 and reduced before the cast.
    """
    h, w = validate.shape2d("shape", shape)
    wavelength, pitch = grid.wave(wavelength, pitch)
    alpha, beta, _ = reference.direction()
    k = 2 * np.pi / wavelength
    px = np.remainder(k * alpha * grid.coords(w, pitch), 2 * np.pi)
    py = np.remainder(k * beta * grid.coords(h, pitch), 2 * np.pi)
    return (amplitude * np.exp(1j * py)[:, None] * np.exp(1j * px)[None, :]).astype(np.complex64)


def interfere(object_wave, reference_wave) -> np.ndarray:
    """H = |O + R|² (Eq. 16), float32."""
    u = np.asarray(object_wave, np.complex64) + np.asarray(reference_wave, np.complex64)
    return (u.real * u.real + u.imag * u.imag).astype(np.float32)


def record_points(positions, colours, *, shape, pitch, wavelengths=DEFAULT_WAVELENGTHS,
                  phases=None, seed=0, reference=Reference(), obliquity=False,
                  keep_object_wave=True, plate=None, method="auto", band=None,
                  channels=(), point_density=0.0, extra_wave=None, bounds=None,
                  progress: jobs.Progress = None) -> Hologram:
    """Holograms of point emitters, one per wavelength.

    Parameters
    ----------
    positions : (N, 3) float array
        Points [m] in the hologram's frame (z < 0).
    colours : (N, C) float array
        Intensity I >= 0 per point and wavelength; the amplitude is A0 = √I (Sect. VII-B).
    shape : (int, int)
        Hologram (rows, cols).
    pitch : float
        Hologram sample spacing [m].
    wavelengths : sequence of float
        One λ [m] per colour channel; equal values are allowed.
    phases : (N,) float array, optional
        Initial phases φ0 [rad]; default uniformly random (a diffuse surface), from ``seed``.
    reference : Reference
        The reference wave; its amplitude follows from ``beam_ratio`` per colour.
    plate : (4, 4) array, optional
        The hologram frame's pose in the world (hologram-to-world), stored with it.
    method, obliquity, band
        As for :func:`holo_core.plate.point_sources.point_wave`; ``band`` is stored for the
        reconstruction's filter.
    channels, point_density
        Stored with the hologram (see :class:`holo_core.scene.hologram.Hologram`).
    extra_wave : callable (channel, wavelength [m]) -> complex (H, W) array, optional
        Further object wave on the hologram from other emitters (textured primitives).
    bounds : (2, 3) array, optional
        The objects' bounding box [m] in the hologram frame; default: the points'.
    """
    pos, wavelengths, amplitude = point_amplitudes(positions, colours, wavelengths, phases,
                                                   seed, empty_ok=extra_wave is not None)
    shape = validate.shape2d("shape", shape)
    pitch = validate.pitch("pitch", pitch)
    band = None if band is None else validate.finite("band", band)
    if not isinstance(reference, Reference):
        raise InputError(f"reference must be a Reference; got {type(reference).__name__}")
    if bounds is None:
        bounds = np.array([pos.min(0), pos.max(0)]) if len(pos) else np.zeros((2, 3))
    # what the hologram will hold, checked now: a bad field is found before the recording
    info = HologramInfo(wavelengths=wavelengths, pitch=pitch, shape=shape,
                        reference_angle=reference.angle, reference_azimuth=reference.azimuth,
                        bounds=bounds, band=band or 0.0, channels=channels,
                        plate=np.eye(4) if plate is None else plate, point_density=point_density,
                        keeps_object_wave=bool(keep_object_wave))
    memory.check_host(f"a {shape[1]}x{shape[0]} hologram of {len(wavelengths)} wavelengths",
                      HOST_BYTES * len(wavelengths) * math.prod(shape))
    for lam in wavelengths:
        reference.check(lam, pitch)
    groups = {lam: [c for c, other in enumerate(wavelengths) if other == lam] for lam in wavelengths}
    objects = {}
    for g, (lam, chans) in enumerate(groups.items()):  # equal wavelengths share one pass
        objects.update(zip(chans, point_wave(
            pos, amplitude[:, chans], wavelength=lam, pitch=pitch, shape=shape,
            obliquity=obliquity, method=method, band=band,
            progress=jobs.scaled(progress, g / len(groups), (g + 1) / len(groups)))))
    intensity, waves, amplitudes = [], [], []
    for c, lam in enumerate(wavelengths):
        o = objects[c]
        if extra_wave is not None:
            o = o + extra_wave(c, lam)
        if not np.isfinite(o).all():  # never a hologram of NaN: it would be written as one
            raise RuntimeError(f"the object wave at λ = {lam:.4g} m holds non-finite samples "
                               f"(the OpenCL device's arithmetic failed); nothing was recorded")
        a_r = math.sqrt(reference.beam_ratio * max(float(np.mean(np.abs(o) ** 2)), 1e-30))
        intensity.append(interfere(o, reference_wave(shape, wavelength=lam, pitch=pitch,
                                                     reference=reference, amplitude=a_r)))
        waves.append(o)
        amplitudes.append(a_r)
    return Hologram(info=info, intensity=np.stack(intensity),
                    object_wave=np.stack(waves) if keep_object_wave else None,
                    reference_amplitudes=tuple(amplitudes))


def point_amplitudes(positions, colours, wavelengths, phases=None, seed=0, *, empty_ok=False):
    """(positions (N, 3) [m], wavelengths [m], complex amplitudes √I·e^{iφ0} (N, C)) of point
    emitters, every argument checked (as :func:`record_points` takes them); the random phases
    drawn from ``seed`` are the same wherever the points are recorded (whole or by tiles)."""
    pos = _array("positions", positions, "an (N, 3) array of finite coordinates [m]", (-1, 3))
    if not pos.size and not empty_ok:
        raise InputError("positions holds no points: there is nothing to record")
    wavelengths = np.atleast_1d(_array("wavelengths", wavelengths, "wavelengths [m]", None))
    if wavelengths.ndim != 1 or not len(wavelengths):
        raise InputError(f"wavelengths must hold at least one wavelength [m]; got "
                         f"{wavelengths.tolist()!r}")
    wavelengths = tuple(validate.wavelength("wavelengths", w) for w in wavelengths)
    memory.check_host(f"{len(pos)} point emitters of {len(wavelengths)} wavelengths",
                      point_bytes(len(pos), len(wavelengths)))
    cols = _array("colours", colours, f"an (N, {len(wavelengths)}) array of intensities, one "
                  f"column per wavelength, N = {len(pos)} points", (len(pos), len(wavelengths)))
    if not np.isfinite(cols).all() or (cols < 0).any() or (cols > MAX_INTENSITY).any():
        raise InputError(f"colours must be finite intensities in [0, {MAX_INTENSITY:g}]; got "
                         f"values from {cols.min():.3g} to {cols.max():.3g}")
    if phases is None:
        phases = np.random.default_rng(validate.seed(seed)).uniform(0, 2 * np.pi, len(pos))
    phases = _array("phases", phases, f"{len(pos)} finite phases [rad]", (len(pos),))
    if not np.isfinite(phases).all():
        raise InputError("phases must be finite [rad]; they hold NaN or infinite values")
    return pos, wavelengths, np.sqrt(cols) * np.exp(1j * phases)[:, None]


def _array(name, value, allowed, shape) -> np.ndarray:
    """``value`` as float64, reshaped to ``shape`` (None: as it is), or :class:`InputError`
    naming ``name`` and what is ``allowed``."""
    try:
        a = np.asarray(value, np.float64)
        return a if shape is None else a.reshape(shape)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be {allowed}; got shape {np.shape(value)}") from None


@validate.scale_free()
def record_hologram(emitters=(), *, plate: Plate, triangles=(), camera=None, zone=None,
                    zone_margin=DEFAULT_ZONE_MARGIN, resolution=None, max_resolution=2048,
                    wavelength=None, encoding="complex", depth=True, seed=0, method="zone",
                    cull=True, code=None, budget=(None, None),
                    progress: jobs.Progress = None) -> Hologram:
    """Record a scene in world metres onto ``plate``, choosing the optics automatically
    (:mod:`holo_core.plate.sampling`; the choice is logged and stored in the hologram).

    Parameters
    ----------
    emitters : Mesh, sequence of Mesh, or (positions (N, 3) [m], colours (N, 3))
        World-space surfaces, or bare point emitters. Colours are linear RGB intensities.
    plate : Plate
    triangles : sequence of Mesh
        World-space meshes recorded as textured triangles (their texture, else the mean of
        their corners' colours): with ``method='zone'`` as the other meshes; with a point
        sum, each carried to the plate by tilted-plane propagation.
    camera : holo_core.scene.camera.Camera, optional
        With ``method='zone'``: the zone's reference view where the zone does not give one
        (:func:`record_plate`). With a point sum, it sizes the cone and the wavelength to
        this view (:func:`holo_core.plate.sampling.choose`).
    zone, zone_margin, code, budget
        As for :func:`record_plate` (the budget applies to plates of meshes).
    encoding
        A point sum's: 'complex' (the object wave, the default) or 'intensity' (|O + R|²); a
        plate of meshes is complex (:func:`record_plate`).
    resolution, max_resolution
        A point sum's samples (:func:`holo_core.plate.sampling.choose`); a plate of meshes
        takes what its zone asks (:mod:`holo_core.plate.plan`).
    wavelength
        λ1 [m] instead of the chosen one.
    depth : bool
        Also record the depth partner λ2 (Sect. VII-C).
    seed : int
        Seeds the emitters' random phases (and the mesh sampling).
    method : {'zone', 'auto', 'direct', 'wrp'}
        'zone' (the default for meshes): the plate as a scene asset, independent of any
        camera, with occlusion, its samples against the carrier converging on its zone
        (:func:`record_plate`). Bare points and the others: the point sums of
        :func:`holo_core.plate.point_sources.point_wave`, without occlusion.
    cull : bool
        For a point sum with a camera, keep only the points and triangles it sees
        (:func:`holo_core.scene.mesh.visible_from`): a hologram shows surfaces hidden from its
        recording viewpoint through the ones in front, as light does not occlude itself.
    """
    from .sampling import choose
    seed = validate.seed(seed)
    if not isinstance(plate, Plate):
        raise InputError(f"plate must be a Plate; got {type(plate).__name__}")
    validate.choice("method", method, PLATE_METHODS)
    validate.choice("encoding", encoding, ENCODINGS)
    meshes = [emitters] if isinstance(emitters, Mesh) else None
    if meshes is None and all(isinstance(e, Mesh) for e in emitters):
        meshes = list(emitters)
    triangles = list(triangles)
    if method == "zone" and meshes is not None:
        if resolution is not None:
            raise InputError("resolution applies to point sums; a plate of meshes takes the "
                             "samples its zone asks (holo_core.plate.plan): give a wavelength "
                             "to change them")
        return record_plate(meshes + triangles, plate=plate, camera=camera, zone=zone,
                            zone_margin=zone_margin, wavelength=wavelength,
                            encoding=encoding, depth=depth, seed=seed, code=code,
                            budget=budget, progress=progress)
    if code is not None:
        raise InputError("code applies to plates of meshes (method 'zone'); bare points and "
                         "point sums take independent seeds")
    if method == "zone":
        method = "auto"  # bare points: no surface to be hidden by
    probe = [m.vertices for m in meshes + triangles] if meshes is not None else \
        [np.asarray(emitters[0], np.float64)] + [m.vertices for m in triangles]
    if not sum(len(p) for p in probe):
        raise InputError("record_hologram needs emitters or triangles")
    view = None
    if camera is not None:
        view = (plate.to_plate(camera.position[None])[0], camera.pixel_angle())
    local = plate.to_plate(np.concatenate(probe))
    s = choose((plate.width, plate.height), local, camera=view,
               resolution=resolution, max_resolution=max_resolution, wavelength=wavelength)
    if meshes is not None:
        parts = [sample_points(m, s.spacing, channels=3, seed=seed + i, normals=True)
                 for i, m in enumerate(meshes)]
        pos = np.concatenate([p for p, _, _ in parts] or [np.zeros((0, 3))])
        rgb = np.concatenate([np.broadcast_to(c, (len(c), 3)) for _, c, _ in parts]
                             or [np.zeros((0, 3))])
        density = 1 / s.spacing**2
        normals = np.concatenate([n for _, _, n in parts] or [np.zeros((0, 3))])
        if cull and camera is not None and len(pos):
            seen = visible_from(camera, pos, s.spacing, normals)
            pos, rgb, normals = pos[seen], rgb[seen], normals[seen]
    else:
        pos, rgb = np.asarray(emitters[0], np.float64), np.asarray(emitters[1], np.float64)
        density, normals = 0.0, None
    # the depth partner's emitters: unit intensity, times the cosine towards the camera, so
    # that its image is the projected area covered (a tilted surface holds more emitters)
    cover = np.ones(len(pos)) if normals is None or camera is None else \
        facing(camera.position, pos, normals)
    prims = [replace(p, corners=plate.to_plate(p.corners)) for m in triangles
             for p in mesh_primitives(m, visible_to=camera if cull else None,
                                         spacing=s.spacing)]  # in the plate's frame
    if prims:
        density = 1 / s.spacing**2
    rgb = np.asarray(rgb, np.float64).reshape(len(pos), 3)
    wavelengths, channels, colours = [s.wavelength] * 3, ["R", "G", "B"], [rgb]
    if depth:
        wavelengths.append(s.depth_wavelength)
        channels.append("Z")
        colours.append(cover[:, None])
    reference = Reference(angle=s.reference_angle)
    split = 0.1 if prims else 1.0  # the triangles' propagations dominate where there are any
    recorded = record_points(plate.to_plate(pos), np.concatenate(colours, 1), shape=s.shape,
                         pitch=s.pitch, wavelengths=tuple(wavelengths), seed=seed,
                         reference=reference, plate=plate.matrix_world, method=method,
                         band=s.band, channels=channels, point_density=density,
                         extra_wave=_triangle_waves(prims, s, wavelengths, channels, view, seed,
                                                    jobs.scaled(progress, split, 1.0))
                         if prims else None, progress=jobs.scaled(progress, 0.0, split),
                         bounds=np.array([local.min(0), local.max(0)]))
    if zone is None and camera is not None:
        zone = plate.zone or plate.zone_for(camera, zone_margin)
    if encoding == "complex":
        return replace(recorded, intensity=None, encoding="complex", reference_amplitudes=(),
                       reference_angle=0.0, zone=zone or plate.zone)
    return replace(recorded, zone=zone or plate.zone)


def _triangle_waves(prims, s, wavelengths, channels, view, seed, progress: jobs.Progress = None):
    """``record_points``' ``extra_wave`` for textured primitives (in the plate's frame) recorded
    with the sampling ``s``: per channel (``channels``, at ``wavelengths`` [m]) their summed wave;
    ``view`` = (camera position [m], pixel angle [rad]) or None. One pass per wavelength serves
    all its channels; ``progress`` hears of every primitive."""
    shortest = min(wavelengths)
    seconds = len(prims) * len(set(wavelengths)) * math.prod(grid.padded_shape(s.shape, 2)) \
        * ROTATION_SECONDS
    (log.warning if seconds > SLOW_TRIANGLES else log.info)(
        "triangles: %d primitives, about %.0f s to record on a 2-core CPU (a rotation and a "
        "propagation per primitive and wavelength); points record tessellated meshes much "
        "faster", len(prims), seconds)
    # a surface field u radiates like points of density ρ and amplitude A when u = A·√ρ·λ/q
    # (q² per sample, the 1/λ of Eq. 7) over the obliquity cos α of Eq. 7 towards the viewer
    # (the camera, else the plate's normal), which isotropic points do not have
    frames = [p.frame() for p in prims]
    pitches = [surface_pitch(p, wavelength=shortest, pitch=s.pitch) for p in prims]
    toward = [abs(m[2, 2]) if view is None else
              float(facing(view[0], centre[None], m[:, 2][None])[0]) for m, centre in frames]

    def intensities(i, p, lam, chans):
        """Per channel in ``chans`` (all at ``lam`` [m]): the primitive's texture as surface
        intensity (the depth partner: unit intensity times its coverage seen by the camera)."""
        gain = (lam / (pitches[i] * s.spacing * max(toward[i], MIN_OBLIQUITY))) ** 2
        cover = 1.0 if view is None else toward[i]
        return [depth_texture(p.texture)[..., 0] * gain * cover
                if channels[c] == "Z" else p.texture[..., c] * gain for c in chans]

    def waves_at(lam):
        """The waves of every channel at ``lam`` [m]. A single-colour primitive's channels
        differ only in amplitude: one propagation serves them all."""
        chans = [c for c, other in enumerate(wavelengths) if other == lam]
        totals = np.zeros((len(chans),) + s.shape, np.complex128)
        for i, p in enumerate(prims):
            jobs.report(progress, passes.index(lam) * len(prims) + i, len(passes) * len(prims))
            texs = intensities(i, p, lam, chans)
            flat = all(t.shape[:2] == (1, 1) for t in texs)
            for k, tex in enumerate([np.ones((1, 1))] if flat else texs):
                wave = primitive_wave(replace(p, texture=tex[..., None]), wavelength=lam,
                                         pitch=s.pitch, shape=s.shape, seed=seed + 7919 * (i + 1),
                                         sampled_for=shortest)
                if flat:
                    totals += np.sqrt([t[0, 0] for t in texs])[:, None, None] * wave
                else:
                    totals[k] += wave
        # the points' cone, in angle: the band the off-axis reference leaves free
        return {c: cone_filter(t, wavelength=lam, pitch=s.pitch, band=s.band)
                for c, t in zip(chans, totals)}

    done, passes = {}, list(dict.fromkeys(wavelengths))  # the order record_points asks for them

    def wave(c, lam):
        if lam not in done:
            done[lam] = waves_at(lam)
        return done[lam].pop(c)
    return wave


# --- plates as scene assets ------------------------------------------------------------------

PLATE_METHODS = ("zone", "auto", "direct", "wrp")


def record_plate(meshes, *, plate: Plate, camera=None, zone: ViewingZone | None = None,
                 zone_margin=DEFAULT_ZONE_MARGIN, wavelength=None, depth=True, seed=0,
                 code=None, encoding="complex", budget=(None, None), url=None, tile=None,
                 scheduler=None, overwrite=False, progress: jobs.Progress = None,
                 dashboard=None) -> Hologram:
    """A plate hologram of ``meshes`` (world metres), independent of any camera: what it
    records depends on the meshes, the plate's placement and size, the viewing zone and the
    views' sharpness (:mod:`holo_core.plate.plan`). Its samples are the object wave against
    the carrier converging on the zone's centre (:mod:`.carrier`), as many as the zone can
    see; every emitter is seen from the zone points it is seen from (:mod:`.emitters`:
    occlusion by depth buffers over the zone), its light summed onto its footprint
    (:mod:`.zone_sum`).

    Parameters
    ----------
    meshes : Mesh or sequence of Mesh
        World-space surfaces; colours are linear RGB intensities.
    plate : Plate
    camera : Camera, optional
        The zone's reference view where the zone does not say: its pupil and pixel angle
        set the wavelength (λ = D·Δ/2: its views resolve a fine pixel); and where no zone is
        given, the zone covers its pupil with ``zone_margin`` [m] around it.
    zone : ViewingZone, optional
        The region [m, the plate's frame] the plate will be looked at from; default
        ``plate.zone``, else from ``camera``.
    wavelength : float, optional
        λ1 [m] instead of the planned one.
    depth : bool
        Also record the depth partner λ2 (Sect. VII-C).
    seed : int
        Seeds the emitters' random phases.
    code : (k, m), optional
        Look k of m² with the emitters' phases shifted by 2π·(k1·i + k2·j)/m on the lattice
        cells (i, j) they lie in (k = k1·m + k2): the mean intensity of the m² looks has no
        cross terms between emitters of neighbouring cells (the looks' speckle cancels
        where random looks would only average it down).
    encoding : 'complex'
        The object wave (against its carrier); a display's or a print's intensity pattern is
        made from it (:mod:`holo_core.phase.display`).
    budget : (memory, disk) [bytes]
        What the recording may hold in memory and the plate take on disk (None: no limit);
        a plate that needs more is refused before any work, with its sizes (in memory, the
        whole plate; tiled, one tile).
    url : str or path, optional
        Record tile by tile into the tiled store there, on Dask, and return it opened
        (:func:`holo_core.plate.tiles.record_looks_tiled`: ``tile`` samples a side, a
        multiple of 256, by default fitted to the plate (:func:`holo_core.plate.plan.
        fitted_tile`); ``scheduler``, ``overwrite``, ``dashboard`` as there). Default: the
        whole plate in memory.
    progress : callable, optional
        Called with the fraction done (rows in memory, tiles in a store).
    """
    return _record_codes(meshes, codes=(code,), urls=None if url is None else [url],
                         plate=plate, camera=camera, zone=zone, zone_margin=zone_margin,
                         wavelength=wavelength, depth=depth, seed=seed, encoding=encoding,
                         budget=budget, tile=tile, scheduler=scheduler, overwrite=overwrite,
                         progress=progress, dashboard=dashboard)[0]


@validate.scale_free()  # as record_hologram: the renderer's jobs come this way
def record_looks(meshes, *, looks: int, plate: Plate, camera=None,
                 zone: ViewingZone | None = None, zone_margin=DEFAULT_ZONE_MARGIN,
                 wavelength=None, depth=True, seed=0, budget=(None, None), urls=None,
                 tile=None, scheduler=None, overwrite=False, progress: jobs.Progress = None,
                 dashboard=None) -> list[Hologram]:
    """``looks`` looks of one plate (:func:`record_plate`'s arguments), recorded in memory in
    one pass: the coded looks of ``seed`` (:func:`look_code`) where ``looks`` allows, else
    seeds ``seed``, ``seed`` + 1, …. The looks differ only in their emitters' phases, so one
    sum carries them all as further channels: each emitter's distance, phase and visibility
    at a sample are found once for every look (on the shot's plate, two looks in 36 s where
    one after the other took 53 s). ``budget`` covers all the looks held together. ``urls``
    (one a look): each look tile by tile into its own store, every tile's looks summed at
    once (:func:`holo_core.plate.tiles.record_looks_tiled`; ``tile``, ``scheduler``,
    ``overwrite``, ``dashboard`` as for :func:`record_plate`)."""
    looks = validate.integer("looks", looks, 1)
    return _record_codes(meshes, codes=tuple(look_code(k, looks) for k in range(looks)),
                         urls=urls, plate=plate, camera=camera, zone=zone,
                         zone_margin=zone_margin, wavelength=wavelength, depth=depth, seed=seed,
                         budget=budget, tile=tile, scheduler=scheduler, overwrite=overwrite,
                         progress=progress, dashboard=dashboard)


def _record_codes(meshes, *, codes, urls, tile, scheduler, overwrite, dashboard, progress,
                  **settings) -> list[Hologram]:
    """The looks ``codes`` of a plate (``settings``: :func:`prepare_plate`'s other arguments)
    in one pass: in memory, or with ``urls`` tile by tile, a store a look."""
    if urls is not None:
        from .tiles import record_looks_tiled
        return record_looks_tiled(meshes, urls=list(urls), codes=codes, tile=tile,
                                  scheduler=scheduler, overwrite=overwrite, progress=progress,
                                  dashboard=dashboard, **settings)
    return prepare_plate(meshes, codes=codes, **settings).record(progress)


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class PlateRecording:
    """A plate of meshes ready to be summed (:func:`prepare_plate`): what it will be
    (``info``, its carrier included), where its samples lie (``window``), its emitters per
    wavelength (``groups``: (λ [m], :class:`ZoneEmitters`) in channel order) and what it was
    made from (``plan``, ``meshes`` in the plate's frame, ``seed``, ``codes``: each look's
    code, or None for the look of seed + its index). Any block of it is the same sum computed
    alone (:meth:`sums`): recorded whole in memory (:meth:`record`) or tile by tile
    (:mod:`.tiles`), its samples are the same. Every look is summed in one pass
    (:func:`record_looks`): the groups' channels are the looks' channels, look after look
    within each wavelength, so a block's samples are (R₀ G₀ B₀ R₁ G₁ B₁ … Z₀ Z₁ …)
    (:meth:`look_channels`)."""

    info: HologramInfo
    window: ZoneWindow
    groups: tuple
    plan: PlatePlan
    meshes: tuple
    seed: int
    codes: tuple

    @property
    def looks(self) -> int:
        return len(self.codes)

    def look_columns(self, look: int) -> list[slice]:
        """Per group, the columns of its emitters' amplitudes that are look ``look``'s."""
        return [slice(look * n, (look + 1) * n)
                for n in (em.amplitude.shape[1] // self.looks for _, em in self.groups)]

    def look_channels(self, look: int) -> list[int]:
        """The channels of a block's samples (:meth:`region`) that are look ``look``'s, in the
        hologram's channel order."""
        out, first = [], 0
        for (_, em), columns in zip(self.groups, self.look_columns(look)):
            out += range(first + columns.start, first + columns.stop)
            first += em.amplitude.shape[1]
        return out

    def look_seed(self, look: int) -> int:
        """The seed of look ``look``'s random phases (its code shifts them, where it has one)."""
        return _look_seed(self.seed, self.codes, look)

    @property
    def shape(self) -> tuple[int, int]:
        return self.window.shape

    def sums(self, rt=None) -> list[ZoneSum]:
        """The :class:`ZoneSum` of the wavelengths, its emitters on the device: the depth
        pair's partner summed with the colours in one pass where their channels an emitter
        fit the kernel's accumulators (FUSED_CHANNELS), else one a wavelength."""
        (lam, em), *rest = self.groups
        per_emitter = sum(e.amplitude.shape[1] // (1 if e.mixing is None else len(e.mixing))
                          for _, e in self.groups)
        if len(rest) == 1 and per_emitter <= FUSED_CHANNELS:
            return [ZoneSum(em, self.window, lam, rt, partner=rest[0])]
        return [ZoneSum(e, self.window, lam, rt) for lam, e in self.groups]

    def region(self, sums, row0: int, col0: int, rows: int, cols: int) -> np.ndarray:
        """The samples (C, rows, cols) complex64 of a block (row0, col0 multiples of 256),
        every channel; :class:`RuntimeError` if any is not finite (never written)."""
        samples = np.concatenate([s.region(row0, col0, rows, cols) for s in sums])
        if not np.isfinite(samples).all():  # never a hologram of NaN: it would be written
            _not_finite(row0, col0, rows, cols)
        return samples

    def record(self, progress: jobs.Progress = None) -> list[Hologram]:
        """Each look's whole plate in memory, summed in bands of rows, each channel read from
        the device into its look's plane (no block on the host: its copies cost 2.3 s of the
        shot's 28 s)."""
        rows, cols = self.shape
        channels = len(self.info.wavelengths)
        waves = [memory.aligned_zeros((channels, rows, cols)) for _ in range(self.looks)]
        # each sum's channel c goes to plane i of look l
        where, first = [], 0
        for s in self.sums():
            where.append((s, [(look, i, b - first) for look in range(self.looks)
                              for i, b in enumerate(self.look_channels(look))
                              if first <= b < first + s.channels]))
            first += s.channels
        for r0 in range(0, rows, BAND_ROWS):
            here = min(BAND_ROWS, rows - r0)
            for s, planes in where:
                block = s.on_device(r0, 0, here, cols)
                if nonfinite_count(s.rt, block):  # never a hologram of NaN
                    _not_finite(r0, 0, here, cols)
                for look, i, c in planes:
                    read(block[c], out=waves[look][i, r0:r0 + here])
            jobs.report(progress, r0 + here, rows)
        return [Hologram(info=self.info, object_wave=w) for w in waves]


def _not_finite(row0, col0, rows, cols):
    raise RuntimeError(f"the object wave holds non-finite samples in rows {row0}-"
                       f"{row0 + rows - 1}, columns {col0}-{col0 + cols - 1} (the OpenCL "
                       f"device's arithmetic failed); nothing was recorded")


BAND_ROWS = 256  # rows of the plate summed at once in memory (a multiple of the block lists')
FUSED_CHANNELS = 8  # channels an emitter the zone sum carries in one pass at most: its
                    # accumulators (32 columns x 16 lanes x re, im) stay within a core's L1


def plate_plan(meshes, *, plate: Plate, camera=None, zone: ViewingZone | None = None,
               zone_margin=DEFAULT_ZONE_MARGIN, wavelength=None, tile=None
               ) -> tuple[PlatePlan, list, ViewingZone]:
    """(the plan, the meshes in the plate's frame, the zone) of a plate of ``meshes`` (the
    arguments as :func:`record_plate` takes them): what its recording will hold and cost,
    before any emitter is found."""
    if not isinstance(plate, Plate):
        raise InputError(f"plate must be a Plate; got {type(plate).__name__}")
    meshes = [meshes] if isinstance(meshes, Mesh) else list(meshes)
    if not meshes or not all(isinstance(m, Mesh) for m in meshes):
        raise InputError("meshes must be a Mesh or a non-empty sequence of Mesh")
    memory.check_host(f"moving {sum(len(m.triangles) for m in meshes)} triangles onto the "
                      f"plate", sum(320.0 * len(m.triangles) + 96.0 * len(m.vertices)
                                    for m in meshes))
    local = [replace(m, vertices=plate.to_plate(m.vertices)) for m in meshes]
    every = np.concatenate([m.vertices for m in local])
    bounds = np.array([every.min(0), every.max(0)])
    if bounds[1, 2] >= 0:
        raise InputError(f"the objects must lie behind the plate (z < 0 in its frame); they "
                         f"reach z = {bounds[1, 2]:.4g} m")
    zone = resolve_zone(plate, zone, camera, zone_margin, bounds)
    pixel = zone.pixel or (camera.pixel_angle() if camera is not None else None)
    if pixel is None and wavelength is None:
        raise InputError("a plate needs the sharpness of its views: a camera, a zone with its "
                         "pixel angle, or a wavelength")
    p = plan((plate.width, plate.height), bounds, zone=zone, pixel_angle=pixel or 1.0,
             wavelength=wavelength, **({} if tile is None else {"tile": tile}))
    count = crossing_count(local, np.asarray(zone.centre, np.float64), zone_frame(zone, bounds),
                           p.spacing)  # what finding the emitters holds, before it starts
    memory.check_host(f"finding the emitters of {sum(len(m.triangles) for m in local)} "
                      f"triangles ({count:.3g} crossings of the zone's rays: many large "
                      f"triangles through each other cross many)", CROSSING_BYTES * count)
    return p, local, zone


def prepare_plate(meshes, *, plate: Plate, camera=None, zone: ViewingZone | None = None,
                  zone_margin=DEFAULT_ZONE_MARGIN, wavelength=None, depth=True, seed=0,
                  code=None, encoding="complex", tile=None, budget=(None, None),
                  codes=None) -> PlateRecording:
    """The emitters, visibility tables and sampling of a plate of ``meshes`` (the arguments
    as :func:`record_plate` takes them), before any sum: the plan, the emitters the zone sees
    with their amplitudes. The host's memory and the ``budget`` are checked for the whole
    plate, or with ``tile`` (samples a side) for one tile of it. ``codes`` (in place of
    ``code``): several looks summed at once (:func:`record_looks`), look l's phases coded
    by codes[l], or where that is None drawn from ``seed`` + l."""
    if encoding != "complex":
        raise InputError(f"encoding must be 'complex' for a plate of meshes (a display's "
                         f"intensity pattern is made from it: holo_core.phase.display); got "
                         f"{encoding!r}"[:200])
    seed = validate.seed(seed)
    if codes is not None and code is not None:
        raise InputError("give code (one look) or codes (several), not both")
    codes = (code,) if codes is None else tuple(codes)
    p, local, zone = plate_plan(meshes, plate=plate, camera=camera, zone=zone,
                                zone_margin=zone_margin, wavelength=wavelength, tile=tile)
    every = np.concatenate([m.vertices for m in local])
    bounds = np.array([every.min(0), every.max(0)])
    log.info("sampling: %s", p.describe())
    channels = ["R", "G", "B"] + (["Z"] if depth else [])
    held_channels = len(channels) * len(codes)  # every look's, in one pass
    p.check_budget(memory=budget[0], disk=budget[1], channels=len(channels),
                   tiled=tile is not None, held=len(codes))
    held = f"a {p.tile}x{p.tile} tile" if tile is not None else f"a {p.shape[1]}x{p.shape[0]} plate"
    memory.check_host(f"{held} of {held_channels} channels",
                      p.memory_bytes(held_channels, tiled=tile is not None))
    em = zone_emitters(local, zone, p.spacing, layers=LAYERS)
    if not len(em):
        raise InputError(f"no surface of the meshes is seen from the viewing zone "
                         f"({zone.describe()})")
    # |a| = √I·|p − Z|: each emitter's light reaches the zone's centre with its own amplitude
    reach = np.linalg.norm(em.position - np.asarray(zone.centre), axis=1)
    waves = [np.exp(1j * _phases(em, _look_seed(seed, codes, look), c)) * reach
             for look, c in enumerate(codes)]
    partial = em.visibility.reshape(len(em), -1).min(1) < 1
    rows = np.where(partial, np.cumsum(partial) - 1, -1).astype(np.int32)
    table = np.round(em.visibility[partial] * 255).astype(np.uint8)
    window = ZoneWindow(origin=p.origin, pitch=p.pitch, row_pitch=p.row_pitch, shape=p.shape,
                        centre=zone.centre, half_extents=zone.half_extents, rim=RIM)
    amplitudes = [(p.wavelength, np.concatenate([np.sqrt(em.colour) * wave[:, None]
                                                 for wave in waves], 1))]
    if depth:
        amplitudes.append((p.depth_wavelength, np.stack(waves, 1)))
    classes, mixing = _code_classes(em, codes)
    groups = tuple((lam, ZoneEmitters(position=em.position, amplitude=a, visibility=rows,
                                      table=table, grid=em.grid, classes=classes,
                                      mixing=mixing)) for lam, a in amplitudes)
    distance = float(np.linalg.norm(bounds.mean(0) - np.asarray(zone.centre)))
    wavelengths = (p.wavelength,) * 3 + ((p.depth_wavelength,) if depth else ())
    info = HologramInfo(shape=p.shape, encoding="complex", wavelengths=wavelengths,
                        pitch=p.pitch, band=max(p.band), channels=tuple(channels),
                        point_density=1 / (p.spacing * distance) ** 2, zone=zone,
                        bounds=bounds, plate=plate.matrix_world,
                        carrier=Carrier(centre=zone.centre, origin=p.origin,
                                        row_pitch=p.row_pitch))
    return PlateRecording(info=info, window=window, groups=groups, plan=p, meshes=tuple(local),
                          seed=seed, codes=tuple(None if c is None else tuple(c) for c in codes))


def _code_classes(em, codes) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(each emitter's class, the looks' factors (looks, classes)) where the looks are coded
    looks of one seed (:func:`_phases`): look l's phases are look 0's plus 2π·s_l/m, s_l
    taking m values over the lattice cells, so the emitters fall in the classes of equal
    shifts and each look is the classes' sums times exp(2πi·(s_l − s_0)/m)
    (:class:`ZoneEmitters`). (None, None) for a single look or independent ones."""
    if len(codes) < 2 or any(c is None for c in codes) or len({c[1] for c in codes}) > 1:
        return None, None
    m = codes[0][1]
    shifts = np.stack([_code_steps(em, code) % m for code in codes], 1)
    kinds, classes = np.unique(shifts, axis=0, return_inverse=True)
    mixing = np.exp(2j * np.pi * (kinds - kinds[:, :1]).T / m)
    return classes.reshape(-1).astype(np.int32), mixing


def _look_seed(seed: int, codes, look: int) -> int:
    """The seed of look ``look``'s phases: the plate's, shifted by the look's code where it
    has one, else seed + look (independent looks)."""
    return seed + (0 if codes[look] else look)


def _phases(em, seed: int, code) -> np.ndarray:
    """The emitters' random phases [rad] of ``seed``, shifted by ``code`` (k, m): 2π·(k1·i +
    k2·j)/m on the lattice cells (i, j) they lie in (k = k1·m + k2; :func:`record_plate`)."""
    phases = np.random.default_rng(seed).uniform(0, 2 * np.pi, len(em))
    if code is not None:
        phases = phases + 2 * np.pi * _code_steps(em, code) / code[1]
    return phases


def _code_steps(em, code) -> np.ndarray:
    """k1·i + k2·j (int) for the emitters' lattice cells (i, j) and code (k1·m + k2, m): their
    phases are shifted by 2π/m times it."""
    k1, k2 = divmod(code[0], code[1])
    return k1 * em.cell[:, 1] + k2 * em.cell[:, 0]


def look_code(k: int, n: int):
    """``code`` of look ``k`` of ``n`` looks of one plate (:func:`record_plate`, one seed for
    all): n = m² gives the m² looks whose mean has no cross terms between emitters of
    neighbouring lattice cells, n = 2 the checkerboard pair (looks 0 and 3 of m = 2), whose
    mean has none between the four nearest cells (on the plate scene: 28.0–28.5 dB against
    29.3–30.0 for four and 25.6–26.1 for one). Other n: None (independent random phases, one
    seed per look)."""
    n = validate.integer("looks", n, 1)
    k = validate.integer("look", k, 0, n - 1)
    m = math.isqrt(n)
    if n == 2:
        return (3 * k, 2)
    return (k, m) if m > 1 and m * m == n else None


def resolve_zone(plate: Plate, zone, camera, margin, bounds) -> ViewingZone:
    """The viewing zone of a recording: ``zone``, else the plate's own, else one around
    ``camera``'s pupil (``margin`` [m]), else the plate's extent mirrored at the objects'
    distance in front of it (``bounds`` (2, 3) [m], the plate's frame)."""
    if zone is not None:
        if not isinstance(zone, ViewingZone):
            raise InputError(f"zone must be a ViewingZone or None; got {type(zone).__name__}")
        return zone
    if plate.zone is not None:
        return plate.zone
    if camera is not None:
        return plate.zone_for(camera, margin)
    distance = -float(bounds[1, 2])
    zone = ViewingZone(centre=(0.0, 0.0, distance),
                       half_extents=(plate.width / 2, plate.height / 2, distance / 4))
    log.info("plate: no camera and no viewing zone given: %s", zone.describe())
    return zone


def encode(waves, *, wavelengths, pitch, band, encoding, reference_angle=0.0, plate=None,
           bounds=None, channels=(), point_density=0.0, zone=None, beam_ratio=4.0,
           keep_object_wave=False) -> Hologram:
    """The hologram of object waves ``waves`` (C, H, W) on the plate: 'complex' keeps them;
    'intensity' records H = |O + R|² (Eq. 19) with the plane reference at ``reference_angle``
    [rad], |R|² = ``beam_ratio``·mean|O|², each wave limited to its cone sin θ <= ``band``
    first (so that the carrier separates it from the twin and |O|² terms)."""
    common = {"wavelengths": wavelengths, "pitch": pitch, "band": band, "channels": channels,
              "point_density": point_density, "zone": zone, "bounds": bounds,
              "plate": np.eye(4) if plate is None else plate}
    waves = np.asarray(waves)
    if not np.isfinite(waves).all():  # never a hologram of NaN: it would be written as one
        raise RuntimeError("the object wave holds non-finite samples (the OpenCL device's "
                           "arithmetic failed); nothing was recorded")
    if encoding == "complex":
        return Hologram(object_wave=waves.astype(np.complex64), encoding="complex", **common)
    reference = Reference(angle=reference_angle)
    shape = waves.shape[1:]
    intensity, kept, amplitudes = [], [], []
    for o, lam in zip(waves, wavelengths):
        reference.check(lam, pitch)
        o = cone_filter(o, wavelength=lam, pitch=pitch, band=band)
        a_r = math.sqrt(beam_ratio * max(float(np.mean(np.abs(o) ** 2)), 1e-30))
        intensity.append(interfere(o, reference_wave(shape, wavelength=lam, pitch=pitch,
                                                     reference=reference, amplitude=a_r)))
        kept.append(o)
        amplitudes.append(a_r)
    return Hologram(intensity=np.stack(intensity), encoding="intensity",
                    object_wave=np.stack(kept) if keep_object_wave else None,
                    reference_angle=reference.angle, reference_amplitudes=tuple(amplitudes),
                    **common)
