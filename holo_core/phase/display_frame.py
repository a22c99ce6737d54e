"""One frame of a holographic display's animation: the recorded waves to the files its SLM
driver takes, and what the display will show.

A :class:`holo_core.job.DisplayFrame` names, per laser, the plate recorded for it (the
scene's wave, as the display shows the scene: in its metres, at its wavelength) and the
display. :func:`make_frame` carries each laser's
wave to the display's grid (:func:`wave_at_display`: back from the volume's front where it
was recorded there), checks the setup (:func:`holo_core.phase.slm.check_scene`), encodes it
through the laser's phase table (:func:`holo_core.phase.encode.encode`), simulates the focal
stack the quantised pattern shows against the unencoded wave's
(:class:`holo_core.phase.stack.Optics`: the display's 4f filter, the planes from the
volume's back to its front, each seen by an eye at the eye box's centre focused there;
PSNR and SSIM per slice), then writes every file of the frame
as one set (:func:`holo_core.io.image.atomic_paths`): per laser the pattern as its driver
reads it and its layout (:func:`holo_core.io.slm.pattern_files`), the focal stack (EXR) and
its contact sheet (PNG) (:func:`holo_core.io.slm.write_stack`), and last the frame's layout
(JSON) that names them. A frame's files appear together or not at all; a failed or
cancelled frame leaves the earlier frames as they were.

The display is lit by a plane wave along its normal, as the recorded wave's field is
(:func:`holo_core.phase.display.display_field`). The focal stack is what an eye (or a
camera) sees through its pupil (the frame's ``pupil``, at the eye box's centre
``eye_distance`` in front), its lens focused on each slice in turn
(:class:`holo_core.phase.stack.EyePupil`, :meth:`~holo_core.phase.stack.Optics.seen`): in
focus the scene's parts at that depth are as sharp as the pupil resolves (λL/a), the rest
blurred by the cone from them to the pupil. The iterative encodings fit the planes' own
amplitudes (every direction the filter passes, the whole eye box); the stack and its PSNR
and SSIM are the eye's, the pattern's against the unencoded wave's through the same pupil.

Run as ``python -m holo_core.phase.display_frame FOLDER``: reads ``FOLDER/frame.json``,
prints ``HOLO_PROGRESS <fraction>`` lines and the frame's layout (JSON) as its last line.
"""

from __future__ import annotations

import json
import logging
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from .. import jobs
from ..io import slm as slm_io
from ..io.image import atomic_paths
from ..job import DisplayFrame, FrameLaser
from ..validate import InputError
from . import levels
from .display import Display, display_field
from .encode import encode
from .export import laser_name
from .slm import EyeBox, Laser, SLMSetup, check_scene, read_phase_table
from .stack import EyePupil, Optics, compare, fitted

log = logging.getLogger(__name__)
LAYOUT_FORMAT, LAYOUT_VERSION = "holo-display-frame", 1


def setup_of(frame: DisplayFrame) -> SLMSetup:
    """The core's description of the frame's display, lasers, tables, eye box and volume."""
    display = Display(
        name=frame.name[:100],
        resolution=frame.resolution,
        pitch=frame.pitch,
        bit_depth=frame.bit_depth,
        phase_range=frame.phase_range,
        inverted=frame.inverted,
    )
    tables = tuple(
        read_phase_table(x.table, wavelength=x.wavelength, bit_depth=frame.bit_depth)
        for x in frame.lasers
        if x.table
    )
    if tables and len(tables) != len(frame.lasers):
        bare = [x.name for x in frame.lasers if not x.table]
        raise InputError(
            f"phase tables are given for some lasers but not for {', '.join(bare)}: "
            f"give one per laser, or none (the display's linear response)"
        )
    return SLMSetup(
        display=display,
        lasers=tuple(Laser(wavelength=x.wavelength, power=x.power) for x in frame.lasers),
        tables=tables,
        eye_box=EyeBox(
            size=(frame.eye_box, frame.eye_box), distance=frame.eye_distance, pupil=frame.pupil
        ),
        depth_range=(-frame.behind, frame.front),
        slices=frame.slices,
    )


