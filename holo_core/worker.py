"""The pipeline in a process of its own: the Blender add-on's worker.

Blender's process never loads an OpenCL driver: drivers bring native libraries that clash with
Blender's (Intel's CPU runtime needs a newer TBB than Blender bundles, and PoCL's LLVM then
meets Intel's), and a driver crash or an out-of-memory must not take unsaved work down with it.
The parent hands a job of plain data (NumPy arrays and holo_core's value types, pickled into a
folder of its own) to ``python -m holo_core.worker FOLDER``. The worker reports progress and
log records as JSON lines on its stdout, writes its outputs atomically once every stage has
finished, and leaves its result in the folder; the parent kills it to cancel, so a cancelled or
failed run leaves earlier files as they were.

:func:`run_job` is the work itself; :class:`Worker` is the parent's handle. This module imports
nothing of OpenCL in the parent.
"""

from __future__ import annotations

import json
import logging
import os
import pickle
import queue
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from . import jobs

log = logging.getLogger(__name__)


def pass_file(folder, frame: int) -> Path:
    """Frame ``frame``'s holographic pass in ``folder``: ``holo_pass_NNNN.exr``, one file per
    frame and nothing shared between frames (farm workers never write the same file)."""
    return Path(folder) / f"holo_pass_{frame:04d}.exr"


def _check_outputs(job: dict) -> None:
    """:class:`InputError` for a hologram or pass file that cannot be written, before any work
    (a read-only output folder is found at once, not after the recording)."""
    from .io.image import check_writable
    outputs = [] if job["current"] else list(job["holograms"])
    if job["render"]:
        outputs.append(pass_file(job["output_dir"], job["frame"]))
    for path in outputs:
        check_writable(path, ".exr")


class WorkerError(RuntimeError):
    """The worker failed: the message says how (its error, or how the process died)."""


def run_job(job: dict, progress: jobs.Progress = None, on_partial=None) -> dict:
    """Record the holograms (unless ``job['current']``) and render the pass.

    ``job``: ``points``, ``triangles`` (lists of :class:`holo_core.scene.mesh.Mesh`, world metres),
    ``plate``, ``camera``, ``settings`` (dict: mode 'CAMERA' or 'PLATE', speckle 'EXACT' or
    'LOOKS' (:data:`CAMERA_ROUTES`), samples, max_resolution, wavelength [m] or None,
    iterations, supersample, composition, exposure, opacity_threshold, seed), ``holograms``
    (paths of the iterations' files), ``current``,
    ``render``, ``output_dir``, ``frame``; optional ``radiance`` (the emitters' colours from a
    renderer, :func:`lit_emitters`), ``depth_unit`` (metres per unit of the pass's depth),
    ``border``, ``pass_key``. 'CAMERA' renders the camera hologram
    (:mod:`holo_core.camera`; no plate, no hologram file); 'PLATE' records the
    plate's holograms (unless ``current``) and views them. Returns ``recorded``,
    ``pass_path``, ``frame_path`` and ``info``. Files are written only after every stage has
    finished, each one atomically; ``on_partial(view, n)`` gets a camera hologram's running
    result after 1, 2, 4, 8 … samples (the user may stop there and keep it)."""
    from .io.hologram import read_hologram, write_hologram
    from .plate.record import look_code, record_hologram
    from .plate.view import nyquist_supersample, render_view
    s, current, n = job["settings"], job["current"], len(job["holograms"])
    _check_outputs(job)
    lit_seconds = None
    if job.get("radiance") and not current:
        share, start = RADIANCE_SHARE, time.perf_counter()
        job = {**job, **lit_emitters(job, jobs.scaled(progress, 0.0, share))}
        progress = jobs.scaled(progress, share, 1.0)
        lit_seconds = time.perf_counter() - start
    job = {**job, "radiance_seconds": lit_seconds}
    if s.get("mode", "PLATE") == "CAMERA":
        from .camera.render import render_camera
        def sample(view, n):
            if on_partial is not None and n < s["samples"] and not n & (n - 1):
                on_partial(view, n)

        view = render_camera(job["points"] + job["triangles"], job["camera"],
                             samples=s["samples"], supersample=s["supersample"],
                             exposure=s["exposure"], seed=s["seed"], progress=progress,
                             via=CAMERA_ROUTES[s.get("speckle", "EXACT")], on_sample=sample)
        return _write_pass(job, view, {"recorded": False})
    record_share = 0.0 if current else (0.85 if job["render"] else 1.0)
    if current:
        holos = [read_hologram(p) for p in job["holograms"]]
    else:
        # a plate with its viewing zone is a scene asset: the camera sizes nothing of it (its
        # samples are Max Hologram Size), so moving or refocusing it never records again
        asset = job["plate"].zone is not None
        # the iterations are coded looks of one seed where n allows (look_code), else seeds
        codes = [look_code(i, n) for i in range(n)]
        holos = [record_hologram(
            job["points"], triangles=job["triangles"], plate=job["plate"],
            camera=None if asset else job["camera"],
            resolution=s["max_resolution"] if asset else None,
            max_resolution=s["max_resolution"], wavelength=s["wavelength"],
            seed=s["seed"] + (0 if code else i), code=code,
            progress=jobs.scaled(progress, record_share * i / n, record_share * (i + 1) / n))
            for i, code in enumerate(codes)]
    view = None
    if job["render"]:
        # the panel's Supersample, or the intensity's Nyquist rate where that is finer
        fine = max(s["supersample"], nyquist_supersample(holos[0], job["camera"]))
        view = render_view(holos, job["camera"], supersample=fine,
                           composition=s["composition"], opacity_threshold=s["opacity_threshold"],
                           progress=jobs.scaled(progress, record_share, 1.0))
        view.rgb[...] *= s["exposure"]
    # every stage has finished: only now are files replaced (each one atomically)
    Path(job["output_dir"]).mkdir(parents=True, exist_ok=True)
    if not current:
        for path, h in zip(job["holograms"], holos):
            write_hologram(path, h)
    return _write_pass(job, view, {"recorded": not current})


