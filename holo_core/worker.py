"""The pipeline in a process of its own: the parent's handle on the Blender add-on's worker.

Blender's process never loads an OpenCL driver: drivers bring native libraries that clash with
Blender's (Intel's CPU runtime needs a newer TBB than Blender bundles, and PoCL's LLVM then
meets Intel's), and a driver crash or an out-of-memory must not take unsaved work down with it.
The parent hands a :class:`~holo_core.job.Job` as plain data (its ``to_dict``, pickled into a
folder of its own) to a ``python -m holo_core.runner --serve`` process, one folder a line on
its stdin; it runs each (:func:`holo_core.runner.run`), reports progress and log records as
JSON lines on its stdout, writes its outputs atomically once every stage has finished, and
leaves its :class:`~holo_core.job.Result` in the folder; the parent kills it to cancel, so a
cancelled or failed run leaves earlier files as they were. A process serves one job, or, kept
between the frames of a render (``resident``), the frames one after another with the plate
held in memory.

:class:`Worker` is the parent's handle, as Cycles' ``engine.py`` is Blender's on its renderer;
this module and what it imports load nothing of OpenCL.

:class:`Views` is the handle on a view-serving worker (``python -m holo_core.view_server``,
the same serving loop): it holds a recorded plate and answers views as a camera moves, each
picture handed back through shared memory (:mod:`holo_core.io.shared_view`), never a file.
"""

from __future__ import annotations

import atexit
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
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import jobs
from .io.image import atomic_paths
from .io.shared_view import SharedView, slot_bytes
from .job import Job, Result, ViewOpen, ViewReply, ViewRequest
from .scene.camera import Camera

_log = logging.getLogger(__name__)


class WorkerError(RuntimeError):
    """The worker failed: the message says how (its error, or how the process died)."""


# --- the parent's handle ----------------------------------------------------------------------


def environment(
    paths=(),
    device: str | None = None,
    memory_limit: str | None = None,
    cache_dir: str | None = None,
) -> dict:
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
    why = {
        signal.SIGKILL: " (killed: out of memory?)",
        signal.SIGSEGV: " (a crash in native code: the OpenCL driver?)",
        signal.SIGABRT: " (aborted in native code: the OpenCL driver?)",
    }
    return f"signal {name}{why.get(-code, '')}"