def paths(frame: DisplayFrame) -> dict:
    """Every file of the frame by role: per laser its pattern and the pattern's layout, the
    stack and its sheet, and the frame's layout last (it names the others)."""
    folder, stem = Path(frame.folder), frame.stem()
    out = {}
    for x in frame.lasers:
        image = folder / f"{stem}_{laser_name(x.wavelength)}.png"
        out[x.name] = image
        out[f"{x.name} layout"] = image.with_suffix(".json")
    out["stack"] = folder / f"{stem}_stack.exr"
    out["sheet"] = folder / f"{stem}_stack.png"
    out["layout"] = folder / f"{stem}.json"
    return out


def wave_at_display(frame: DisplayFrame, laser: FrameLaser) -> np.ndarray:
    """The laser's wave on the display's grid (rows, cols), complex128, its largest
    amplitude 1: the recorded plate resampled to the display's pitch, carried back from the volume's front by the band-limited angular spectrum where it was
    recorded there."""
    from ..io.plate_paths import read_plate
    from ..propagation import angular_spectrum

    hologram = read_plate(Path(laser.hologram))
    p = frame.pitch
    cols, rows = frame.resolution
    pad = 0
    if frame.front > 0:  # the light the display's edge sends to the eye box crosses the front
        sin_t = min(laser.wavelength / (2 * p), 0.99)
        pad = math.ceil(frame.front * sin_t / math.sqrt(1 - sin_t**2) / p) + 8
    wide = Display(name=frame.name[:100], resolution=(cols + 2 * pad, rows + 2 * pad), pitch=p)
    u = np.asarray(display_field(hologram, wide, channel=laser.channel), np.complex128)
    if frame.front > 0:
        u = np.asarray(
            angular_spectrum(u, wavelength=laser.wavelength, pitch=p, distance=-frame.front),
            np.complex128,
        )
        u = u[pad : pad + rows, pad : pad + cols]
    peak = float(np.abs(u).max())
    if not peak > 0 or not np.isfinite(u).all():
        raise InputError(
            f"the recorded wave of the {laser.name} laser ({laser.hologram}) is "
            f"zero or not finite on the display: nothing to encode"
        )
    return u / peak


def make_frame(frame: DisplayFrame, progress: jobs.Progress = None) -> dict:
    """Make and write the frame (module docstring); returns its layout (as its JSON file
    holds it), with each laser's PSNR [dB] and SSIM per slice."""
    started = time.perf_counter()
    setup = setup_of(frame)
    half = (frame.resolution[0] * frame.pitch / 2, frame.resolution[1] * frame.pitch / 2)
    for note in check_scene(setup, extent=half):
        log.warning("display '%s': %s", frame.name, note)
    where = paths(frame)
    Path(frame.folder).mkdir(parents=True, exist_ok=True)
    files, lasers, shown, wanted = {}, [], [], []
    n, distances = len(frame.lasers), setup.distances()
    extra = {
        "frame": frame.frame,
        "digest": frame.digest,
        "scale": frame.scale,
        "eye_box": {
            "size": [frame.eye_box] * 2,
            "distance": frame.eye_distance,
            "pupil": frame.pupil,
        },
    }
    for i, (x, laser) in enumerate(zip(frame.lasers, setup.lasers)):
        jobs.report(progress, i, n)
        u = wave_at_display(frame, x)
        optics = Optics(
            setup.display.shape,
            pitch=frame.pitch,
            wavelength=x.wavelength,
            distances=distances,
            band=setup.band,
            eye=EyePupil(diameter=frame.pupil, distance=frame.eye_distance),
        )
        ref = optics.seen(u)
        pattern = encode(
            u,
            setup,
            wavelength=x.wavelength,
            method=frame.method,
            optics=optics,
            iterations=frame.iterations,
        )
        table = setup.table_for(x.wavelength)
        data, layout = slm_io.pattern_files(
            where[x.name].name,
            pattern.codes,
            response=levels.response(setup.display, table),
            display=frame.name,
            pitch=frame.pitch,
            bit_depth=frame.bit_depth,
            phase_range=frame.phase_range,
            inverted=frame.inverted,
            wavelength=x.wavelength,
            power=laser.power,
            distance=frame.distance,
            encoding=frame.method,
            packing=frame.packing,
            table=pattern.table,
            extra=extra,
        )
        files[x.name] = data
        files[f"{x.name} layout"] = (json.dumps(layout, indent=1) + "\n").encode()
        log.info(
            "display '%s' frame %d: %s encoded (%s) in %.2f s",
            frame.name,
            frame.frame,
            x.name,
            frame.method,
            pattern.seconds,
        )  # a time: never in a file
        jobs.report(progress, i + 0.6, n)
        got = optics.seen(np.exp(1j * pattern.phase))
        c = compare(got, ref)
        shown.append((x.channel, fitted(got, ref)[0] ** 2))
        wanted.append((x.channel, np.asarray(ref, np.float64) ** 2))
        lasers.append(
            {
                "name": x.name,
                "wavelength": x.wavelength,
                "power": x.power,
                "pattern": where[x.name].name,
                "layout": where[f"{x.name} layout"].name,
                "encoding": frame.method,
                "table": pattern.table,
                "psnr_db": [round(float(v), 3) for v in c.psnr_db],
                "ssim": [round(float(v), 4) for v in c.ssim],
            }
        )
    stack, sheet = _stack_files(frame, shown, wanted, distances, lasers)
    files["stack"], files["sheet"] = stack, sheet
    layout = {
        "format": LAYOUT_FORMAT,
        "version": LAYOUT_VERSION,
        "display": frame.name,
        "frame": frame.frame,
        "digest": frame.digest,
        "resolution": list(frame.resolution),
        "pitch": frame.pitch,
        "distance": frame.distance,
        "scale": frame.scale,
        "packing": frame.packing,
        "lasers": lasers,
        "stack": {
            "file": where["stack"].name,
            "sheet": where["sheet"].name,
            "depths": [float(z) for z in distances],
        },
    }
    files["layout"] = (json.dumps(layout, indent=1) + "\n").encode()
    roles = list(where)  # the frame's layout last: it appears with the files it names
    with atomic_paths(*(where[r] for r in roles)) as temps:
        for role, tmp in zip(roles, temps):
            Path(tmp).write_bytes(files[role])
    jobs.report(progress, 1, 1)
    log.info(
        "display '%s' frame %d: %d pattern(s) in %.1f s",
        frame.name,
        frame.frame,
        n,
        time.perf_counter() - started,
    )
    return layout


