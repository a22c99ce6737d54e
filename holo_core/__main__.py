"""Command line: ``python -m holo_core devices | demo | plan | record | info | render |
import | calibrate``."""

from __future__ import annotations

import argparse
import logging
import math
import re
import sys
import warnings
from pathlib import Path

from . import units
from .validate import MAX_LENGTH, MAX_SUPERSAMPLE, MIN_LENGTH


def devices(_args) -> int:
    from .opencl import device_table
    from .opencl.icd import packaged_drivers

    rows = device_table()
    for desc, status, chosen in rows:
        print(f"  {desc}: {status}{'   <- would use' if chosen else ''}")
    if not rows:
        print("  no OpenCL device found")
    drivers = packaged_drivers()
    print(
        "packaged drivers: "
        + (
            ", ".join(f"{k} ({v})" for k, v in drivers.items())
            or "none (pip install intel-opencl-rt for Intel's CPU runtime)"
        )
    )
    if not any(chosen for *_, chosen in rows):
        print("would use: nothing usable (see the reasons above)")
        return 1
    print("choose with HOLO_DEVICE=gpu|cpu|P:D|part of a device or platform name")
    return 0


def calibrate(args) -> int:
    """Measure this machine's rates for the estimates and keep them (:mod:`.calibration`)."""
    from .calibration import calibrate as measure

    path = measure(device=args.device, say=print)
    print(f"kept in {path}")
    return 0


def demo(args) -> int:
    from .demo import run

    for path in run(args.output):
        print(path)
    return 0


POINT_OPTIONS = {
    "pitch": "--pitch",
    "wavelengths": "--wavelengths",
    "reference_angle": "--reference-angle",
    "spacing": "--spacing",
    "max_points": "--max-points",
}
ZONE_OPTIONS = {
    "camera": "--camera",
    "look_at": "--look-at",
    "zone": "--zone",
    "dolly": "--dolly",
    "zone_margin": "--zone-margin",
    "plate_size": "--plate-size",
    "focus_distance": "--focus-distance",
    "look": "--look",
}


def record(args) -> int:
    """A plate of the mesh: by default against the carrier converging on its viewing zone,
    with occlusion (``--method zone``), else a point sum (``auto``, ``direct``, ``wrp``);
    into an EXR file, or tile by tile on Dask into a store (NAME.zarr or a URL)."""
    import dataclasses

    from .io.mesh import read_mesh

    zone = args.method == "zone"
    for name, flag in (ZONE_OPTIONS if not zone else POINT_OPTIONS).items():
        if getattr(args, name) is not None:
            raise ValueError(
                f"{flag} applies to "
                + (
                    "point sums (--method auto, direct or wrp); a plate of meshes (--method zone, "
                    "the default) plans its samples and wavelength from its viewing zone"
                    if zone
                    else "a plate of meshes (--method zone, the default); a point sum records "
                    "the hologram --resolution and --pitch give"
                )
            )
    tiled = _is_store(args.output)
    if tiled:  # before the work: the store's path or URL, made absolute for the workers
        from .io.files import check_output

        out = check_output(args.output).url
    else:
        out = _output(args.output, args.mesh, "")
    mesh = read_mesh(args.mesh)
    if args.distance is not None:
        mesh = dataclasses.replace(mesh, vertices=_placed(mesh.vertices, args.distance))
    return (_record_zone if zone else _record_points)(args, mesh, out, tiled)


def _placed(vertices, distance: float):
    """``vertices`` (N, 3) [m] moved so that their nearest point is ``distance`` [m] behind
    the plate (z = 0), their box centred on its axis: ``--distance`` of ``plan`` and
    ``record`` alike."""
    lo, hi = vertices.min(0), vertices.max(0)
    return vertices - [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, hi[2] + distance]


def _plate_for(args, bounds):
    """(the plate, its reference camera, its plan of one look) for objects in ``bounds``
    (2, 3) [m], as ``record`` makes it and ``plan`` states it: the plate z = 0 of the
    world, the objects behind it, the camera (``--camera``, default on the objects' axis as
    far in front as their nearest point is behind) and zone options, the plate
    ``--plate-size`` or as wide as the light from the objects to the zone needs."""
    import numpy as np

    from .plate.plan import plan as plan_plate
    from .plate.zone_light import window_on_plate
    from .scene.plate import Plate

    bounds = np.asarray(bounds, np.float64)
    if bounds[1, 2] >= 0:
        raise ValueError(
            f"the objects must lie behind the plate (z < 0; the plate is z = 0, "
            f"the camera in front): they reach z = {bounds[1, 2]:.4g} m; give "
            f"--distance to place them"
        )
    centre = bounds.mean(0)
    cam, zone = _camera_and_zone(
        args, bounds, (centre[0], centre[1], -bounds[1, 2]), tuple(args.resolution or (640, 360))
    )
    if args.plate_size is not None:
        size = tuple(args.plate_size)
    else:  # wide enough for all the light from the objects to the zone
        lo, hi = window_on_plate(bounds, zone, math.inf, math.inf)
        size = tuple(2 * np.maximum(np.abs(lo), np.abs(hi)))
    plate = Plate(matrix_world=np.eye(4), width=size[0], height=size[1], zone=zone)
    return plate, cam, plan_plate(size, bounds, zone=zone, pixel_angle=zone.pixel, looks=1)


