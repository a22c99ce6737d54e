"""The worker process's side: :func:`run` makes a :class:`~holo_core.job.Job`'s pass (and a
plate's holograms), dispatching on its route; :func:`serve` is the process
(``python -m holo_core.runner --serve IDLE``, started by :class:`holo_core.worker.Worker`),
which runs the job folders named on its stdin in turn, holding the plate between them
(``KeptPlates``), and :func:`main` runs one (``python -m holo_core.runner FOLDER``).

For each job the process reads its plain data from ``FOLDER/job.pickle`` (checked again as
it becomes a Job: the child trusts nothing it is handed), reports progress and log records
as JSON lines on its stdout, writes its outputs atomically once every stage has finished,
and leaves its :class:`~holo_core.job.Result` in ``FOLDER/result.pickle``. This module loads
the OpenCL driver; the parent never imports it.
"""

from __future__ import annotations

import json
import logging
import os
import pickle
import queue
import shutil
import subprocess
import sys
import threading
import time
import traceback
import warnings
from collections import deque
from dataclasses import replace
from pathlib import Path

import numpy as np

from . import estimate, jobs
from .camera.render import render_camera
from .io.hologram import HologramFileError, write_hologram
from .io.image import check_room, check_writable, read_exr
from .io.kept_plates import KeptPlates
from .io.plate_paths import store_of
from .io.plate_set import MANIFEST
from .io.tiled_wave import TiledWave
from .io.view import write_view
from .job import SPECKLE, CameraRoute, Job, PlateRoute, Report, Result, SetRoute
from .plate.looks import record_planned
from .plate.parts import record_set
from .plate.path import part_for
from .plate.plan import PlatePlan, plan_view
from .plate.recording import PlannedPlate, plate_plan
from .plate.view import OutsideZoneWarning, render_set_view, render_view
from .scene.radiance import projected
from .view import BACKGROUND_DEPTH

log = logging.getLogger(__name__)
RADIANCE_SHARE = 0.2  # of the progress bar: the renderer's radiance before the hologram


def run(
    job: Job, progress: jobs.Progress = None, on_partial=None, *, kept: KeptPlates | None = None
) -> Result:
    """Make the job: the emitters coloured by the renderer's radiance (when the job has
    one), then its route's holograms and view, then its files, each written atomically only
    after every stage has finished (a failed or cancelled run leaves earlier files as they
    were). ``on_partial(view, n)`` gets a camera hologram's running result after 1, 2, 4, 8 …
    samples (the user may stop there and keep it). ``kept``: the plate's holograms held
    from the jobs before (a serving worker's, :func:`serve`), used where their files are
    unchanged and updated with this job's."""
    start = time.perf_counter()
    _check_outputs(job)
    with _Heard() as heard:
        lit = None
        if job.radiance is not None:
            t = time.perf_counter()
            job = lit_emitters(job, jobs.scaled(progress, 0.0, RADIANCE_SHARE))
            progress = jobs.scaled(progress, RADIANCE_SHARE, 1.0)
            lit = time.perf_counter() - t
        route, recorded = job.route, ()
        if isinstance(route, CameraRoute):  # made for this view: no plate, no hologram file
            _say_estimate(job)

            def sample(view, n):
                if on_partial is not None and n < route.samples and not n & (n - 1):
                    on_partial(view, n)

            view = render_camera(
                job.points + job.triangles,
                job.camera,
                samples=route.samples,
                supersample=route.supersample,
                exposure=route.exposure,
                seed=route.seed,
                progress=progress,
                via=SPECKLE[route.speckle],
                on_sample=sample,
            )
        elif isinstance(route, SetRoute):
            view, recorded = _plate_set(
                job, progress, KeptPlates(hold=False) if kept is None else kept
            )
        else:
            view, recorded = _plate(job, progress, KeptPlates(hold=False) if kept is None else kept)
        path = None if view is None else _write_pass(job, view, lit)
    estimate.mark_warm("camera" if isinstance(job.route, CameraRoute) else "plate")
    report = Report.of(
        view,
        warnings=tuple(dict.fromkeys(heard.texts)),
        seconds=time.perf_counter() - start,
        radiance_seconds=lit,
    )
    return Result(recorded=recorded, pass_path=path, report=report, view=view)