# the camera hologram's route per setting: the looks' limit in one pass, or progressive looks
CAMERA_ROUTES = {"EXACT": "incoherent", "LOOKS": "object_wave"}
RADIANCE_SHARE = 0.2  # of the progress bar: the renderer's radiance before the hologram


def lit_emitters(job: dict, progress: jobs.Progress = None) -> dict:
    """``points`` and ``triangles`` textured with the radiance a renderer saw from a camera
    (:func:`holo_core.scene.radiance.projected`). ``job['radiance']``: ``command`` (the
    renderer's command line, which writes ``image``: an RGBA OpenEXR of the emitters alone,
    premultiplied, as ``camera`` sees them, and may print ``HOLO_PROGRESS <fraction>`` lines),
    ``image``, ``camera``, and ``folder`` (its scratch folder, removed afterwards). The
    renderer runs in this process's group, so killing the worker's group ends it too."""
    from .io.image import read_exr
    from .scene.radiance import projected
    r = job["radiance"]
    try:
        tail = []
        with subprocess.Popen(r["command"], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, cwd=r["folder"], text=True,
                              errors="replace") as child:
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
        if child.returncode != 0 or not Path(r["image"]).is_file():
            raise RuntimeError(f"the radiance render failed (exit code {child.returncode}): "
                               + " | ".join(tail[-3:]))
        _, channels = read_exr(r["image"], what="radiance")
    finally:
        shutil.rmtree(r["folder"], ignore_errors=True)
    rgb = np.stack([channels[c] for c in "RGB"], -1)
    alpha = channels.get("A", np.ones(rgb.shape[:2], np.float32))
    return {kind: projected(job[kind], r["camera"], rgb, alpha)
            for kind in ("points", "triangles")}


def _write_pass(job, view, result) -> dict:
    """The pass of frame N (:func:`pass_file`); its depth in ``job['depth_unit']`` metres
    per unit (Blender's scene units: ``unit_settings.scale_length``), 1 when absent."""
    from .io.view import write_view
    from .view import BACKGROUND_DEPTH
    result.update(pass_path=None, frame_path=None, info={})
    if view is not None:
        if job.get("radiance_seconds") is not None:  # the lit radiance's share of the time
            view.info["radiance_seconds"] = round(job["radiance_seconds"], 3)
        unit = float(job.get("depth_unit") or 1.0)
        if unit != 1.0:
            near = view.depth < BACKGROUND_DEPTH
            view.depth[near] /= unit
        if job.get("border"):
            _outside_border(view, job["border"])
        frame_path = pass_file(job["output_dir"], job["frame"])
        if job.get("pass_key"):
            view.info["pass_key"] = job["pass_key"]
        write_view(view, frame_path)
        result.update(pass_path=frame_path, frame_path=frame_path, info=view.info)
    return result


