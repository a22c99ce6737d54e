"""The worker process's side of live views: a plate held with its plans, views served as
they are asked for, pictures written into shared memory.

A view-serving worker is ``python -m holo_core.view_server IDLE`` (:func:`main`): the
serving loop of :func:`holo_core.runner.serve` (job folders run as ever), which hands each
JSON line of its stdin here: ``{"open": ViewOpen}``
makes a :class:`holo_core.PlateViewer` of the plate (held until the next open, its plans
reused by every view), ``{"view": ViewRequest}`` renders one view into the request's
:class:`~holo_core.io.shared_view.SharedView` and answers with a
:class:`~holo_core.job.ViewReply` line (``{"view": ...}``) on stdout. A camera outside the
plate's zone is answered with the viewer's sentence saying why, and no picture. The viewer
looks at the plate's files before each view: a file written again since is read again, one
gone or of another recording is named in the reply.
"""

from __future__ import annotations

import logging
import sys
import time

import numpy as np

from . import runner
from .io.shared_view import SharedView
from .job import ViewOpen, ViewReply, ViewRequest
from .validate import InputError

log = logging.getLogger(__name__)
# what a view may fail with and the worker survive: its input, its files; anything else (a
# driver's error) ends the worker, whose state is then not trusted with the next view
SURVIVED = (InputError, ValueError, OSError)


class ViewServer:
    """The held plate's viewer and the shared views it writes into (one worker's)."""

    def __init__(self):
        self.settings: ViewOpen | None = None
        self.viewer = None
        self._shared: dict[str, SharedView] = {}

    def open(self, settings: ViewOpen) -> None:
        """Hold the plate of ``settings`` (the one held before is closed first)."""
        from .plate.viewer import PlateViewer  # loads the OpenCL driver: the worker's alone

        self.close_viewer()
        self.settings = settings
        plates = list(settings.plates)
        self.viewer = PlateViewer(
            plates if len(plates) > 1 else plates[0],
            scene=settings.recording or None,
            **settings.options(),
        )
        log.info("live views of recording %s held", self.viewer.recording or "(unnamed)")

    def view(self, request: ViewRequest) -> ViewReply:
        """Render ``request``'s view into its shared view; the reply says how long it took,
        or why there is no picture (outside the zone: ``where``; a failure: ``error``)."""
        start = time.perf_counter()
        if self.settings is None:
            return ViewReply(id=request.id, error="no plate is held: open one first")
        if self.viewer is None:  # its opening failed: tried again, its error said again
            self.open(self.settings)
        where = self.viewer.where(request.camera)
        if where:
            return ViewReply(
                id=request.id,
                where=where,
                coarse=request.coarse,
                seconds=time.perf_counter() - start,
            )
        result = self.viewer.view(request.camera, coarse=request.coarse)
        planes = (result.rgb, result.alpha, result.depth)
        if not all(np.isfinite(p).all() for p in planes):
            return ViewReply(
                id=request.id, error="the view holds NaN or infinite values: nothing is shown"
            )
        h, w = np.shape(result.alpha)[:2]
        shared = self._attached(request.shared)
        with shared.writing(
            w, h, 5, request=request.id, coarse=request.coarse, started=start
        ) as out:
            np.multiply(result.rgb, self.settings.exposure, out=out[..., :3], casting="unsafe")
            out[..., 3] = result.alpha
            out[..., 4] = result.depth
        seconds = time.perf_counter() - start
        return ViewReply(id=request.id, seconds=seconds, shared=shared.name, coarse=request.coarse)

    def _attached(self, name: str) -> SharedView:
        """The shared view ``name``, attached once (those of earlier names are let go: the
        parent made a larger one)."""
        if name not in self._shared:
            for old in self._shared.values():
                old.close()
            self._shared = {name: SharedView.attach(name)}
        return self._shared[name]

    def close_viewer(self) -> None:
        if self.viewer is not None:
            self.viewer.close()
        self.viewer = None

    def close(self) -> None:
        self.close_viewer()
        for shared in self._shared.values():
            shared.close()
        self._shared = {}


def handle(server: ViewServer, message: dict, send) -> bool:
    """Answer one message (``{"open": ...}`` or ``{"view": ...}``) on ``send``; whether the
    worker may go on (False after a failure it should not survive)."""
    if "open" in message:
        try:
            server.open(ViewOpen.from_dict(message["open"]))
            send({"opened": {"recording": server.viewer.recording or "", "error": ""}})
        except SURVIVED as e:
            server.close_viewer()
            send({"opened": {"recording": "", "error": str(e)}})
        return True
    try:
        request = ViewRequest.from_dict(message.get("view"))
    except InputError as e:
        send({"view": ViewReply(id=0, error=str(e)).to_dict()})
        return True
    try:
        reply = server.view(request)
    except SURVIVED as e:
        reply = ViewReply(id=request.id, error=str(e))
    except Exception as e:  # said to the parent, then the worker ends
        log.exception("the view failed")
        send({"view": ViewReply(id=request.id, error=f"{type(e).__name__}: {e}").to_dict()})
        return False
    send({"view": reply.to_dict()})
    return True


def main(idle: float) -> int:
    """The view-serving worker (``python -m holo_core.view_server IDLE``): jobs and live
    views, until stdin closes or no line comes for ``idle`` seconds."""
    server = ViewServer()
    try:
        return runner.serve(idle, on_message=lambda message, send: handle(server, message, send))
    finally:
        server.close()


if __name__ == "__main__":  # run as the package's module, so that its log records are the
    from holo_core import view_server  # core's and reach the parent

    sys.exit(view_server.main(float(sys.argv[1])))