def _plate(job: Job, progress, kept: KeptPlates):
    """The plate's holograms, recorded (or read when current, or ``kept`` from a job
    before), and their view: the stages in order, each called once from here."""
    route = job.route
    record_share = 0.0 if not route.record else (0.85 if job.output.render else 1.0)
    recording, viewing = (
        jobs.scaled(progress, 0, record_share),
        jobs.scaled(progress, record_share, 1.0),
    )
    if route.record:
        kept.clear()  # a new plate: the one held is not held beside it
        # a plate with its viewing zone is a scene asset: the camera sizes nothing of it (its
        # samples follow the zone and the views it is made for; the camera gives only the
        # pixel angle a zone of an earlier file lacks), so moving or refocusing the camera
        # never records again
        # the iterations are coded looks of one seed where n allows (look_code), else seeds,
        # every look in one pass; the plan is made once, here, and read by every stage
        planned, urls = _plan(job)
        _say_estimate(job, planned.plan)
        holos = record_planned(
            planned,
            seed=route.seed,
            urls=urls,
            scheduler=route.scheduler,
            recording=route.recording,
            phases=route.phases,
            progress=recording,
        )
    else:
        holos = kept.read(route.holograms, route.recording)
    view = None
    if job.output.render:
        view = render_view(
            holos,
            job.camera,
            supersample=route.supersample,
            composition=route.composition,
            opacity_threshold=route.opacity_threshold,
            progress=viewing,
        )
        view.rgb[...] *= route.exposure
    if route.record:  # every stage has finished: only now are files replaced (each atomically)
        job.output.folder.mkdir(parents=True, exist_ok=True)
        for path, h in zip(route.holograms, holos):
            if not isinstance(h.object_wave, TiledWave):  # a store is written as it is recorded
                write_hologram(path, h)
    kept.hold(route.holograms, holos)
    return view, route.holograms if route.record else ()


def _plate_set(job: Job, progress, kept: KeptPlates):
    """A plate set's parts recorded into its folder (those it lacks: a stopped recording
    resumes, a complete one records nothing), or read (or ``kept`` from a job before), and
    the view of the job's camera from the part that holds its pupil."""
    route = job.route
    record_share = 0.0 if not route.record else (0.85 if job.output.render else 1.0)
    if route.record:
        kept.clear()  # a new set: the one held is not held beside it
        plates = record_set(
            list(job.points) + list(job.triangles),
            route.parts,
            looks=route.looks,
            seed=route.seed,
            folder=route.folder,
            budget=(route.memory_budget, route.disk_budget),
            recording=route.recording,
            progress=jobs.scaled(progress, 0, record_share),
        )
        kept.hold_set(route.folder, plates)
    else:
        plates = kept.read_set(route.folder)
    if route.recording and plates.recording != route.recording:
        raise HologramFileError(
            f"{route.folder}: holds the plate set of recording "
            f"{plates.recording[:16]}, not {route.recording} (this "
            f"scene's): another recording's set under this name is never "
            f"rendered; record the set again"
        )
    if len(plates) != len(route.parts) or not all(
        np.allclose(a.plate.matrix_world, b.plate.matrix_world, atol=1e-9)
        for a, b in zip(plates.parts, route.parts)
    ):
        raise HologramFileError(
            f"{route.folder}: holds a set of {len(plates)} part(s) that "
            f"are not this job's {len(route.parts)}: another shot's set "
            f"under this name is never rendered; record the set again"
        )
    view = None
    if job.output.render:
        k, _ = part_for(plates, job.camera)
        view = render_set_view(
            plates,
            job.camera,
            frame=job.output.frame,
            outside=route.outside,
            supersample=route.supersample,
            composition=route.composition,
            opacity_threshold=route.opacity_threshold,
            progress=jobs.scaled(progress, record_share, 1.0),
        )
        view.rgb[...] *= route.exposure
        view.info["part"] = k
        if route.recording:
            log.info(
                "frame %d from part %d of %d of the plate set %s",
                job.output.frame,
                k + 1,
                len(plates),
                route.recording,
            )
    return view, ((route.folder / MANIFEST,) if route.record else ())


def _say_estimate(job: Job, p: PlatePlan | None = None) -> None:
    """Log the job's estimate (:func:`holo_core.estimate.job`) in this running worker: its
    work, and what a cold kernel cache adds (the worker's own start is behind it)."""
    view = None
    if p is not None and job.output.render:
        eye = job.route.plate.to_plate(np.asarray(job.camera.position)[None])[0]
        view = plan_view(
            p,
            position=eye,
            pixel_angle=job.camera.pixel_angle(),
            pupil=job.camera.aperture_diameter or None,
            resolution=job.camera.resolution,
        )
    est = replace(estimate.job(job, plan=p, view=view), process=0.0)
    log.info(
        "estimate: the %s %s",
        "plate's recording and view" if p is not None else "camera pass",
        est.words(),
    )