class _Process:
    """A worker process (``python -m holo_core.runner --serve``) and the reader of its stdout.

    It runs the job folders written to its stdin one after another, and ends when its stdin
    closes, when it is left idle (``IDLE_SECONDS``) or after a failed job. Its
    stderr goes to a file of its own folder (the last line explains a death)."""

    def __init__(self, env: dict, command=("holo_core.runner", "--serve")):
        self.env = env
        self.folder = Path(tempfile.mkdtemp(prefix="holo-process-"))
        self.stderr = open(self.folder / "stderr.txt", "w+b")
        self.popen = subprocess.Popen(
            [sys.executable, "-m", *command, str(IDLE_SECONDS)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self.stderr,
            env=env,
            cwd=self.folder,
            start_new_session=os.name == "posix",
        )  # its group: the renderer it runs dies too
        self.messages: queue.SimpleQueue = queue.SimpleQueue()
        self.busy = False
        self.idle_since = time.monotonic()
        threading.Thread(target=self._read, daemon=True, name="holo-worker-reader").start()

    def _read(self):
        with self.popen.stdout:
            for line in self.popen.stdout:
                try:
                    self.messages.put(json.loads(line))
                except ValueError:
                    pass
        self.messages.put(None)  # end of output: the process has ended or is ending

    def ready(self) -> bool:
        """Alive, and idle for too short a time to be ending (it ends after IDLE_SECONDS
        without a job: one handed over just then could be lost)."""
        fresh = time.monotonic() - self.idle_since < IDLE_SECONDS - IDLE_GRACE
        return fresh and self.popen.poll() is None

    def submit(self, folder: Path, *, last: bool) -> None:
        """Hand it the job in ``folder``; ``last``: close its stdin (it ends after this
        job)."""
        self.busy = True
        self.popen.stdin.write(f"{folder}\n".encode())
        self.popen.stdin.flush()
        if last:
            self.popen.stdin.close()

    def stderr_tail(self) -> str:
        self.stderr.flush()
        self.stderr.seek(0)
        lines = [
            ln for ln in self.stderr.read().decode(errors="replace").splitlines() if ln.strip()
        ]
        return f"; its last output: {lines[-1][-300:]}" if lines else ""

    def kill(self) -> None:
        """Kill it and whatever it started (a renderer: its process group)."""
        if self.popen.poll() is None:
            if os.name == "posix":
                try:
                    os.killpg(self.popen.pid, signal.SIGKILL)
                except OSError:
                    self.popen.kill()
            else:
                self.popen.kill()
        self.popen.wait()

    def close(self) -> None:
        """Its end: stdin closed, it is given a moment to end on its own, then killed; its
        folder removed."""
        try:
            if not self.popen.stdin.closed:
                self.popen.stdin.close()
            self.popen.wait(timeout=2)
        except (OSError, subprocess.TimeoutExpired):
            pass
        self.kill()
        self.stderr.close()
        shutil.rmtree(self.folder, ignore_errors=True)


IDLE_SECONDS = 600  # a serving worker left this long without a job ends (its plate freed)
IDLE_GRACE = 60  # ... and is not handed a job in its last minute
# the process kept between jobs (resident=True)
_resident: _Process | None = None
_resident_lock = threading.Lock()


def _process(env: dict, resident: bool) -> _Process:
    """A fresh process of environment ``env``, or with ``resident`` the kept one: started
    when there is none alive with this environment (a preference or variable changed since
    starts a fresh one), or, while it is busy with another job, a fresh one not kept."""
    global _resident
    if not resident:
        return _Process(env)
    with _resident_lock:
        kept = _resident
        if kept is not None and kept.busy:
            return _Process(env)
        if kept is not None and (kept.env != env or not kept.ready()):
            kept.close()
            kept = None
        if kept is None:
            kept = _resident = _Process(env)
        return kept


def release() -> None:
    """End the resident worker process (a render's end): the plate it keeps in memory between
    frames is freed. Nothing happens when there is none; a job it runs is killed."""
    global _resident
    with _resident_lock:
        kept, _resident = _resident, None
    if kept is not None:
        kept.close()


atexit.register(release)


class Worker:
    """One job in a worker process.

    ``poll()`` returns the messages that arrived, never blocking: ``("progress", fraction)``,
    ``("log", (level, text))``, ``("partial", samples)`` (a running camera-hologram pass), and
    last ``("done", result)`` or ``("failed", message)``. ``wait()`` runs it to the end
    (``blender --background``); ``cancel()`` kills it; ``stop_and_keep()`` kills it and hands
    over its latest running pass.

    ``resident``: the job runs in the process kept between jobs (started on first use), which
    keeps the plate's holograms it read or recorded in memory, with its OpenCL programs and
    FFT plans: the next frame of a shot renders from them, where a fresh process would read
    the plate's files again. The process lives until :func:`release`, until it is idle for
    ``IDLE_SECONDS``, or until this process ends; a cancelled or failed job ends
    it (the next starts a fresh one).
    """

    def __init__(
        self,
        job: Job,
        *,
        paths=(),
        device: str | None = None,
        memory_limit: str | None = None,
        cache_dir: str | None = None,
        resident: bool = False,
    ):
        data = pickle.dumps(job.to_dict(), protocol=pickle.HIGHEST_PROTOCOL)  # plain data
        self.folder = Path(tempfile.mkdtemp(prefix="holo-worker-"))
        (self.folder / "job.pickle").write_bytes(data)
        self._scratch = None if job.radiance is None else job.radiance.folder
        env = environment(paths, device, memory_limit, cache_dir)
        self._server = _process(env, resident)
        self._resident = self._server is _resident
        try:
            self._server.submit(self.folder, last=not self._resident)
        except OSError:  # the kept process ended as it was handed the job: a fresh one
            if not self._resident:
                raise
            release()
            self._server, self._resident = _process(env, False), False
            self._server.submit(self.folder, last=True)
        self._error = None
        self.finished = False
        self.partial = 0  # samples of the latest running pass in the folder

    @property
    def process(self) -> subprocess.Popen:
        """The worker's process (kept between jobs when resident)."""
        return self._server.popen

    def poll(self, timeout: float | None = None) -> list[tuple]:
        """Messages that arrived (waiting up to ``timeout`` seconds for the first one)."""
        out = []
        while not self.finished:
            try:
                msg = (
                    self._server.messages.get(timeout=timeout)
                    if timeout and not out
                    else self._server.messages.get_nowait()
                )
            except queue.Empty:
                break
            out.append(self._translate(msg))
            if out[-1][0] in ("done", "failed"):
                self._end(kill=out[-1][0] == "failed")
        return out

    def _translate(self, msg):
        if msg is None:
            code = self.process.wait()
            return (
                "failed",
                self._error
                or f"the worker process ended with {_death(code)}{self._server.stderr_tail()}",
            )
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
        with open(self.folder / "result.pickle", "rb") as f:
            return ("done", Result.from_dict(pickle.load(f)))

    def wait(self, progress: jobs.Progress = None, on_log=None) -> Result:
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

    def cancel(self) -> None:
        """Kill the worker now (its partial work is never written)."""
        self._server.kill()
        self._end(kill=True)

    def stop_and_keep(self, path) -> int:
        """Kill the worker and write its latest running pass to ``path`` with its PNG (as one
        unit, as :func:`holo_core.io.view.write_view` writes them): returns its samples, or 0
        when there was none yet (nothing is written)."""
        self.poll()  # the newest partial message
        self._server.kill()
        src = self.folder / "partial.exr"
        kept = self.partial if self.partial and src.is_file() else 0
        if kept:
            path = Path(path)
            with atomic_paths(path, path.with_suffix(".png")) as (exr, png):
                shutil.copyfile(src, exr)
                shutil.copyfile(src.with_suffix(".png"), png)
        self._end(kill=True)
        return kept

    def _end(self, *, kill: bool) -> None:
        """The job's end: its folders removed; its process closed unless it is the resident
        one and the job finished (a killed or failed one is ended: the next job starts a
        fresh process)."""
        self.finished = True
        shutil.rmtree(self.folder, ignore_errors=True)
        if self._scratch:
            shutil.rmtree(self._scratch, ignore_errors=True)
        if self._resident and not kill:
            self._server.busy = False
            self._server.idle_since = time.monotonic()
        elif self._resident:
            release()
        else:
            self._server.close()


def run(job: Job, progress: jobs.Progress = None, on_log=None, **options) -> Result:
    """The job run in a worker process (:func:`holo_core.runner.run`; ``options``:
    :class:`Worker`'s), waiting for it."""
    return Worker(job, **options).wait(progress, on_log)


# --- live views of a held plate ---------------------------------------------------------------


@dataclass(frozen=True, slots=True, kw_only=True)
class ViewPicture:
    """The newest finished answer of a :class:`Views`.

    Attributes
    ----------
    request : int
        The request it answers (:meth:`Views.ask`'s number).
    rgba : (H, W, 4) float32 array or None
        Straight radiance (exposure applied) and opacity, row 0 at the top; None where the
        camera was outside the zone or the view failed.
    depth : (H, W) float32 array or None
        Planar depth [m].
    coarse : bool
        A coarse view (a quick one while the camera moves).
    seconds : float
        The worker's time for it [s].
    where : str
        Why the camera is outside the plate's zone ('' inside).
    error : str
        What failed ('' : nothing).
    """

    request: int
    rgba: np.ndarray | None = None
    depth: np.ndarray | None = None
    coarse: bool = False
    seconds: float = 0.0
    where: str = ""
    error: str = ""


VIEW_SERVER = ("holo_core.view_server",)  # the view-serving worker's module


class Views:
    """Views of a plate held by a worker process of its own, pictures through shared memory.

    The worker (``python -m holo_core.view_server``, :mod:`holo_core.view_server`) holds the plate with its plans
    (:class:`holo_core.PlateViewer`, on the device where there is one) and renders each view
    as it is asked for; a view asked while newer ones wait behind it is skipped. Its pictures
    come back through a :class:`holo_core.io.shared_view.SharedView` this process owns. A
    worker that ended (a crash, its idle end, :meth:`close`) is started again at the next
    :meth:`ask`, with the same plate and settings.

    Parameters
    ----------
    plates : path or sequence of paths
        The kept plate's files (its looks' hologram files, or a plate set's manifest).
    recording : str
        The digest of the recording they must be ('' : not checked).
    supersample, composition, opacity_threshold, exposure
        As :class:`holo_core.job.ViewOpen`'s.
    paths, device, memory_limit, cache_dir
        The worker's environment, as :class:`Worker`'s.

    Examples
    --------
    >>> views = Views(["shot/plate_hologram.exr"])                     # doctest: +SKIP
    >>> n = views.ask(camera, coarse=True)                             # doctest: +SKIP
    >>> picture = views.wait(n, timeout=10.0)                          # doctest: +SKIP
    >>> picture.rgba.shape if not picture.where else picture.where     # doctest: +SKIP
    (360, 640, 4)
    >>> views.close()                                                  # doctest: +SKIP
    """

    def __init__(
        self,
        plates,
        *,
        recording: str = "",
        supersample="auto",
        composition: str = "mean",
        opacity_threshold: float = 0.5,
        exposure: float = 1.0,
        paths=(),
        device: str | None = None,
        memory_limit: str | None = None,
        cache_dir: str | None = None,
    ):
        self.settings = ViewOpen(
            plates=plates,
            recording=recording,
            supersample=supersample,
            composition=composition,
            opacity_threshold=opacity_threshold,
            exposure=exposure,
        )
        self._env = environment(paths, device, memory_limit, cache_dir)
        self._process: _Process | None = None
        self._shared: SharedView | None = None
        self._asked = 0  # the newest request's number
        self._shown = None  # the newest finished ViewPicture
        self._number = 0  # the shared view's newest picture read
        self._replies: dict = {}  # request -> ViewReply, newest kept
        self.opened = ""  # the recording the worker holds ('' : not yet)
        self.error = ""  # why the worker holds no plate, or why it ended
        self.starts = 0  # worker processes started (a crash starts another)
        self.answered = 0  # replies received (a skipped request gets none)
        self._closed = False

    def ask(self, camera: Camera, *, coarse: bool = False) -> int:
        """Ask the view from ``camera`` (its resolution [px] sizes the picture); returns the
        request's number at once. A newer request supersedes this one while it waits."""
        if self._closed:
            raise WorkerError("these views are closed")
        w, h = camera.resolution
        need = slot_bytes(w, h, 5)
        if self._shared is None or self._shared.capacity < need:
            old, self._shared, self._number = self._shared, SharedView.create(need), 0
            if old is not None:
                old.close()  # unlinked; a worker still writing into it keeps its mapping
        self._asked += 1
        request = ViewRequest(
            id=self._asked, camera=camera, shared=self._shared.name, coarse=coarse
        )
        self._send({"view": request.to_dict()})
        return self._asked

    def _send(self, message: dict) -> None:
        """One JSON line to the worker; one that ended is started again (the plate opened
        first), once, before the line is sent again."""
        line = (json.dumps(message) + "\n").encode()
        for attempt in (0, 1):
            if self._process is None or not self._process.ready():
                self._start()
            try:
                self._process.popen.stdin.write(line)
                self._process.popen.stdin.flush()
                self._process.idle_since = time.monotonic()  # its idle end starts again
                return
            except OSError:
                if attempt:
                    raise WorkerError(f"the view worker did not start: {self.error}") from None
                self._drain()  # it died: say how before the next

    def _start(self) -> None:
        self._drain()  # how the one before ended, where it did
        if self._process is not None:
            self._process.close()
        self._process = _Process(self._env, VIEW_SERVER)
        self.starts += 1
        self.opened = ""
        line = json.dumps({"open": self.settings.to_dict()}) + "\n"
        self._process.popen.stdin.write(line.encode())
        self._process.popen.stdin.flush()

    def _drain(self) -> None:
        """Take the worker's messages: its replies, its log records (logged here), its end."""
        process = self._process
        if process is None:
            return
        while True:
            try:
                msg = process.messages.get_nowait()
            except queue.Empty:
                return
            if msg is None:
                code = process.popen.wait()
                self.error = (
                    f"the view worker ended with {_death(code)}{process.stderr_tail()}"
                    if code
                    else ""
                )
                process.close()
                self._process = None
                return
            if "log" in msg:
                level, text = msg["log"]
                _log.log(level, "view worker: %s", text)
            elif "opened" in msg:
                self.opened, self.error = msg["opened"]["recording"], msg["opened"]["error"]
            elif "view" in msg:
                reply = ViewReply.from_dict(msg["view"])
                self.answered += 1
                self._replies = {
                    k: v for k, v in self._replies.items() if k >= reply.id - 8
                }  # a few kept for their pictures
                self._replies[reply.id] = reply

    def latest(self) -> ViewPicture | None:
        """The newest finished answer (a picture, or why there is none), or None before the
        first; never blocks. An answer to an older request than one shown is never shown
        after it."""
        self._drain()
        replies = [r for r in self._replies.values() if r.where or r.error] if self._replies else []
        newest = max(replies, key=lambda r: r.id, default=None)
        picture = self._shared.read(after=self._number) if self._shared is not None else None
        if picture is not None:
            self._number = picture.number
        shown = self._shown.request if self._shown is not None else 0
        if (
            picture is not None
            and picture.request > shown
            and (newest is None or picture.request > newest.id)
        ):
            self._shown = ViewPicture(
                request=picture.request,
                rgba=picture.rgba,
                depth=picture.depth,
                coarse=picture.coarse,
                seconds=picture.seconds,
            )
        elif newest is not None and newest.id > shown:
            self._shown = ViewPicture(
                request=newest.id,
                coarse=newest.coarse,
                seconds=newest.seconds,
                where=newest.where,
                error=newest.error,
            )
        return self._shown

    def wait(self, request: int, timeout: float = 60.0) -> ViewPicture:
        """Wait for the answer to ``request`` (or a newer one) [s at most]; raises
        :class:`WorkerError` when the worker ends or the time runs out first."""
        end = time.monotonic() + timeout
        while True:
            shown = self.latest()
            if shown is not None and shown.request >= request:
                return shown
            if self._process is None:
                raise WorkerError(self.error or "the view worker ended")
            if time.monotonic() > end:
                raise WorkerError(f"no answer to view {request} within {timeout:g} s")
            time.sleep(0.002)

    @property
    def shared_name(self) -> str:
        """The name of the shared view the pictures come through ('' before the first
        request)."""
        return "" if self._shared is None else self._shared.name

    @property
    def process(self) -> subprocess.Popen | None:
        """The worker's process (None: none running)."""
        return None if self._process is None else self._process.popen

    def close(self) -> None:
        """End the worker and unlink the shared view. Asking again raises."""
        self._closed = True
        if self._process is not None:
            self._process.close()
            self._process = None
        if self._shared is not None:
            self._shared.close()
            self._shared = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        if not getattr(self, "_closed", True):
            self.close()