def _outside_border(view, border) -> None:
    """Clear the pass outside Blender's render region (``border``: left, top, right, bottom
    pixels from the top-left corner), which the render leaves empty."""
    from .view import BACKGROUND_DEPTH
    left, top, right, bottom = border
    keep = np.zeros(view.alpha.shape, bool)
    keep[top:bottom, left:right] = True
    view.rgb[~keep] = 0
    view.alpha[~keep] = 0
    view.depth[~keep] = BACKGROUND_DEPTH


# --- the worker process ---------------------------------------------------------------------

class _Forward(logging.Handler):
    def __init__(self, send):
        super().__init__(logging.INFO)
        self.send = send

    def emit(self, record):
        self.send({"log": [record.levelno, record.getMessage()]})


def main(folder: str) -> int:
    """The worker: run ``FOLDER/job.pickle``, write ``FOLDER/result.pickle``."""
    channel = os.fdopen(os.dup(1), "w", buffering=1)
    os.dup2(2, 1)  # anything else printed, by Python or a driver, goes to stderr
    sys.stdout = sys.stderr

    def send(message):
        channel.write(json.dumps(message) + "\n")

    core = logging.getLogger("holo_core")
    core.addHandler(_Forward(send))
    core.setLevel(logging.INFO)
    folder = Path(folder)
    try:
        with open(folder / "job.pickle", "rb") as f:
            job = pickle.load(f)
        def partial(view, n):  # a complete pass of fewer samples, kept only if the user asks
            from .io.view import write_view
            write_view(view, folder / "partial.exr")
            send({"partial": n})

        result = run_job(job, lambda f: send({"progress": round(f, 4)}), partial)
        tmp = folder / "result.pickle.tmp"
        with open(tmp, "wb") as f:
            pickle.dump(result, f)
        os.replace(tmp, folder / "result.pickle")
        send({"done": True})
        return 0
    except Exception as e:  # reported to the parent as one line, the traceback on stderr
        import traceback
        traceback.print_exc()
        kind = "" if isinstance(e, (ValueError, OSError)) else f"{type(e).__name__}: "
        send({"error": f"{kind}{e}"})
        return 1


# --- the parent's handle ----------------------------------------------------------------------

def environment(paths=(), device: str | None = None, memory_limit: str | None = None,
                cache_dir: str | None = None) -> dict:
    """The parent's environment for a child Python: its module search path (the worker imports
    holo_core and its dependencies from wherever the parent found them, Blender's extension
    folder), ``paths`` before it (packages installed on demand), ``HOLO_DEVICE`` when
    ``device`` is given, ``HOLO_MEMORY_LIMIT`` when ``memory_limit`` is (e.g. "8G") and
    ``XDG_CACHE_HOME`` when ``cache_dir`` is (the folder of the OpenCL kernel cache and the
    FFTW wisdom)."""
    env = dict(os.environ)
    found = [str(p) for p in (*paths, *sys.path) if p and os.path.isdir(p)]
    env["PYTHONPATH"] = os.pathsep.join(dict.fromkeys(found))
    env["PYTHONUNBUFFERED"] = "1"
    if device:
        env["HOLO_DEVICE"] = device
    if memory_limit:
        env["HOLO_MEMORY_LIMIT"] = memory_limit
    if cache_dir:
        env["XDG_CACHE_HOME"] = str(cache_dir)
    return env


def _death(code: int) -> str:
    if code >= 0:
        return f"exit code {code}"
    try:
        name = signal.Signals(-code).name
    except ValueError:
        name = str(-code)
    why = {signal.SIGKILL: " (killed: out of memory?)",
           signal.SIGSEGV: " (a crash in native code: the OpenCL driver?)",
           signal.SIGABRT: " (aborted in native code: the OpenCL driver?)"}
    return f"signal {name}{why.get(-code, '')}"