def _record_zone(args, mesh, out, tiled) -> int:
    """The plate of meshes: its zone and reference view from the camera options, the plate
    (z = 0 of the world, the mesh behind it) as large as the light to the zone needs."""
    from .io.hologram import write_hologram
    from .plate.look_codes import look_code
    from .plate.looks import record_plate

    v = mesh.vertices
    plate, cam, p = _plate_for(args, [v.min(0), v.max(0)])
    print(f"plate of {p.describe()}")
    if not tiled:  # before the work: a full disk is said now (a store checks its own room)
        _check_room(out, p.disk_bytes(), p.shape)
    code = look_code(*args.look) if args.look else None
    common = {"plate": plate, "camera": cam, "code": code, "progress": _progress_bar()}
    if tiled:
        record_plate(
            mesh,
            url=out,
            tile=args.tile,
            scheduler=args.scheduler,
            overwrite=args.overwrite,
            dashboard=lambda link: print(f"Dask dashboard: {link}"),
            **common,
        )
        print(f"\n{out}")
        return 0
    holo = record_plate(mesh, **common)
    print()
    print(write_hologram(out, holo))
    return 0


def _record_points(args, mesh, out, tiled) -> int:
    """A point sum of points sampled on the mesh (no occlusion), of the given size."""
    import numpy as np

    from .io.hologram import write_hologram
    from .plate.points import record_points
    from .plate.reference import Reference
    from .scene.mesh import default_spacing, sample_points

    shape = tuple(reversed(args.resolution or (1024, 1024)))
    pitch = args.pitch or 8e-6
    wavelengths = tuple(w * 1e-9 for w in (args.wavelengths or (633, 532, 473)))
    spacing = args.spacing or default_spacing(max(wavelengths), pitch, shape, mesh.vertices)
    pos, colours = sample_points(
        mesh, spacing, channels=len(wavelengths), max_points=args.max_points or 200_000
    )
    colours = (
        colours[:, : len(wavelengths)]
        if colours.shape[1] >= len(wavelengths)
        else np.repeat(colours.mean(1, keepdims=True), len(wavelengths), 1)
    )
    print(
        f"{len(pos)} point emitters ({spacing:.3g} m apart) -> {shape[1]}x{shape[0]} "
        f"hologram, pitch {pitch:.3g} m, wavelengths "
        f"{[round(w * 1e9, 3) for w in wavelengths]} nm"
    )
    if not tiled:
        _check_room(out, FILE_SAMPLE_BYTES * len(wavelengths) * shape[0] * shape[1], shape)
    if tiled:  # a complex plate in tiles, on Dask (the object wave: no reference)
        from .plate.tiles import DEFAULT_TILE, record_tiled

        method = "direct" if args.method == "auto" else args.method
        record_tiled(
            pos,
            colours,
            url=out,
            shape=shape,
            pitch=pitch,
            wavelengths=wavelengths,
            tile=args.tile or DEFAULT_TILE,
            method=method,
            scheduler=args.scheduler,
            overwrite=args.overwrite,
            progress=_progress_bar(),
            dashboard=lambda link: print(f"Dask dashboard: {link}"),
        )
        print(f"\n{out}")
        return 0
    holo = record_points(
        pos,
        colours,
        shape=shape,
        pitch=pitch,
        wavelengths=wavelengths,
        reference=Reference(angle=args.reference_angle or 0.0),
        method=args.method,
        progress=_progress_bar(),
    )
    print()
    print(write_hologram(out, holo))
    return 0


FILE_SAMPLE_BYTES = 12  # a hologram file's sample of one channel: intensity and object wave
VIEW_PIXEL_BYTES = 20  # a view file's pixel: colour, alpha and depth, float32


def _check_room(out, nbytes, shape) -> None:
    """Refuse, before the recording, a hologram file the disk has no room for."""
    from .io.image import check_room

    check_room([out], nbytes, f"the hologram ({shape[1]} x {shape[0]} samples) would")


def _view_room(paths, camera) -> None:
    """:class:`InputError` where the disk cannot take the view files ``paths`` of
    ``camera``'s resolution, before the view is rendered."""
    from .io.image import check_room

    w, h = camera.resolution
    check_room(paths, VIEW_PIXEL_BYTES * w * h, f"the {w}x{h} view's {{n}} file(s)")


def _is_store(path) -> bool:
    """A tiled plate's store (a Zarr folder or an fsspec URL), not an EXR file."""
    return str(path).rstrip("/").endswith(".zarr") or "://" in str(path)


