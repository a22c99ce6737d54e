"""Writes: atomic, the target's permissions kept, links replaced (never written through),
outputs checked before the work, temporary files
removed on SIGTERM and, after SIGKILL, by the next write; a view's EXR and PNG as one unit."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from disks import fill

from holo_core.io import image as image_files
from holo_core.io.hologram import read_hologram, write_hologram
from holo_core.io.image import (
    TEMP_TAG,
    check_writable,
    remove_stale_temps,
    write_atomic,
    write_exr,
    write_png,
)
from holo_core.io.view import write_view
from holo_core.scene.hologram import Hologram
from holo_core.validate import InputError
from holo_core.view import RenderResult

KILLS = 20

# A writer that rewrites one hologram forever, version i carrying i in its first sample.
WRITER = """
import sys
import numpy as np
from holo_core.io.hologram import write_hologram
from holo_core.scene.hologram import Hologram
noise = np.random.default_rng(1).random((2, 512, 512), np.float32)
print("ready", flush=True)
for i in range(1, 10**6):
    noise[0, 0, 0] = i
    write_hologram(sys.argv[1], Hologram(intensity=noise, wavelengths=(633e-9, 532e-9),
                                         pitch=8e-6))
"""


def temps(folder):
    return sorted(p.name for p in folder.iterdir() if TEMP_TAG in p.name)


def version(path):
    return int(read_hologram(path).intensity[0, 0, 0])


def test_permissions_are_kept_and_new_files_follow_the_umask(tmp_path):
    path = tmp_path / "f.bin"
    old = os.umask(0o027)
    try:
        write_atomic(path, b"new")
        assert path.stat().st_mode & 0o777 == 0o640
    finally:
        os.umask(old)
    for mode in (0o644, 0o600, 0o664):
        path.chmod(mode)
        write_atomic(path, b"again")
        assert path.stat().st_mode & 0o777 == mode and path.read_bytes() == b"again"


def _write_hologram(path):
    write_hologram(
        path, Hologram(intensity=np.ones((1, 4, 4), np.float32), wavelengths=(633e-9,), pitch=8e-6)
    )


def _write_view(path):
    write_view(
        RenderResult(
            rgb=np.full((4, 4, 3), 0.5, np.float32), alpha=np.ones((4, 4)), depth=np.ones((4, 4))
        ),
        path,
    )


WRITERS = {
    "write_atomic": lambda p: write_atomic(p, b"new"),
    "write_png": lambda p: write_png(p, np.full((4, 4), 0.5)),
    "write_hologram": _write_hologram,
    "write_view": _write_view,
}


@pytest.mark.parametrize("writer", WRITERS)
@pytest.mark.parametrize("dangling", [False, True])
def test_a_symbolic_link_is_replaced_never_written_through(tmp_path, writer, dangling):
    """A link planted at the output name (a shared folder) must not redirect the write: the
    link is replaced by the new file, and the file it pointed to keeps its bytes and mode."""
    (tmp_path / "victim").mkdir()
    outputs = [tmp_path / ("v.png" if writer == "write_png" else "v.exr")]
    if writer == "write_view":
        outputs.append(outputs[0].with_suffix(".png"))  # the preview is a link too
    victims = []
    for i, out in enumerate(outputs):
        victim = tmp_path / "victim" / f"secret{i}"
        if not dangling:
            victim.write_bytes(b"do not touch")
            victim.chmod(0o600)
        out.symlink_to(victim)
        victims.append(victim)
    WRITERS[writer](outputs[0])
    for out, victim in zip(outputs, victims):
        assert not out.is_symlink() and out.is_file(), f"{out} is still a link"
        if dangling:
            assert not victim.exists(), "the write created the link's target"
        else:
            assert victim.read_bytes() == b"do not touch"
            assert victim.stat().st_mode & 0o777 == 0o600
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["victim"] + [o.name for o in outputs]
    ), "files other than those asked for"


def test_an_output_is_checked_before_the_work_and_nothing_is_created(tmp_path):
    (tmp_path / "file").write_text("a file")
    (tmp_path / "sub.exr").mkdir()
    for path, problem in [
        (tmp_path / "file" / "h.exr", "not a folder"),
        (tmp_path / "sub.exr", "is a folder"),
        ("/sys/holo_test.exr", "not writable"),  # read-only even for root
        (tmp_path / "new" / "r.png", r"as OpenEXR; name it \*\.exr"),
    ]:
        with pytest.raises(InputError, match=problem):
            check_writable(path, ".exr")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "sub.exr"]
    assert (
        check_writable(tmp_path / "new" / "deeper" / "h.exr", ".exr")
        == tmp_path.resolve() / "new" / "deeper" / "h.exr"
    )
    assert not (tmp_path / "new").exists() and temps(tmp_path) == []


def test_sigterm_during_a_write_removes_the_temporary_file(tmp_path):
    """A SIGTERM that lands while a write is open ends the writer with status 143 and no
    temporary file left; one that lands between two writes ends it as SIGTERM does. The
    signal is sent once a write is seen open, again until one lands inside a write (a loaded
    machine may let the write finish first)."""
    target = tmp_path / "h.exr"
    write_hologram(
        target,
        Hologram(intensity=np.zeros((1, 4, 4), np.float32), wavelengths=(633e-9,), pitch=8e-6),
    )
    statuses = []
    while len(statuses) < 10 and 128 + signal.SIGTERM not in statuses:
        with subprocess.Popen(
            [sys.executable, "-c", WRITER, str(target)], stdout=subprocess.PIPE, text=True
        ) as proc:
            assert proc.stdout.readline().strip() == "ready"
            deadline = time.time() + 30
            while not temps(tmp_path) and time.time() < deadline:  # a write is open
                time.sleep(0.005)
            proc.send_signal(signal.SIGTERM)
            statuses.append(proc.wait(timeout=30))
        assert statuses[-1] in (128 + signal.SIGTERM, -signal.SIGTERM), statuses
        assert temps(tmp_path) == [], f"a temporary file left after status {statuses[-1]}"
        assert read_hologram(target).intensity.shape[0] in (1, 2)
    assert 128 + signal.SIGTERM in statuses, f"no SIGTERM landed inside a write: {statuses}"


def test_kill_9_leaves_the_old_or_the_new_file_and_the_next_write_cleans_up(tmp_path):
    target = tmp_path / "h.exr"
    write_hologram(
        target,
        Hologram(intensity=np.zeros((1, 4, 4), np.float32), wavelengths=(633e-9,), pitch=8e-6),
    )
    rng = np.random.default_rng(7)
    seen, mid_write = [], 0
    for n in range(KILLS + 20):  # past KILLS only until a kill lands mid-write, for the cleanup
        if n >= KILLS and temps(tmp_path):
            break
        with subprocess.Popen(
            [sys.executable, "-c", WRITER, str(target)], stdout=subprocess.PIPE, text=True
        ) as proc:
            assert proc.stdout.readline().strip() == "ready"
            time.sleep(rng.uniform(0.0, 0.6))
            proc.kill()
        mid_write += bool(temps(tmp_path))
        seen.append(version(target))  # a complete hologram: version 0 or one fully written
    print(f"{len(seen)} kills: {mid_write} during a write, versions seen {seen}")
    assert mid_write >= KILLS // 4, "the kills never landed during a write: the test is idle"
    assert temps(tmp_path), "temporary files of the killed writers"
    write_atomic(tmp_path / "other.bin", b"next run")
    assert temps(tmp_path) == []


def test_only_dead_writers_temporary_files_are_removed(tmp_path):
    host = image_files._HOST
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True
    ).stdout.strip()
    stale = tmp_path / f".h{TEMP_TAG}{host}.{dead}.0.exr"
    live = tmp_path / f".h{TEMP_TAG}{host}.{os.getppid()}.0.exr"
    other = tmp_path / f".h{TEMP_TAG}otherhost.{dead}.0.exr"
    for p in (stale, live, other):
        p.write_bytes(b"x")
    assert remove_stale_temps(tmp_path) == [stale]
    assert live.exists() and other.exists()


def test_a_view_is_written_as_one_unit(tmp_path, monkeypatch):
    def view(value):
        return RenderResult(
            rgb=np.full((4, 4, 3), value, np.float32), alpha=np.ones((4, 4)), depth=np.ones((4, 4))
        )

    exr, png = write_view(view(0.25), tmp_path / "v.exr")
    before = exr.read_bytes(), png.read_bytes()

    def broken(_image):
        raise RuntimeError("PNG encoder failed")

    monkeypatch.setattr("holo_core.io.image.png_bytes", broken)
    with pytest.raises(RuntimeError):
        write_view(view(0.75), tmp_path / "v.exr")
    assert (exr.read_bytes(), png.read_bytes()) == before and temps(tmp_path) == []


def test_a_views_png_preview_shows_what_its_exr_shows_over_black(tmp_path):
    """The PNG preview is the EXR's premultiplied colour (emission over black) through the
    sRGB curve: where the view is clear (alpha 0) it is black whatever colour the pixel
    holds, where opaque the colour, where half covered half of it (linear)."""
    from PIL import Image

    rgb = np.empty((2, 3, 3), np.float32)
    rgb[...] = (0.8, 0.4, 0.2)
    alpha = np.array([[0, 0.5, 1], [1, 0, 0.5]], np.float32)
    (png,) = write_view(
        RenderResult(rgb=rgb, alpha=alpha, depth=np.ones((2, 3))), tmp_path / "v.exr"
    )[1:]
    shown = np.asarray(Image.open(png), np.float64)[..., :3] / 255
    expect = image_files.srgb(rgb * alpha[..., None])
    assert np.abs(shown - expect).max() <= 0.5 / 255 + 1e-9, (shown, expect)
    assert not shown[alpha == 0].any()


def test_a_disk_that_fills_mid_write_names_the_file_asked_for_not_the_temporary(small_disk):
    """A full disk met inside a write was OpenEXR's or the system's error naming the hidden
    temporary file; it is the project's error naming the file asked for, and nothing of the
    write is left."""
    fill(small_disk)
    rng = np.random.default_rng(0)
    for path, write in (
        (small_disk / "v.exr", lambda p: write_exr(p, {"R": rng.random((256, 256), np.float32)})),
        (small_disk / "v.png", lambda p: write_png(p, rng.random((256, 256, 3)))),
    ):
        with pytest.raises(
            InputError,
            match=rf"^{path}: cannot be written \(.*No space left "
            rf"on device\) \(the disk is full",
        ) as e:
            write(path)
        assert "holo-tmp" not in str(e.value), str(e.value)
    assert sorted(p.name for p in small_disk.iterdir()) == ["filler"]