class Worker:
    """One job in a worker process.

    ``poll()`` returns the messages that arrived, never blocking: ``("progress", fraction)``,
    ``("log", (level, text))``, ``("partial", samples)`` (a running camera-hologram pass), and
    last ``("done", result)`` or ``("failed", message)``. ``wait()`` runs it to the end
    (``blender --background``); ``cancel()`` kills it; ``stop_and_keep()`` kills it and hands
    over its latest running pass.
    """

    def __init__(self, job: dict, *, paths=(), device: str | None = None,
                 memory_limit: str | None = None, cache_dir: str | None = None):
        data = pickle.dumps(job, protocol=pickle.HIGHEST_PROTOCOL)  # plain data only
        self.folder = Path(tempfile.mkdtemp(prefix="holo-worker-"))
        (self.folder / "job.pickle").write_bytes(data)
        self._stderr = open(self.folder / "stderr.txt", "w+b")
        self._scratch = (job.get("radiance") or {}).get("folder")
        self.process = subprocess.Popen(
            [sys.executable, "-m", "holo_core.worker", str(self.folder)],
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=self._stderr,
            env=environment(paths, device, memory_limit, cache_dir), cwd=self.folder,
            start_new_session=os.name == "posix")  # its group: the renderer it runs dies too
        self._messages: queue.SimpleQueue = queue.SimpleQueue()
        self._error = None
        self.finished = False
        self.partial = 0  # samples of the latest running pass in the folder
        threading.Thread(target=self._read, daemon=True, name="holo-worker-reader").start()

    def _read(self):
        with self.process.stdout:
            for line in self.process.stdout:
                try:
                    self._messages.put(json.loads(line))
                except ValueError:
                    pass
        self._messages.put(None)  # end of output: the process has ended or is ending

    def poll(self, timeout: float | None = None) -> list[tuple]:
        """Messages that arrived (waiting up to ``timeout`` seconds for the first one)."""
        out = []
        while not self.finished:
            try:
                msg = self._messages.get(timeout=timeout) if timeout and not out else \
                    self._messages.get_nowait()
            except queue.Empty:
                break
            out.append(self._translate(msg))
            if out[-1][0] in ("done", "failed"):
                self.finished = True
                self._cleanup()
        return out

    def _translate(self, msg):
        if msg is None:
            code = self.process.wait()
            return ("failed", self._error or f"the worker process ended with {_death(code)}"
                    f"{self._stderr_tail()}")
        if "progress" in msg:
            return ("progress", float(msg["progress"]))
        if "log" in msg:
            return ("log", tuple(msg["log"]))
        if "partial" in msg:
            self.partial = int(msg["partial"])
            return ("partial", self.partial)
        if "error" in msg:
            self._error = msg["error"]
            return self._translate(None)
        self.process.wait()
        with open(self.folder / "result.pickle", "rb") as f:
            return ("done", pickle.load(f))

    def _stderr_tail(self) -> str:
        self._stderr.flush()
        self._stderr.seek(0)
        lines = [ln for ln in self._stderr.read().decode(errors="replace").splitlines()
                 if ln.strip()]
        return f"; its last output: {lines[-1][-300:]}" if lines else ""

    def wait(self, progress: jobs.Progress = None, on_log=None) -> dict:
        """Run to the end; ``progress`` may raise :class:`holo_core.jobs.Cancelled`, which
        kills the worker. Raises :class:`WorkerError` when the worker fails."""
        while True:
            for kind, value in self.poll(timeout=0.1):
                try:
                    if kind == "progress" and progress is not None:
                        progress(value)
                except BaseException:
                    self.cancel()
                    raise
                if kind == "log" and on_log is not None:
                    on_log(*value)
                elif kind == "done":
                    return value
                elif kind == "failed":
                    raise WorkerError(value)

    def _kill(self) -> None:
        """Kill the worker and whatever it started (a renderer: its process group)."""
        if self.process.poll() is None:
            if os.name == "posix":
                try:
                    os.killpg(self.process.pid, signal.SIGKILL)
                except OSError:
                    self.process.kill()
            else:
                self.process.kill()
        self.process.wait()

    def cancel(self) -> None:
        """Kill the worker now (its partial work is never written)."""
        self._kill()
        self.finished = True
        self._cleanup()

    def stop_and_keep(self, path) -> int:
        """Kill the worker and write its latest running pass to ``path`` with its PNG (as one
        unit, as :func:`holo_core.io.view.write_view` writes them): returns its samples, or 0
        when there was none yet (nothing is written)."""
        from .io.image import atomic_paths
        self.poll()  # the newest partial message
        self._kill()
        src = self.folder / "partial.exr"
        kept = self.partial if self.partial and src.is_file() else 0
        if kept:
            path = Path(path)
            with atomic_paths(path, path.with_suffix(".png")) as (exr, png):
                shutil.copyfile(src, exr)
                shutil.copyfile(src.with_suffix(".png"), png)
        self.finished = True
        self._cleanup()
        return kept

    def _cleanup(self):
        self._stderr.close()
        shutil.rmtree(self.folder, ignore_errors=True)
        if self._scratch:
            shutil.rmtree(self._scratch, ignore_errors=True)


def run(job: dict, progress: jobs.Progress = None, on_log=None, **options) -> dict:
    """:func:`run_job` in a worker process (``options``: :class:`Worker`'s), waiting for it."""
    return Worker(job, **options).wait(progress, on_log)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
