"""Dask, the runtime of tiled recordings: a client of a scheduler or of a local cluster, the
scheduler's address checked by a raw TCP probe before any work (a wrong endpoint fails fast
and by name), and tasks run with their progress and cancellation.
"""

from __future__ import annotations

import contextlib
import logging
import os
import socket
import struct
from contextlib import contextmanager

from . import jobs
from .validate import InputError

log = logging.getLogger(__name__)
CONNECT_TIMEOUT = 10.0  # [s] to reach a scheduler and hear its first message
MAX_HANDSHAKE = 2**20  # bytes a Dask scheduler's first message may claim (a few hundred)


def scheduler_address(scheduler=None) -> str | None:
    """The scheduler's address (``scheduler``, else ``DASK_SCHEDULER_ADDRESS``; None: a local
    cluster), checked to answer as a Dask scheduler (:class:`InputError` naming it)."""
    address = scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS")
    if address:
        _probe(address)
    return address


def run_tasks(
    task, shared, calls, *, address=None, progress: jobs.Progress = None, dashboard=None, lost=None
) -> None:
    """``task(shared, *args)`` for each ``args`` of ``calls``, on the cluster of
    :func:`client_for` (``address``): ``shared`` scattered once to every worker, the fraction
    done to ``progress``, the dashboard's address to ``dashboard``; tasks lost with the
    workers or the scheduler raise :class:`TasksLost` saying ``lost()`` (what was kept)."""
    with client_for(address) as client:
        if dashboard is not None:
            dashboard(client.dashboard_link)
        data = client.scatter(shared, broadcast=True)
        futures = [client.submit(task, data, *args, pure=False) for args in calls]
        _wait(client, futures, progress, lost=lost)


@contextmanager
def client_for(scheduler=None):
    """A Dask client: of the scheduler at ``scheduler`` (or ``DASK_SCHEDULER_ADDRESS``), else
    of a local cluster with one single-threaded worker process per core (each worker holds
    its own OpenCL context), listening on 127.0.0.1 alone (``HOLO_DASK_HOST``: the host or
    interface address to listen on instead); its dashboard's address is logged."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise InputError("tiled plates need Dask: pip install 'holo[tiles]'") from None
    address = scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS")
    if address:
        with _connected(Client, address) as client:
            log.info("Dask scheduler %s, dashboard %s", address, client.dashboard_link)
            yield client
        return
    # the scheduler, the workers and the dashboard (a recording's tasks, logs and profiles)
    # listen on loopback only, unless HOLO_DASK_HOST names the interface to publish them on
    host = os.environ.get("HOLO_DASK_HOST", "").strip() or "127.0.0.1"
    with (
        LocalCluster(
            n_workers=os.cpu_count() or 1,
            threads_per_worker=1,
            processes=True,
            host=host,
            dashboard_address=f"[{host}]:0" if ":" in host else f"{host}:0",
        ) as cluster,
        Client(cluster) as client,
    ):
        log.info("local Dask cluster, dashboard %s", client.dashboard_link)
        yield client


@contextmanager
def _connected(Client, address):
    """A client of the scheduler at ``address``, or :class:`InputError` naming it within
    ``CONNECT_TIMEOUT`` seconds: an address that is not one, an unknown host, a refused
    connection, a port that never answers or answers other than a scheduler."""
    _probe(address)
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT)
    except Exception as e:  # noqa: BLE001 -- Dask's failures to connect vary; all mean one thing
        raise InputError(
            f"scheduler {address}: cannot connect ({type(e).__name__}: {e})"[:400]
        ) from None
    with client:
        yield client


def _probe(address) -> None:
    """Reach a TCP scheduler and read the length of its first message (a Dask scheduler
    speaks first, a few hundred bytes) within ``CONNECT_TIMEOUT`` seconds, so that a wrong
    endpoint fails fast and by name instead of hanging or allocating what garbage claims."""
    from distributed.comm.addressing import parse_address, parse_host_port

    what = f"scheduler {address}"
    try:
        scheme, location = parse_address(address)
        if scheme not in ("tcp", "tls"):
            return  # another transport (inproc://, ucx://): Dask's own timeout applies
        host, port = parse_host_port(location)
    except (ValueError, TypeError) as e:
        raise InputError(f"{what}: not a scheduler address (tcp://host:port; {e})"[:300]) from None
    try:
        with socket.create_connection((host, port), timeout=CONNECT_TIMEOUT) as s:
            if scheme == "tls":
                return  # its messages are encrypted: reaching it is what can be checked
            header = _receive(s, 8)
    except socket.gaierror as e:
        raise InputError(f"{what}: unknown host {host!r} ({e.strerror})") from None
    except ConnectionRefusedError:
        raise InputError(f"{what}: refuses connections (is a scheduler running there?)") from None
    except TimeoutError:
        raise InputError(
            f"{what}: no answer within {CONNECT_TIMEOUT:g} s (is it a Dask scheduler?)"
        ) from None
    except OSError as e:
        raise InputError(f"{what}: cannot connect ({e.strerror or e})") from None
    if header is None:
        raise InputError(f"{what}: closed the connection without a word; not a Dask scheduler")
    (claimed,) = struct.unpack("<Q", header)
    if not 0 < claimed <= MAX_HANDSHAKE:
        raise InputError(
            f"{what}: answers, but not as a Dask scheduler (its first message "
            f"claims {claimed} bytes)"
        )


def _receive(sock, n) -> bytes | None:
    data = b""
    while len(data) < n:
        part = sock.recv(n - len(data))
        if not part:
            return None
        data += part
    return data


class TasksLost(RuntimeError):
    """A recording's tasks lost with the Dask workers or the scheduler that ran them; the
    message says what was kept and how to go on."""


def _wait(client, futures, progress, lost=None) -> None:
    """Each task's result as it finishes, with the fraction done to ``progress``; on a
    cancellation or a failed task the rest are cancelled. Tasks lost with their workers or
    the scheduler (Dask's ``CancelledError``, ``KilledWorker``, a closed connection) are
    :class:`TasksLost` in ``lost()``'s words (the stores and the tiles they keep)."""
    from concurrent.futures import CancelledError

    from distributed import KilledWorker, as_completed
    from distributed.comm import CommClosedError

    try:
        for n, future in enumerate(as_completed(futures), 1):
            future.result()  # a failed tile raises its error here
            jobs.report(progress, n, len(futures))
    except (CancelledError, KilledWorker, CommClosedError) as e:
        with contextlib.suppress(Exception):  # the scheduler may be gone with them
            client.cancel(futures)
        why = f"{type(e).__name__}: {e}".splitlines()[0][:200]
        raise TasksLost(
            f"the recording lost its Dask workers or scheduler ({why}); "
            f"{lost() if lost else 'the tiles written are kept'}; run the same "
            f"recording again to resume it"
        ) from None
    except BaseException:
        client.cancel(futures)
        raise