def _read(path):
    from .io.hologram import read_hologram

    if _is_store(path):
        from .io.tiled_wave import open_plate

        return open_plate(path)
    return read_hologram(path)


def plan(args) -> int:
    """What a plate will take and give, before any recording (the plate's frame: the plate is
    z = 0, the objects behind it, the camera in front), in plain words, the verdict first."""
    from dataclasses import replace

    import numpy as np

    from .plate.plan import plan_view
    from .plate.plan_summary import summary

    if args.bounds is not None:  # where they are: no move
        bounds = np.reshape(args.bounds, (2, 3))
    elif args.mesh is not None:  # where it is, or at --distance: as record places it
        from .io.mesh import read_mesh

        v = read_mesh(args.mesh).vertices
        v = v if args.distance is None else _placed(v, args.distance)
        bounds = np.array([v.min(0), v.max(0)])
    elif args.box is not None:
        half = np.array(args.box) / 2
        bounds = _placed(np.array([-half, half]), args.distance or BOX_DISTANCE)
    else:
        raise ValueError("plan needs the objects: a mesh file, --box W H D or --bounds [m]")
    plate, cam, p = _plate_for(args, bounds)
    p = replace(p, looks=args.looks)
    eye, pixel = np.asarray(cam.position), cam.pixel_angle()
    v = plan_view(
        p,
        position=eye,
        pixel_angle=pixel,
        pupil=cam.aperture_diameter or None,
        resolution=cam.resolution,
    )
    lens = f"{cam.lens:g} mm f/{cam.fstop:g}" if cam.fstop else f"a {cam.lens:g} mm pinhole"
    lines = summary(
        p,
        v,
        lens=lens,
        resolution=cam.resolution,
        plate_size=(plate.width, plate.height),
        camera=eye,
    )
    refused = _refusal(p)
    if refused:
        lines.insert(1, f"refused     {refused}")
    print("\n".join(lines))
    return 2 if refused else 0


BOX_DISTANCE = 0.3  # [m] plan --box: the box's nearest face behind the plate, by default


def _refusal(p) -> str:
    """Why the plan ``p`` cannot be recorded on this machine ("" where it can): its looks,
    in one piece where they fit the host's share of memory, else tile by tile, need more."""
    from . import memory
    from .validate import InputError

    limit = memory.host_share()
    try:
        p.check_recording(memory=limit, tiled=None)
    except InputError as e:
        return str(e)
    return ""


def _camera_and_zone(args, bounds, eye, resolution):
    """(the reference camera, the viewing zone) of ``plan`` and ``record``'s options: the
    camera at ``--camera`` (default ``eye`` [m]) looking at ``--look-at`` (default the
    objects' box ``bounds`` centre), focused there unless ``--focus-distance``; the zone
    ``--zone``, else ``--zone-margin`` around its pupil along the ``--dolly``."""
    import numpy as np

    from .scene.camera import Camera, look_at
    from .scene.plate import SHOT_ZONE_MARGIN, ViewingZone

    eye = np.array(args.camera if args.camera else eye, np.float64)
    if eye[2] <= 0:
        raise ValueError(
            f"--camera must be in front of the plate (z > 0 in its frame: the plate "
            f"is z = 0, the objects behind it); got ({eye[0]:g}, {eye[1]:g}, "
            f"{eye[2]:g}) m, {'on' if eye[2] == 0 else 'behind'} the plate"
        )
    target = np.array(args.look_at) if args.look_at else np.asarray(bounds).mean(0)
    focus = args.focus_distance or float(np.linalg.norm(eye - target))
    cam = Camera(
        matrix_world=look_at(eye, target, up=(0, 1, 0)),
        lens=args.lens,
        sensor_width=args.sensor_width,
        resolution=resolution,
        fstop=args.fstop,
        focus_distance=focus if args.fstop else None,
    )
    pupil, pixel = cam.aperture_diameter or 0.0, cam.pixel_angle()
    if args.zone is not None:
        return cam, ViewingZone(
            centre=args.zone[:3], half_extents=args.zone[3:], pupil=pupil, pixel=pixel
        )
    dolly = args.dolly or 0.0
    path = [eye + (x, 0.0, 0.0) for x in (-dolly / 2, dolly / 2)]
    margin = SHOT_ZONE_MARGIN if args.zone_margin is None else args.zone_margin
    return cam, ViewingZone.fit(path, pupil, margin, pixel)