def _stack_files(frame: DisplayFrame, shown, wanted, distances, lasers) -> tuple[bytes, bytes]:
    """(the focal stack's EXR, its contact sheet's PNG), as bytes: the simulated
    intensities in each laser's colour channel beside the wave's
    (:func:`holo_core.io.slm.write_stack`, written in a scratch folder so that the frame's
    files are renamed into place as one set)."""
    rows, cols = shown[0][1].shape[1:]
    sim = np.zeros((len(distances), rows, cols, 3))
    ref = np.zeros_like(sim)
    for (channel, s), (_, r) in zip(shown, wanted):
        sim[..., channel] += s
        ref[..., channel] += r
    psnrs = np.mean([x["psnr_db"] for x in lasers], axis=0)
    labels = [f"{z * 1e3:+.2f} mm {q:.1f} dB" for z, q in zip(distances, psnrs)]
    metrics = {x["name"]: {"psnr_db": x["psnr_db"], "ssim": x["ssim"]} for x in lasers}
    with tempfile.TemporaryDirectory(prefix="holo-stack-") as folder:
        exr, png = slm_io.write_stack(
            Path(folder) / "stack.exr",
            sim,
            reference=ref,
            distances=distances,
            metrics=metrics,
            labels=labels,
        )
        return exr.read_bytes(), png.read_bytes()


def main(argv=None) -> int:
    """``python -m holo_core.phase.display_frame FOLDER``: the frame of ``FOLDER/frame.json``
    made; progress lines on stdout, the layout's JSON as the last line; status 1 and the
    reason on stderr when it fails."""
    argv = sys.argv[1:] if argv is None else argv
    logging.basicConfig(level=logging.INFO, stream=sys.stderr, format="%(message)s")
    if len(argv) != 1:
        print("usage: python -m holo_core.phase.display_frame FOLDER", file=sys.stderr)
        return 2
    try:
        frame = DisplayFrame.from_dict(json.loads((Path(argv[0]) / "frame.json").read_text()))
        layout = make_frame(frame, lambda f: print(f"HOLO_PROGRESS {f:.4f}", flush=True))
    except (ValueError, OSError) as e:
        print(f"{type(e).__name__}: {e}", file=sys.stderr)
        return 1
    print(json.dumps(layout), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