def _plan(job: Job) -> tuple[PlannedPlate, list[str] | None]:
    """The plan of the job's plate of meshes and its looks (:func:`plate_plan`), made once a
    job before any emitter is found and checked there against the route's budgets, and where
    the looks go: ``None`` (recorded in memory together), or where in one piece they exceed
    the route's memory budget or the host's share of its memory, the tiled stores beside
    their files (:func:`store_of`: recorded tile by tile on Dask, a cancelled recording
    resuming there). The disk that takes them is checked for their room now, before the
    recording."""
    route = job.route
    planned = plate_plan(
        list(job.points) + list(job.triangles),
        plate=route.plate,
        camera=job.camera,
        wavelength=route.wavelength,
        looks=len(route.holograms),
        budget=(route.memory_budget, route.disk_budget),
        tiled=None,
    )
    p, channels = planned.plan, len(planned.channels)
    check_room(
        route.holograms,
        p.disk_bytes(channels, tiled=planned.tiled) / p.looks,
        f"the plate's {{n}} look(s) ({p.shape[1]} x {p.shape[0]} samples, {channels} "
        f"channels{', in tiles' if planned.tiled else ''})",
    )
    return planned, [str(store_of(path)) for path in route.holograms] if planned.tiled else None


def _check_outputs(job: Job) -> None:
    """:class:`InputError` for a hologram or pass file that cannot be written, before any work
    (a read-only output folder is found at once, not after the recording)."""
    route = job.route
    outputs = list(route.holograms) if isinstance(route, PlateRoute) and route.record else []
    if isinstance(route, SetRoute) and route.record:
        check_writable(route.folder / MANIFEST, ".json")
    if job.output.render:
        outputs.append(job.output.pass_path)
    for path in outputs:
        check_writable(path, ".exr")


def lit_emitters(job: Job, progress: jobs.Progress = None) -> Job:
    """The job whose ``points`` and ``triangles`` are textured with the radiance its renderer
    saw (:func:`holo_core.scene.radiance.projected`; :class:`holo_core.job.Radiance`). The
    renderer runs in this process's group, so killing the worker's group ends it too; its
    scratch folder is removed afterwards."""
    r = job.radiance
    try:
        tail = []
        with subprocess.Popen(
            r.command,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            cwd=r.folder,
            text=True,
            errors="replace",
        ) as child:
            try:
                for line in child.stdout:
                    if line.startswith("HOLO_PROGRESS "):
                        jobs.report(progress, float(line.split()[1]), 1.0)
                    elif line.strip():
                        tail = (tail + [line.rstrip()])[-20:]
                        log.debug("renderer: %s", line.rstrip())
            except BaseException:
                child.kill()
                raise
        if child.returncode != 0 or not r.image.is_file():
            raise RuntimeError(
                f"the radiance render failed (exit code {child.returncode}): "
                + " | ".join(tail[-3:])
            )
        _, channels = read_exr(r.image, what="radiance")
    finally:
        shutil.rmtree(r.folder, ignore_errors=True)
    rgb = np.stack([channels[c] for c in "RGB"], -1)
    alpha = channels.get("A", np.ones(rgb.shape[:2], np.float32))
    points, triangles = (
        tuple(projected(list(meshes), r.camera, rgb, alpha))
        for meshes in (job.points, job.triangles)
    )
    return replace(job, points=points, triangles=triangles, radiance=None)


def _write_pass(job: Job, view, lit_seconds) -> Path:
    """The pass of the job's frame (:func:`holo_core.job.pass_file`); its depth in the
    output's ``depth_unit`` metres per unit (Blender's scene units), cleared outside its
    border."""
    out = job.output
    if lit_seconds is not None:  # the lit radiance's share of the time
        view.info["radiance_seconds"] = round(lit_seconds, 3)
    if out.depth_unit != 1.0:
        near = view.depth < BACKGROUND_DEPTH
        view.depth[near] /= out.depth_unit
    if out.border is not None:
        _outside_border(view, out.border)
    for key in ("pass_key", "shot_key"):
        if getattr(out, key):
            view.info[key] = getattr(out, key)
    write_view(view, out.pass_path)
    return out.pass_path


def _outside_border(view, border) -> None:
    """Clear the pass outside Blender's render region (``border``: left, top, right, bottom
    pixels from the top-left corner), which the render leaves empty."""
    left, top, right, bottom = border
    keep = np.zeros(view.alpha.shape, bool)
    keep[top:bottom, left:right] = True
    view.rgb[~keep] = 0
    view.alpha[~keep] = 0
    view.depth[~keep] = BACKGROUND_DEPTH