def _view_options(p, *, plate_size=None, point_sums=False):
    """The options of a plate's zone and its reference camera, for ``plan`` and ``record``
    (``point_sums``: where a point sum ignores them, their help says so)."""
    only = " (--method zone)" if point_sums else ""
    metres = _number(float, lambda v: 0 <= v <= MAX_LENGTH, "metres >= 0")
    p.add_argument(
        "--zone",
        type=FINITE,
        nargs=6,
        metavar=("X", "Y", "Z", "HX", "HY", "HZ"),
        help="the viewing zone's centre and half widths [m] in the plate's frame "
        "(default: --zone-margin around the camera's pupil)" + only,
    )
    p.add_argument(
        "--plate-size",
        type=POSITIVE,
        nargs=2,
        default=plate_size,
        metavar=("W", "H"),
        help=f"[m] ({' '.join(map(str, plate_size))})"
        if plate_size
        else "[m] (default: wide enough for all the light from the objects to the zone)" + only,
    )
    p.add_argument(
        "--zone-margin",
        type=metres,
        default=None,
        help="the viewing zone reaches this far beyond the camera's pupil [m] (0.005)" + only,
    )
    p.add_argument(
        "--dolly",
        type=metres,
        default=None,
        help="the camera moves this far along x, centred on --camera [m] (0)" + only,
    )
    p.add_argument(
        "--camera",
        type=FINITE,
        nargs=3,
        metavar=("X", "Y", "Z"),
        help="camera position [m] in the plate's frame (default: on the axis, as "
        "far in front as the objects' nearest point is behind)" + only,
    )
    p.add_argument(
        "--look-at",
        type=FINITE,
        nargs=3,
        metavar=("X", "Y", "Z"),
        help="[m] (default: the objects' centre)" + only,
    )
    p.add_argument("--lens", type=POSITIVE, default=50.0, help="focal length [mm] (50)" + only)
    p.add_argument("--sensor-width", type=POSITIVE, default=36.0, help="[mm] (36)" + only)
    p.add_argument(
        "--fstop", type=POSITIVE, default=2.8, help="f-number (2.8); 0 is refused" + only
    )
    p.add_argument(
        "--pinhole",
        dest="fstop",
        action="store_const",
        const=None,
        help="a camera without a lens" + only,
    )
    p.add_argument(
        "--focus-distance",
        type=POSITIVE,
        default=None,
        help="[m] (default: the objects' centre)" + only,
    )


def info(args) -> int:
    import json

    from .io.hologram import metadata

    print(json.dumps(metadata(_read(args.hologram)), indent=2))
    return 0


def render(args) -> int:
    from .io.view import write_view
    from .plate.view import render_view

    out = _output(args.output, args.hologram, "_view", preview=True)
    h = _scan_or_hologram(args)
    camera = _camera(args, h)
    _view_room([out, out.with_suffix(".png")], camera)
    view = render_view(
        h,
        camera,
        supersample=args.supersample or "auto",
        composition=args.composition,
        source=args.source,
        progress=_progress_bar(),
    )
    print()
    for path in write_view(view, out):
        print(path)
    return 0


def _camera(args, h):
    """The camera the options describe; without ``--camera``, for a hologram of objects on one
    stated plane (an acquired one), the camera that frames it, focused there."""
    import numpy as np

    from .acquired import default_camera
    from .acquired.framing import stated_plane
    from .scene.camera import Camera, look_at

    resolution = tuple(args.resolution) if args.resolution else None
    if not args.camera and stated_plane(h) is not None:
        return default_camera(h, resolution=resolution)
    plate = np.asarray(h.plate)
    centre = (plate @ np.append(np.asarray(h.bounds).mean(0), 1.0))[:3]
    if args.camera:
        eye = args.camera
    elif h.zone is not None:  # the centre of the zone it was recorded for
        eye = (plate @ np.append(h.zone.centre, 1.0))[:3]
    else:
        eye = plate[:3, 3] + plate[:3, 2] * 3 * max(h.size)
    target = args.look_at if args.look_at else centre
    fstop = args.fstop
    if fstop is None and h.zone is not None and h.zone.pupil:  # the zone's own views
        fstop = args.lens * 1e-3 / h.zone.pupil
    focus = args.focus_distance
    if fstop and focus is None:
        focus = float(np.linalg.norm(np.asarray(eye) - centre))
    return Camera(
        matrix_world=look_at(eye, target, up=plate[:3, 1]),
        lens=args.lens,
        sensor_width=args.sensor_width,
        resolution=resolution or (256, 256),
        fstop=fstop,
        focus_distance=focus if fstop else None,
    )


def _scan_or_hologram(args):
    """A Holo hologram file (or store) as it is; a scan (PNG, TIFF, EXR, .npy, HDF5, .mat)
    imported with ``--pitch``, ``--wavelength`` and ``--distance``: its object wave at that
    distance (:func:`import_scan`)."""
    from .io.hologram import HologramFileError

    path = Path(args.hologram)
    given = [n for n in ("pitch", "wavelength", "distance") if getattr(args, n, None)]
    if _is_store(args.hologram) or (path.suffix.lower() == ".exr" and not given):
        try:
            return _read(args.hologram)
        except HologramFileError as e:
            if "without hologram metadata" not in str(e):
                raise
    if len(given) < 3:
        missing = ", ".join(f"--{n}" for n in ("pitch", "wavelength", "distance") if n not in given)
        raise ValueError(
            f"{path} is a scan, not a Holo hologram: give {missing} (the pitch [m], "
            f"the wavelength [nm, or with a unit], how far behind it the objects "
            f"lie [m]), or import it: python -m holo_core import {path} --pitch "
            f"... --wavelength ... --distance ..."
        )
    return import_scan(args)[0]


