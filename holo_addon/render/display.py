"""A holographic display's frame: each laser's wave recorded as a plate in the worker
(:func:`holo_addon.render.pipeline.start`; a wave recorded before for the same scene is
reused), then the frame's patterns, layout and focal stack made by the core's frame stage in
a process of its own (:mod:`holo_core.phase.display_frame`: no OpenCL in Blender's process),
which writes them all at once. A cancelled or failed frame leaves the earlier frames'
files as they were; a frame whose layout holds this scene's digest is up to date and is not
made again.
"""

from __future__ import annotations

import json
import logging
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from holo_core import jobs
from holo_core.job import DisplayFrame, FrameLaser
from holo_core.worker import WorkerError, environment

from ..export.display import DisplayPrepared
from . import pipeline
from .options import worker_options

log = logging.getLogger(__name__)
PACKINGS = {"PNG8": "grey8", "PNG16": "grey16", "PACKED10": "packed10"}  # holo_core.io.slm's
RECORD_SHARE = 0.7  # of a frame's progress: the waves' recordings, before the frame stage


@dataclass(frozen=True)
class FrameResult:
    """What a display frame made: its ``layout`` (as its JSON file holds it), the layout's
    ``path``, whether it was ``made`` now (False: up to date), each laser's wave
    ``recorded`` now, and its ``seconds``."""

    layout: dict
    path: Path
    made: bool
    recorded: tuple
    seconds: float

    @property
    def sheet(self) -> Path:
        """The focal stack's contact sheet (PNG)."""
        return self.path.parent / self.layout["stack"]["sheet"]


def frame_of(prepared: DisplayPrepared) -> DisplayFrame:
    """The core's description of the frame's stage."""
    spec = prepared.spec
    lasers = tuple(
        FrameLaser(
            name=laser.name,
            wavelength=laser.wavelength,
            power=laser.power,
            hologram=str(p.holograms[0]),
            channel=laser.channel,
            table=laser.table,
        )
        for laser, p in prepared.colours
    )
    return DisplayFrame(
        name=spec.name,
        frame=prepared.frame,
        folder=str(prepared.folder),
        resolution=spec.resolution,
        pitch=spec.pitch,
        bit_depth=spec.bit_depth,
        phase_range=spec.phase_range,
        inverted=spec.inverted,
        packing=PACKINGS[spec.pattern_format],
        lasers=lasers,
        scale=spec.scale,
        front=spec.front,
        behind=spec.behind,
        eye_distance=spec.eye_distance,
        eye_box=spec.eye_box,
        pupil=spec.pupil,
        distance=prepared.distance,
        method=spec.method,
        iterations=spec.iterations,
        slices=spec.slices,
        digest=prepared.digest,
    )


def layout_path(frame: DisplayFrame) -> Path:
    """The frame's layout: ``frame_NNNN.json`` in its folder (it names the frame's files)."""
    return Path(frame.folder) / f"{frame.stem()}.json"


def current(frame: DisplayFrame) -> dict | None:
    """The frame's layout when it and the files it names are there and it was made from
    this digest, else None."""
    path = layout_path(frame)
    try:
        layout = json.loads(path.read_text())
        names = [x[key] for x in layout["lasers"] for key in ("pattern", "layout")] + [
            layout["stack"]["file"],
            layout["stack"]["sheet"],
        ]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if layout.get("digest") != frame.digest or not frame.digest:
        return None
    return layout if all((path.parent / str(n)).is_file() for n in names) else None


def run(
    prepared: DisplayPrepared,
    progress: jobs.Progress = None,
    on_log=None,
    *,
    resident: bool = False,
) -> FrameResult:
    """Make the frame (module docstring). ``progress`` may raise
    :class:`holo_core.jobs.Cancelled`: the running process is killed and nothing of the
    frame is written. A failed stage raises :class:`holo_core.worker.WorkerError`."""
    started = time.perf_counter()
    frame = frame_of(prepared)
    layout = current(frame)
    if layout is not None:
        return FrameResult(
            layout=layout,
            path=layout_path(frame),
            made=False,
            recorded=(),
            seconds=time.perf_counter() - started,
        )
    todo = [(laser, p) for laser, p in prepared.colours if p.records]
    recorded = []
    for i, (laser, p) in enumerate(todo):
        share = jobs.scaled(
            progress, RECORD_SHARE * i / len(todo), RECORD_SHARE * (i + 1) / len(todo)
        )
        pipeline.start(p, resident=resident).wait(share, on_log)
        recorded.append(laser.name)
    layout = _stage(frame, jobs.scaled(progress, RECORD_SHARE if todo else 0.0, 1.0))
    return FrameResult(
        layout=layout,
        path=layout_path(frame),
        made=True,
        recorded=tuple(recorded),
        seconds=time.perf_counter() - started,
    )


def _stage(frame: DisplayFrame, progress: jobs.Progress) -> dict:
    """The core's frame stage in a child process, its progress drained as it runs; killed
    when ``progress`` raises."""
    with tempfile.TemporaryDirectory(prefix="holo-display-") as folder:
        (Path(folder) / "frame.json").write_text(json.dumps(frame.to_dict()))
        command = [sys.executable, "-m", "holo_core.phase.display_frame", folder]
        with tempfile.TemporaryFile("w+") as errors:
            # the worker's environment (the preferences' device, memory limit, kernel cache);
            # its own session, so that a kill reaches what it started too
            child = subprocess.Popen(
                command,
                stdout=subprocess.PIPE,
                stderr=errors,
                text=True,
                env=environment(**worker_options()),
                start_new_session=os.name == "posix",
            )
            last = ""
            try:
                for line in child.stdout:
                    if line.startswith("HOLO_PROGRESS "):
                        if progress is not None:
                            progress(float(line.split()[1]))
                    elif line.strip():
                        last = line
                code = child.wait()
            except BaseException:
                child.kill()
                child.wait()
                raise
            finally:
                child.stdout.close()
            if code != 0:
                errors.seek(0)
                lines = [t for t in errors.read().splitlines() if t.strip()]
                raise WorkerError(
                    f"the display frame {frame.frame} failed: "
                    f"{lines[-1] if lines else f'exit code {code}'}"
                )
    return json.loads(last)


def summary(name: str, result: FrameResult) -> str:
    """The frame's log line: what it made, in what time, where, and each laser's PSNR [dB]
    and SSIM per focal slice (the quantised pattern's stack against the wave's)."""
    layout = result.layout
    lasers = layout["lasers"]
    verb = (
        (
            f"made in {result.seconds:.1f} s"
            + (f" (waves recorded: {', '.join(result.recorded)})" if result.recorded else "")
        )
        if result.made
        else "up to date"
    )
    depths = " ".join(f"{z * 1e3:.3g}" for z in layout["stack"]["depths"])
    scores = "; ".join(
        f"{laser['name']} PSNR "
        + " ".join(f"{v:.1f}" for v in laser["psnr_db"])
        + " dB, SSIM "
        + " ".join(f"{v:.3f}" for v in laser["ssim"])
        for laser in lasers
    )
    return (
        f"display '{name}' frame {layout['frame']}: {len(lasers)} pattern(s) "
        f"{verb}: {result.path}; focal slices at {depths} mm: {scores}"
    )
