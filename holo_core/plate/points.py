"""The point-sum recorder (the researchers' route, beside the plate of meshes): holograms of
point emitters, one per wavelength (Sect. V-B), each the sum of the points' spherical waves
(:mod:`.point_sources`, Eq. 16-18) and of textured triangles' waves (:mod:`.triangles`),
complex or against a plane reference (:mod:`.reference`).

The hologram lies in the plane z = 0 of its own frame, objects at z < 0, light travelling +z.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace

import numpy as np

from .. import jobs, memory, validate
from ..propagation import grid
from ..scene.hologram import Hologram, HologramInfo
from ..scene.mesh import facing, sample_points, visible_from
from ..validate import InputError
from .point_sources import cone_filter, point_bytes, point_wave
from .reference import Reference, interfere, reference_wave
from .sampling import choose
from .triangles import depth_texture, mesh_primitives, primitive_wave, surface_pitch

DEFAULT_WAVELENGTHS = (633e-9, 532e-9, 473e-9)  # HeNe red, Nd:YAG green, DPSS blue [m]
MIN_OBLIQUITY = 0.1  # a primitive seen more edge-on than this (cos) gets no brighter
# a primitive's rotation and propagation per padded hologram sample and wavelength, a 2-core CPU's
# (docs, Performance) ...
ROTATION_SECONDS = 2e-7
SLOW_TRIANGLES = 60.0  # ... and the estimate [s] above which the user is warned
MAX_INTENSITY = 1e12  # a point's colour, at most: the float32 hologram holds sums of millions
HOST_BYTES = 40  # per sample and wavelength: object and reference waves, H, the stored copy
log = logging.getLogger(__name__)


def record_points(
    positions,
    colours,
    *,
    shape,
    pitch,
    wavelengths=DEFAULT_WAVELENGTHS,
    phases=None,
    seed=0,
    reference=Reference(),  # noqa: B008 -- frozen
    obliquity=False,
    keep_object_wave=True,
    plate=None,
    method="auto",
    band=None,
    channels=(),
    point_density=0.0,
    extra_wave=None,
    bounds=None,
    progress: jobs.Progress = None,
) -> Hologram:
    """Record the holograms of point emitters, one per wavelength.

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

    seed : int
        Seeds the random phases.
    keep_object_wave : bool
        Keep the object wave O with the intensity.
    progress : callable, optional
        Given the fraction done in [0, 1] between units of work.

    Returns
    -------
    Hologram
        One channel per wavelength: the intensity H = ``|O + R|²`` and (``keep_object_wave``)
        the object wave O.

    Raises
    ------
    InputError
        Where a point is not at z < 0, a colour is negative,
        or a setting is out of range.

    Notes
    -----
    Each point is a spherical wave A0·exp(i(kr + φ0))/r (Eq. 3); the hologram is
    H = ``|O + R|²`` (Eq. 16).

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import record_points
    >>> h = record_points(np.array([[0.0, 0.0, -2e-3]]), np.array([[1.0]]), shape=(64, 64),
    ...                   pitch=2e-6, wavelengths=(633e-9,))
    >>> h.intensity.shape, h.object_wave.shape
    ((1, 64, 64), (1, 64, 64))
    """
    pos, wavelengths, amplitude = point_amplitudes(
        positions, colours, wavelengths, phases, seed, empty_ok=extra_wave is not None
    )
    shape = validate.shape2d("shape", shape)
    pitch = validate.pitch("pitch", pitch)
    band = None if band is None else validate.finite("band", band)
    if not isinstance(reference, Reference):
        raise InputError(f"reference must be a Reference; got {type(reference).__name__}")
    if bounds is None:
        bounds = np.array([pos.min(0), pos.max(0)]) if len(pos) else np.zeros((2, 3))
    # what the hologram will hold, checked now: a bad field is found before the recording
    info = HologramInfo(
        wavelengths=wavelengths,
        pitch=pitch,
        shape=shape,
        reference_angle=reference.angle,
        reference_azimuth=reference.azimuth,
        bounds=bounds,
        band=band or 0.0,
        channels=channels,
        plate=np.eye(4) if plate is None else plate,
        point_density=point_density,
        keeps_object_wave=bool(keep_object_wave),
    )
    memory.check_host(
        f"a {shape[1]}x{shape[0]} hologram of {len(wavelengths)} wavelengths",
        HOST_BYTES * len(wavelengths) * math.prod(shape),
    )
    for lam in wavelengths:
        reference.check(lam, pitch)
    groups = {
        lam: [c for c, other in enumerate(wavelengths) if other == lam] for lam in wavelengths
    }
    objects = {}
    for g, (lam, chans) in enumerate(groups.items()):  # equal wavelengths share one pass
        objects.update(
            zip(
                chans,
                point_wave(
                    pos,
                    amplitude[:, chans],
                    wavelength=lam,
                    pitch=pitch,
                    shape=shape,
                    obliquity=obliquity,
                    method=method,
                    band=band,
                    progress=jobs.scaled(progress, g / len(groups), (g + 1) / len(groups)),
                ),
            )
        )
    intensity, waves, amplitudes = [], [], []
    for c, lam in enumerate(wavelengths):
        o = objects[c]
        if extra_wave is not None:
            o = o + extra_wave(c, lam)
        if not np.isfinite(o).all():  # never a hologram of NaN: it would be written as one
            raise RuntimeError(
                f"the object wave at λ = {lam:.4g} m holds non-finite samples "
                f"(the OpenCL device's arithmetic failed); nothing was recorded"
            )
        a_r = math.sqrt(reference.beam_ratio * max(float(np.mean(np.abs(o) ** 2)), 1e-30))
        intensity.append(
            interfere(
                o,
                reference_wave(
                    shape, wavelength=lam, pitch=pitch, reference=reference, amplitude=a_r
                ),
            )
        )
        waves.append(o)
        amplitudes.append(a_r)
    return Hologram(
        info=info,
        intensity=np.stack(intensity),
        object_wave=np.stack(waves) if keep_object_wave else None,
        reference_amplitudes=tuple(amplitudes),
    )


def point_amplitudes(positions, colours, wavelengths, phases=None, seed=0, *, empty_ok=False):
    """(positions (N, 3) [m], wavelengths [m], complex amplitudes √I·e^{iφ0} (N, C)) of point
    emitters, every argument checked (as :func:`record_points` takes them); the random phases
    drawn from ``seed`` are the same wherever the points are recorded (whole or by tiles)."""
    pos = _array("positions", positions, "an (N, 3) array of finite coordinates [m]", (-1, 3))
    if not pos.size and not empty_ok:
        raise InputError("positions holds no points: there is nothing to record")
    wavelengths = np.atleast_1d(_array("wavelengths", wavelengths, "wavelengths [m]", None))
    if wavelengths.ndim != 1 or not len(wavelengths):
        raise InputError(
            f"wavelengths must hold at least one wavelength [m]; got {wavelengths.tolist()!r}"
        )
    wavelengths = tuple(validate.wavelength("wavelengths", w) for w in wavelengths)
    memory.check_host(
        f"{len(pos)} point emitters of {len(wavelengths)} wavelengths",
        point_bytes(len(pos), len(wavelengths)),
    )
    cols = _array(
        "colours",
        colours,
        f"an (N, {len(wavelengths)}) array of intensities, one "
        f"column per wavelength, N = {len(pos)} points",
        (len(pos), len(wavelengths)),
    )
    if not np.isfinite(cols).all() or (cols < 0).any() or (cols > MAX_INTENSITY).any():
        raise InputError(
            f"colours must be finite intensities in [0, {MAX_INTENSITY:g}]; got "
            f"values from {cols.min():.3g} to {cols.max():.3g}"
        )
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


def record_scene_points(
    emitters,
    meshes,
    triangles,
    *,
    plate,
    camera,
    zone,
    zone_margin,
    resolution,
    max_resolution,
    wavelength,
    encoding,
    depth,
    seed,
    method,
    cull,
    progress: jobs.Progress = None,
) -> Hologram:
    """The point sum of a scene in world metres on ``plate`` (:func:`holo_core.plate.record.
    record_hologram`'s arguments, checked there): ``meshes`` sampled into points (or, where
    None, the bare points ``emitters``) and ``triangles`` as textured triangles, with the
    sampling chosen for the scene (:func:`holo_core.plate.sampling.choose`)."""
    probe = (
        [m.vertices for m in meshes + triangles]
        if meshes is not None
        else [np.asarray(emitters[0], np.float64)] + [m.vertices for m in triangles]
    )
    if not sum(len(p) for p in probe):
        raise InputError("record_hologram needs emitters or triangles")
    view = None
    if camera is not None:
        view = (plate.to_plate(camera.position[None])[0], camera.pixel_angle())
    local = plate.to_plate(np.concatenate(probe))
    s = choose(
        (plate.width, plate.height),
        local,
        camera=view,
        resolution=resolution,
        max_resolution=max_resolution,
        wavelength=wavelength,
    )
    if meshes is not None:
        parts = [
            sample_points(m, s.spacing, channels=3, seed=seed + i, normals=True)
            for i, m in enumerate(meshes)
        ]
        pos = np.concatenate([p for p, _, _ in parts] or [np.zeros((0, 3))])
        rgb = np.concatenate(
            [np.broadcast_to(c, (len(c), 3)) for _, c, _ in parts] or [np.zeros((0, 3))]
        )
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
    cover = (
        np.ones(len(pos))
        if normals is None or camera is None
        else facing(camera.position, pos, normals)
    )
    prims = [
        replace(p, corners=plate.to_plate(p.corners))
        for m in triangles
        for p in mesh_primitives(m, visible_to=camera if cull else None, spacing=s.spacing)
    ]  # in the plate's frame
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
    recorded = record_points(
        plate.to_plate(pos),
        np.concatenate(colours, 1),
        shape=s.shape,
        pitch=s.pitch,
        wavelengths=tuple(wavelengths),
        seed=seed,
        reference=reference,
        plate=plate.matrix_world,
        method=method,
        band=s.band,
        channels=channels,
        point_density=density,
        extra_wave=_triangle_waves(
            prims, s, wavelengths, channels, view, seed, jobs.scaled(progress, split, 1.0)
        )
        if prims
        else None,
        progress=jobs.scaled(progress, 0.0, split),
        bounds=np.array([local.min(0), local.max(0)]),
    )
    if zone is None and camera is not None:
        zone = plate.zone or plate.zone_for(camera, zone_margin)
    if encoding == "complex":
        return replace(
            recorded,
            intensity=None,
            encoding="complex",
            reference_amplitudes=(),
            reference_angle=0.0,
            zone=zone or plate.zone,
        )
    return replace(recorded, zone=zone or plate.zone)


def _triangle_waves(prims, s, wavelengths, channels, view, seed, progress: jobs.Progress = None):
    """``record_points``' ``extra_wave`` for textured primitives (in the plate's frame) recorded
    with the sampling ``s``: per channel (``channels``, at ``wavelengths`` [m]) their summed wave;
    ``view`` = (camera position [m], pixel angle [rad]) or None. One pass per wavelength serves
    all its channels; ``progress`` hears of every primitive."""
    shortest = min(wavelengths)
    seconds = (
        len(prims)
        * len(set(wavelengths))
        * math.prod(grid.padded_shape(s.shape, 2))
        * ROTATION_SECONDS
    )
    (log.warning if seconds > SLOW_TRIANGLES else log.info)(
        "triangles: %d primitives, about %.0f s to record on a 2-core CPU (a rotation and a "
        "propagation per primitive and wavelength); points record tessellated meshes much "
        "faster",
        len(prims),
        seconds,
    )
    # a surface field u radiates like points of density ρ and amplitude A when u = A·√ρ·λ/q
    # (q² per sample, the 1/λ of Eq. 7) over the obliquity cos α of Eq. 7 towards the viewer
    # (the camera, else the plate's normal), which isotropic points do not have
    frames = [p.frame() for p in prims]
    pitches = [surface_pitch(p, wavelength=shortest, pitch=s.pitch) for p in prims]
    toward = [
        abs(m[2, 2]) if view is None else float(facing(view[0], centre[None], m[:, 2][None])[0])
        for m, centre in frames
    ]

    def intensities(i, p, lam, chans):
        """Per channel in ``chans`` (all at ``lam`` [m]): the primitive's texture as surface
        intensity (the depth partner: unit intensity times its coverage seen by the camera)."""
        gain = (lam / (pitches[i] * s.spacing * max(toward[i], MIN_OBLIQUITY))) ** 2
        cover = 1.0 if view is None else toward[i]
        return [
            depth_texture(p.texture)[..., 0] * gain * cover
            if channels[c] == "Z"
            else p.texture[..., c] * gain
            for c in chans
        ]

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
                wave = primitive_wave(
                    replace(p, texture=tex[..., None]),
                    wavelength=lam,
                    pitch=s.pitch,
                    shape=s.shape,
                    seed=seed + 7919 * (i + 1),
                    sampled_for=shortest,
                )
                if flat:
                    totals += np.sqrt([t[0, 0] for t in texs])[:, None, None] * wave
                else:
                    totals[k] += wave
        # the points' cone, in angle: the band the off-axis reference leaves free
        return {
            c: cone_filter(t, wavelength=lam, pitch=s.pitch, band=s.band)
            for c, t in zip(chans, totals)
        }

    done, passes = {}, list(dict.fromkeys(wavelengths))  # the order record_points asks for them

    def wave(c, lam):
        if lam not in done:
            done[lam] = waves_at(lam)
        return done[lam].pop(c)

    return wave