class _Heard(logging.Handler):
    """The warnings the core logs while it is installed, and those it raises as Python
    warnings (a view softer than its plate was made for, a black view, a hologram without
    depth), logged here in turn: the report's ``warnings``, and the log the worker sends to
    its parent. A camera beyond the plate's zone is left to the job's maker, which checks it
    before the job with its own names for the plate and its settings (the add-on's)."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.texts = []
        self.caught = warnings.catch_warnings(record=True)

    def emit(self, record):
        self.texts.append(record.getMessage())

    def __enter__(self):
        logging.getLogger("holo_core").addHandler(self)
        self.raised = self.caught.__enter__()
        warnings.simplefilter("always")
        return self

    def __exit__(self, *exc):
        self.caught.__exit__(*exc)
        for w in self.raised:
            if issubclass(w.category, OutsideZoneWarning):
                continue
            if w.category.__module__.startswith("holo_core."):
                log.warning("%s", w.message)
            else:  # another library's: as it would have been shown
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        logging.getLogger("holo_core").removeHandler(self)


# --- the process ------------------------------------------------------------------------------


class _Forward(logging.Handler):
    def __init__(self, send):
        super().__init__(logging.INFO)
        self.send = send

    def emit(self, record):
        self.send({"log": [record.levelno, record.getMessage()]})


def _channel():
    """``send(message)``: one JSON line to the parent on the process's stdout; anything else
    printed, by Python or a driver, goes to stderr from here on. The core's log records are
    sent too."""
    channel = os.fdopen(os.dup(1), "w", buffering=1)
    os.dup2(2, 1)
    sys.stdout = sys.stderr

    def send(message):
        channel.write(json.dumps(message) + "\n")

    core = logging.getLogger("holo_core")
    core.addHandler(_Forward(send))
    core.setLevel(logging.INFO)
    return send


def _job(folder: Path, send, kept: KeptPlates | None) -> bool:
    """Run ``FOLDER/job.pickle``, write ``FOLDER/result.pickle``; whether it succeeded (its
    error is sent as one line, the traceback on stderr)."""
    try:
        with open(folder / "job.pickle", "rb") as f:
            job = Job.from_dict(pickle.load(f))

        def partial(view, n):  # a complete pass of fewer samples, kept only if the user asks
            write_view(view, folder / "partial.exr")
            send({"partial": n})

        result = run(job, lambda f: send({"progress": round(f, 4)}), partial, kept=kept)
        tmp = folder / "result.pickle.tmp"
        with open(tmp, "wb") as f:
            pickle.dump(result.to_dict(), f)
        os.replace(tmp, folder / "result.pickle")
        send({"done": True})
        return True
    except Exception as e:  # noqa: BLE001 -- whatever failed, the parent hears it as the job's error
        traceback.print_exc()
        kind = "" if isinstance(e, (ValueError, OSError)) else f"{type(e).__name__}: "
        send({"error": f"{kind}{e}"})
        return False


def main(folder: str) -> int:
    """The worker of one job: run ``FOLDER/job.pickle``, write ``FOLDER/result.pickle``."""
    return 0 if _job(Path(folder), _channel(), None) else 1


def serve(idle: float, on_message=None) -> int:
    """The worker of many jobs (``python -m holo_core.runner --serve IDLE``): each line of
    stdin names a job's folder, run in turn (as :func:`main` runs one), the plate's
    holograms kept in memory between them (``KeptPlates``), or is a JSON message,
    handed to ``on_message(message, send)`` (:mod:`holo_core.view_server`'s live views),
    which returns whether the worker goes on; a message of a kind (its first key) that
    another of the same kind waits behind is skipped, the newest answered (a newer view
    supersedes an older). It ends when stdin closes (the parent ended, or has no more), when
    no line came for ``idle`` seconds, or after a job failed (a driver's state after an
    error is not trusted with the next)."""
    send, kept = _channel(), KeptPlates()
    lines: queue.SimpleQueue = queue.SimpleQueue()
    waiting: deque = deque()  # lines taken off the queue to look behind a message

    def listen():  # a thread, so that waiting for the next job can time out on any platform
        for line in sys.stdin:
            lines.put(line.strip())
        lines.put(None)

    threading.Thread(target=listen, daemon=True, name="holo-jobs").start()
    while True:
        try:
            line = waiting.popleft() if waiting else lines.get(timeout=idle)
        except queue.Empty:
            log.debug("no job for %.0f s: the worker ends", idle)
            return 0
        if line is None:
            return 0
        if line.startswith("{"):
            while True:  # whatever arrived since: a newer message of its kind supersedes it
                try:
                    waiting.append(lines.get_nowait())
                except queue.Empty:
                    break
            message = json.loads(line)
            kind = next(iter(message), "")
            if any(w and w.startswith("{" + json.dumps(kind) + ":") for w in waiting):
                continue
            if on_message is None:
                log.warning("a %r message, which this worker does not take", kind)
            elif not on_message(message, send):
                return 1
        elif line and not _job(Path(line), send, kept):
            return 1


if __name__ == "__main__":  # run as the package's module, so that its log records are the
    from holo_core import runner  # core's ("holo_core.runner", not "__main__") and reach the parent

    sys.exit(
        runner.serve(float(sys.argv[2])) if sys.argv[1] == "--serve" else runner.main(sys.argv[1])
    )