def import_scan(args):
    """(the object hologram, the carrier line) of a scan: read, its carrier found (or the
    reference's angle and azimuth given), the sideband filtered, placed at its distance."""
    from .acquired import Aperture, object_hologram
    from .acquired import import_acquired as import_with_carrier
    from .acquired.scan import complex_scan
    from .io.acquired import read_acquired

    if args.pitch and args.wavelength and args.distance:
        wave = complex_scan(
            args.hologram, pitch=args.pitch, wavelength=args.wavelength, distance=args.distance
        )
        if wave is not None:
            print(
                f"{args.hologram}: a complex object wave (channels re, im); objects "
                f"{args.distance:g} m behind"
            )
            return wave, ""
    h = import_with_carrier(
        args.hologram,
        pitch=args.pitch,
        wavelength=args.wavelength,
        reference_angle=args.reference_angle,
        reference_azimuth=args.reference_azimuth,
        page=args.page,
        dataset=args.dataset,
        distance=args.distance,
        sideband=args.sideband,
    )
    reference = (
        None
        if args.reference_hologram is None
        else read_acquired(
            args.reference_hologram,
            pitch=h.pitch,
            wavelength=h.wavelengths[0],
            page=args.page,
            dataset=args.dataset,
        )
    )
    aperture = Aperture(
        radius=args.radius,
        unit=args.radius_unit,
        edge=args.edge,
        width=args.edge_width,
        window=args.window,
    )
    obj = object_hologram(h, aperture=aperture, reference_hologram=reference)
    line = (
        f"reference {h.reference_angle:.6g} rad ({math.degrees(h.reference_angle):.4g}°) "
        f"at azimuth {h.reference_azimuth:.6g} rad "
        f"({math.degrees(h.reference_azimuth):.4g}°)"
    )
    print(f"{args.hologram}: {line}; objects {args.distance:g} m behind, band sin θ {obj.band:.4g}")
    return obj, line


def import_(args) -> int:
    """A scan to a Holo hologram (its object wave at the distance) and, unless --no-view, the
    view of the camera that frames it."""
    from .io.hologram import write_hologram
    from .io.view import write_view
    from .plate.view import render_view

    out = _output(args.output, args.hologram, "_holo")
    view_out = (
        None
        if args.no_view
        else _output(
            args.output if _is_folder(args.output) else out.with_name(f"{out.stem}_view.exr"),
            args.hologram,
            "_view",
            preview=True,
        )
    )
    h, _ = import_scan(args)
    camera = None if view_out is None else _camera(args, h)
    from .io.image import check_room

    check_room(
        [out],
        FILE_SAMPLE_BYTES * h.shape[0] * h.shape[1] * len(h.wavelengths),
        f"the {h.shape[1]}x{h.shape[0]} hologram",
    )
    if camera is not None:
        _view_room([view_out, view_out.with_suffix(".png")], camera)
    print(write_hologram(out, h))
    if view_out is not None:
        view = render_view(h, camera, supersample="auto", progress=_progress_bar())
        print()
        for path in write_view(view, view_out):
            print(path)
    return 0


def _is_folder(output) -> bool:
    return Path(output).is_dir() or str(output).endswith(("/", "\\"))


def _file_in(output, source, tag) -> Path:
    """``output``, or where it names a folder, ``<folder>/<source's stem><tag>.exr``."""
    out = Path(output)
    if _is_folder(output):
        return out / f"{Path(source).stem}{tag}.exr"
    return out


def _output(output, source, tag, preview=False) -> Path:
    """The file to write (:func:`_file_in`), checked before the work: it ends in .exr and
    its folder takes new files (and, with ``preview``, the PNG beside it too)."""
    from .io.image import check_writable

    out = _file_in(output, source, tag)
    check_writable(out, ".exr")
    if preview:
        check_writable(out.with_suffix(".png"))
    return out


def _number(kind, test, allowed):
    """An argparse type: ``kind`` of the text, finite and passing ``test``, else an error
    naming ``allowed``."""

    def parse(text):
        try:
            value = kind(text)
        except ValueError:
            what = "an integer" if kind is int else "a number"
            raise argparse.ArgumentTypeError(f"{text!r} is not {what} ({allowed})") from None
        if not math.isfinite(value) or not test(value):
            raise argparse.ArgumentTypeError(f"{text!r} is out of range ({allowed})")
        return value

    return parse


