"""Pictures through shared memory between two processes: every picture read is one the
writer completed (never half of one, never a mix of two), a writer that dies mid-picture
leaves the picture before it readable, and the segment's name is gone once its owner
closes it (and only then)."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from holo_core.io.shared_view import SharedView, slot_bytes
from holo_core.validate import InputError

ROOT = Path(__file__).resolve().parents[3]


def _child(code: str, *args, wait=True):
    """``code`` run in a fresh Python process (the worker's side), ``args`` as sys.argv[1:]."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), *sys.path]))
    run = subprocess.run if wait else subprocess.Popen
    kwargs = {"capture_output": True, "timeout": 60} if wait else {}
    return run([sys.executable, "-c", textwrap.dedent(code), *map(str, args)], env=env, **kwargs)


WRITER = """
    import sys
    import numpy as np
    from holo_core.io.shared_view import SharedView
    view = SharedView.attach(sys.argv[1])
    for n in range(1, int(sys.argv[2]) + 1):
        w, h = 40 + 7 * (n % 5), 30 + 3 * (n % 4)  # sizes change from picture to picture
        view.write(np.full((h, w, 4), float(n), np.float32), depth=np.full((h, w), -n),
                   request=n, coarse=n % 2 == 1)
    view.close()
"""


def test_a_reader_sees_only_complete_pictures_while_another_process_writes():
    """A writer process publishes 400 pictures, each filled with its request number and of
    its own size, while this one reads as fast as it can: each picture read is uniform,
    holds its own request's number in every RGBA and depth value, has that request's size
    and coarse flag, and the numbers only grow."""
    count = 400
    with SharedView.create(slot_bytes(72, 45)) as shown:
        writer = _child(WRITER, shown.name, count, wait=False)
        seen, last = [], 0
        while writer.poll() is None or shown.published > last:
            picture = shown.read(after=last)
            if picture is None:
                continue
            n = picture.request
            h, w, _ = picture.rgba.shape
            assert (w, h) == (40 + 7 * (n % 5), 30 + 3 * (n % 4)), (n, w, h)
            assert np.all(picture.rgba == n), f"picture {n} holds {np.unique(picture.rgba)}"
            assert np.all(picture.depth == -n), f"depth of {n}: {np.unique(picture.depth)}"
            assert picture.coarse == (n % 2 == 1)
            assert picture.number > last
            last = picture.number
            seen.append(n)
        assert writer.wait() == 0
        assert seen and seen[-1] == count, f"the last picture read was {seen[-1:]}"
        assert seen == sorted(seen)


def test_a_writer_killed_mid_picture_leaves_the_one_before_readable():
    """The writer publishes picture 1, then dies (SIGKILL) with picture 2 half written:
    the reader gets picture 1 whole; a writer that attaches afterwards publishes again."""
    code = """
        import os, signal, sys
        import numpy as np
        from holo_core.io.shared_view import SharedView
        view = SharedView.attach(sys.argv[1])
        view.write(np.full((8, 16, 4), 1.0, np.float32), request=1)
        with view.writing(16, 8, 4, request=2) as out:
            out[:4] = 2.0  # half of picture 2
            os.kill(os.getpid(), signal.SIGKILL)
    """
    with SharedView.create(slot_bytes(16, 8)) as shown:
        child = _child(code, shown.name)
        assert child.returncode == -9, child.stderr.decode()
        picture = shown.read()
        assert picture is not None and picture.request == 1
        assert np.all(picture.rgba == 1.0), np.unique(picture.rgba)
        writer = SharedView.attach(shown.name)
        writer.write(np.full((8, 16, 4), 3.0, np.float32), request=3)
        writer.close()
        after = shown.read(after=picture.number)
        assert after is not None and after.request == 3 and np.all(after.rgba == 3.0)


def test_the_segment_outlives_its_writer_and_is_unlinked_when_its_owner_closes():
    """A writer process that attaches and ends (its resource tracker too) leaves the segment
    in place; the owner's close removes its name: attaching then is refused, naming it."""
    shown = SharedView.create(slot_bytes(72, 45))
    name = shown.name
    child = _child(WRITER, name, 1)
    assert child.returncode == 0, child.stderr.decode()
    again = SharedView.attach(name)  # still there after the writer's process ended
    assert again.read().request == 1
    again.close()
    shown.close()
    with pytest.raises(InputError, match=name):
        SharedView.attach(name)
    if os.path.isdir("/dev/shm"):
        assert not os.path.exists(f"/dev/shm/{name}")


def test_names_are_unique_and_a_picture_too_large_or_not_finite_is_refused():
    a, b = SharedView.create(64), SharedView.create(64)
    try:
        assert a.name != b.name
        rgba = np.zeros((4, 4, 4), np.float32)
        with pytest.raises(InputError, match="needs 256 bytes"):
            a.write(rgba, request=1)
        rgba = np.zeros((2, 2, 4), np.float32)
        rgba[0, 0, 1] = np.nan
        with pytest.raises(InputError, match="NaN"):
            b.write(rgba, request=1)
        assert b.read() is None and b.published == 0
    finally:
        a.close()
        b.close()