POSITIVE = _number(float, lambda v: v > 0, "a number > 0")
METRES = _number(
    float, lambda v: MIN_LENGTH <= v <= MAX_LENGTH, f"metres, from {MIN_LENGTH:g} to {MAX_LENGTH:g}"
)
NANOMETRES = _number(
    float,
    lambda v: 1 <= v <= MAX_LENGTH * 1e9,
    f"nm, from 1 to {MAX_LENGTH * 1e9:g}: 633 is red light; 633e-9 would be "
    f"metres, which this option does not take",
)
SUPERSAMPLE = _number(
    int, lambda v: 1 <= v <= MAX_SUPERSAMPLE, f"an integer from 1 to {MAX_SUPERSAMPLE}"
)
FINITE = _number(float, lambda v: True, "a finite number")
COUNT = _number(int, lambda v: v >= 1, "an integer >= 1")
PIXELS = _number(int, lambda v: 1 <= v <= 65536, "an integer from 1 to 65536")
INDEX = _number(int, lambda v: v >= 0, "an integer >= 0")


def _with_unit(reader, allowed):
    """An argparse type: a number with an optional unit, read by ``reader`` (text → metres),
    finite and > 0, else an error naming ``allowed``."""

    def parse(text):
        try:
            value = reader(text)
        except ValueError as e:  # InputError: the unit or the number
            raise argparse.ArgumentTypeError(f"{e} ({allowed})") from None
        if not value > 0:
            raise argparse.ArgumentTypeError(f"{text!r} is out of range ({allowed})")
        return value

    return parse


def _scan_wavelength(text: str) -> float:
    """A wavelength [m]: a plain number in nm (below 1 refused: 633e-9 would be metres; an
    X-ray's 0.154 nm is written with its unit), or a length or a voltage with its unit."""
    value, unit = units.split(text, "--wavelength")
    if unit is None and value < 1:
        raise units.InputError(
            f"{text!r}: a plain number is in nm (633 is red light); write "
            f"a unit for others: 0.154nm, 1.97pm, 300kV"
        )
    return units.wavelength(text, "--wavelength")


LENGTH = _with_unit(
    lambda text: units.length(text, "length"), "metres, or a number with its unit: 3.45um, 5cm"
)
WAVE = _with_unit(_scan_wavelength, "nm, or a number with its unit: 633nm, 1.97pm, 300kV")


class _Parser(argparse.ArgumentParser):
    """argparse's parser, its errors on one line (exit status 2), and negative numbers in any
    notation taken as values: argparse's own pattern (Python < 3.13) knows -1 and -.5 but
    not -1e-3, which it took for an option (``--camera 0.01 -1e-3 0.3``: "expected 3
    arguments")."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message):
        self.exit(2, f"error: {self.prog}: {message} (--help lists the options)\n")


NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


def _scan_options(p, lead: str) -> None:
    """The options of an acquired scan: its optics, its carrier and its sideband filter."""
    p.add_argument(
        "--pitch",
        type=LENGTH,
        help=lead + "its pixel pitch [m, or with a unit: 3.45um] (default: the file's)",
    )
    p.add_argument(
        "--wavelength",
        type=WAVE,
        help=lead + "its wavelength [nm, or with a unit: "
        "1.97pm, or an electron microscope's voltage: 300kV] (default: the file's)",
    )
    p.add_argument(
        "--distance",
        type=LENGTH,
        help=lead + "how far behind it the objects lie [m, or with a unit: 5cm]",
    )
    p.add_argument(
        "--sideband",
        choices=["auto", "lower", "upper"],
        default="auto",
        help="which order of the spectrum's pair is the carrier: auto (the one that "
        "focuses behind at --distance), lower or upper (holospy's sb)",
    )
    p.add_argument(
        "--reference-angle",
        type=FINITE,
        default=None,
        help="the reference's angle [rad] (default: the file's, else found)",
    )
    p.add_argument(
        "--reference-azimuth",
        type=FINITE,
        default=None,
        help="the reference's azimuth [rad] from +x towards +y",
    )
    p.add_argument(
        "--radius",
        type=POSITIVE,
        default=None,
        help="the sideband aperture's radius in --radius-unit (default: |fc|/3)",
    )
    p.add_argument(
        "--radius-unit",
        choices=["carrier", "1/m", "1/mm", "1/um", "1/nm", "mrad", "rad"],
        default="carrier",
        help="carrier: a fraction of |fc| (holospy: 0.5 strong, 1/3 weak phase)",
    )
    p.add_argument(
        "--edge",
        choices=["hard", "tanh", "cosine"],
        default="hard",
        help="the aperture's edge (tanh: holospy's)",
    )
    p.add_argument(
        "--edge-width",
        type=POSITIVE,
        default=0.05,
        help="the edge's width, a fraction of the radius (0.05)",
    )
    p.add_argument(
        "--window",
        choices=["none", "hann", "hamming", "blackman", "gaussian", "butterworth"],
        default="none",
        help="an apodisation across the aperture",
    )
    p.add_argument(
        "--reference-hologram",
        default=None,
        help="a reference (vacuum) hologram's file: the wave is divided by its own",
    )
    p.add_argument("--page", type=INDEX, default=None, help="the page of a multi-page scan")
    p.add_argument("--dataset", default=None, help="the dataset of an HDF5 or .mat file")


def _progress_bar(width=40):
    def show(fraction):
        done = int(round(fraction * width))
        print(f"\r[{'#' * done}{'.' * (width - done)}] {fraction:6.1%}", end="", flush=True)

    return show


def main(argv=None) -> int:
    parser = _Parser(prog="python -m holo_core", description=__doc__)
    parser.add_argument("-v", "--verbose", action="store_true")
    parser.add_argument(
        "--debug", action="store_true", help="print the traceback of a failure (default: one line)"
    )
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    sub.add_parser("devices", help="list OpenCL devices and the one Holo would use")
    p = sub.add_parser("demo", help="render the built-in demo to image files")
    p.add_argument("-o", "--output", default="out", help="output folder (default: out)")
    p = sub.add_parser(
        "calibrate",
        help="measure this machine's rates for the estimates "
        "(about a minute) and keep them in the user cache",
    )
    p.add_argument(
        "--device",
        default=None,
        help="the device to measure (as HOLO_DEVICE; default: its value, or automatic)",
    )
    p = sub.add_parser("record", help="record a hologram of a PLY or OBJ mesh")
    p.add_argument("mesh", help="mesh file (.ply or .obj), units taken as metres")
    p.add_argument(
        "-o",
        "--output",
        required=True,
        help="hologram file to write (.exr), or a folder for <mesh>.exr, or a "
        "tiled plate NAME.zarr (a folder or an fsspec URL; recorded on Dask)",
    )
    p.add_argument(
        "--method",
        choices=["zone", "auto", "direct", "wrp"],
        default="zone",
        help="zone (default): the plate of meshes, with occlusion, against the "
        "carrier converging on its viewing zone, sampled as the zone needs; "
        "auto, direct, wrp: a point sum of points sampled on the mesh, no "
        "occlusion (auto: the faster)",
    )
    p.add_argument(
        "--resolution",
        type=PIXELS,
        nargs=2,
        default=None,
        metavar=("W", "H"),
        help="zone: the views' pixels, which with --lens and --sensor-width set "
        "the sharpness the plate records (640 360); a point sum: the "
        "hologram's samples (1024 1024)",
    )
    p.add_argument(
        "--distance",
        type=POSITIVE,
        default=None,
        help="move the mesh so its nearest point is this far behind the plate, "
        "centred on its axis [m] (default: where it is)",
    )
    _view_options(p, point_sums=True)
    p.add_argument(
        "--look",
        type=_number(int, lambda v: v >= 0, "an integer >= 0"),
        nargs=2,
        metavar=("K", "N"),
        help="record coded look K of N (--method zone; default: one look of random phases)",
    )
    p.add_argument(
        "--pitch", type=METRES, default=None, help="a point sum's sample spacing [m] (8e-6)"
    )
    p.add_argument(
        "--wavelengths",
        type=NANOMETRES,
        nargs="+",
        default=None,
        help="a point sum's wavelengths [nm, not m like the other lengths] (633 532 473)",
    )
    p.add_argument(
        "--reference-angle", type=FINITE, default=None, help="a point sum's reference ϑ [rad] (0)"
    )
    p.add_argument(
        "--spacing",
        type=POSITIVE,
        default=None,
        help="a point sum's point spacing on the surface [m] (default: the hologram's resolution)",
    )
    p.add_argument(
        "--max-points",
        type=COUNT,
        default=None,
        help="a point sum's most point emitters sampled on the mesh (200000)",
    )
    p.add_argument(
        "--tile",
        type=PIXELS,
        default=None,
        help="with an output NAME.zarr or URL: samples per tile side (a plate of "
        "meshes: fitted to the plate, at most 2048; a point sum: 2048)",
    )
    p.add_argument(
        "--scheduler",
        default=None,
        help="with an output NAME.zarr or URL: a Dask scheduler's address "
        "(tcp://host:8786; default DASK_SCHEDULER_ADDRESS, else a local "
        "cluster); one not reached within 10 s is an error",
    )
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="with an output NAME.zarr or URL: replace a store of another "
        "recording there (default: refused; the same recording resumes)",
    )
    p = sub.add_parser(
        "plan",
        help="a plate's samples, wavelength, memory and time, and what "
        "a camera's view of it resolves, before any recording",
    )
    p.add_argument("mesh", nargs="?", help="the objects (.ply or .obj, metres), or --box")
    p.add_argument(
        "--box",
        type=POSITIVE,
        nargs=3,
        metavar=("W", "H", "D"),
        help="the objects' box [m] instead of a mesh",
    )
    p.add_argument(
        "--bounds",
        type=FINITE,
        nargs=6,
        metavar=("X0", "Y0", "Z0", "X1", "Y1", "Z1"),
        help="the objects' box [m] in the plate's frame, where it is (no --distance)",
    )
    p.add_argument(
        "--distance",
        type=POSITIVE,
        default=None,
        help="move the objects so their nearest point is this far behind the "
        "plate, centred on its axis [m], as record --distance does (default: "
        f"a mesh where it is, a --box {BOX_DISTANCE:g})",
    )
    p.add_argument(
        "--looks",
        type=PIXELS,
        default=1,
        help="looks to record (1, what one record makes; N coded looks are N records, --look K N)",
    )
    p.add_argument("--resolution", type=PIXELS, nargs=2, default=(640, 360), metavar=("W", "H"))
    _view_options(p)
    p = sub.add_parser("info", help="print a hologram file's metadata")
    p.add_argument("hologram")
    p = sub.add_parser("render", help="render a view of a hologram to EXR (+ PNG preview)")
    p.add_argument("hologram")
    p.add_argument(
        "-o",
        "--output",
        required=True,
        help="view file to write (.exr), or a folder for <hologram>_view.exr",
    )
    p.add_argument(
        "--camera",
        type=FINITE,
        nargs=3,
        metavar=("X", "Y", "Z"),
        help="camera position [m], world (default: the centre of the zone the plate was "
        "recorded for, else 3 plate sizes in front)",
    )
    p.add_argument(
        "--look-at",
        type=FINITE,
        nargs=3,
        metavar=("X", "Y", "Z"),
        help="point the camera looks at [m] (default: the objects' centre)",
    )
    p.add_argument("--lens", type=POSITIVE, default=50.0, help="focal length [mm] (50)")
    p.add_argument("--sensor-width", type=POSITIVE, default=36.0, help="[mm] (36)")
    p.add_argument(
        "--resolution",
        type=PIXELS,
        nargs=2,
        default=None,
        metavar=("W", "H"),
        help="(256 256; an acquired hologram's: its band's Nyquist sampling)",
    )
    p.add_argument(
        "--fstop",
        type=POSITIVE,
        default=None,
        help="f-number (default: the pupil of the zone the plate was recorded for, else a pinhole)",
    )
    p.add_argument(
        "--focus-distance",
        type=POSITIVE,
        default=None,
        help="[m] (default with --fstop: the objects' centre)",
    )
    p.add_argument(
        "--supersample",
        type=SUPERSAMPLE,
        default=None,
        help="speckle low-pass factor (default: the intensity's Nyquist rate)",
    )
    p.add_argument("--composition", choices=["mean", "max"], default="mean")
    p.add_argument("--source", choices=["hologram", "object_wave"], default="hologram")
    _scan_options(p, "a scan given as HOLOGRAM (PNG, TIFF, EXR, .npy, HDF5, .mat): ")
    p = sub.add_parser(
        "import",
        help="import a scan (an acquired off-axis hologram): its "
        "carrier found, its object wave at its distance written "
        "as a Holo hologram, and the view that frames it",
    )
    p.add_argument(
        "hologram", metavar="scan", help="PNG, TIFF, EXR, .npy, HDF5 or .mat (v7.3) file"
    )
    p.add_argument(
        "-o",
        "--output",
        required=True,
        help="hologram file to write (.exr), or a folder for <scan>_holo.exr; the "
        "view goes beside it (<name>_view.exr and .png)",
    )
    p.add_argument("--no-view", action="store_true", help="write the hologram only")
    p.add_argument(
        "--resolution",
        type=PIXELS,
        nargs=2,
        default=None,
        metavar=("W", "H"),
        help="the view's size (default: its band's Nyquist sampling)",
    )
    p.set_defaults(camera=None)
    _scan_options(p, "")
    args = parser.parse_args(argv)
    warnings.formatwarning = lambda message, category, *_: (
        f"warning: {message} ({category.__name__})\n"
    )
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    command = {
        "devices": devices,
        "calibrate": calibrate,
        "demo": demo,
        "plan": plan,
        "record": record,
        "info": info,
        "render": render,
        "import": import_,
    }[args.command]
    try:
        return command(args)
    except ValueError as e:  # InputError and the like: the user can act on the message
        return _fail(args, f"error: {e}", 2)
    except KeyboardInterrupt:
        return _fail(args, "\ninterrupted", 130)
    except Exception as e:  # noqa: BLE001 -- one line for any other failure; --debug for more
        first = (str(e).strip().splitlines() or [""])[0]
        return _fail(args, f"error: {type(e).__name__}: {first} (--debug shows the traceback)", 1)


def _fail(args, line, status) -> int:
    if args.debug:
        import traceback

        traceback.print_exc()
    print(line, file=sys.stderr)
    return status


if __name__ == "__main__":
    sys.exit(main())
