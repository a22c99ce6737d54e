"""Pictures handed from the worker process to Blender through shared memory, never files.

A :class:`SharedView` is one ``multiprocessing.shared_memory`` segment of two picture slots
and a small header. The process that shows the pictures creates it
(:meth:`SharedView.create`: its owner, which unlinks it on :meth:`~SharedView.close`); the
worker attaches by name (:meth:`SharedView.attach`) and writes each view into the slot not
being shown, then publishes it. Each slot is guarded by a sequence lock (its counter is odd
while the slot is written), so a reader copies a picture only when the counter is the same,
and even, before and after its copy: a half-written picture, or one the writer died
writing, is never read (the other slot's complete picture is read instead).

A picture is ``channels`` float32 planes interleaved per pixel, row 0 at the top as the core
renders it: R, G, B, A (straight, not premultiplied), then the depth [m] when there are 5.
"""

from __future__ import annotations

import contextlib
import math
import os
import secrets
import sys
import time
from dataclasses import dataclass
from multiprocessing import shared_memory

import numpy as np

from ..validate import InputError, integer

MAGIC = 0x484F4C4F56494557  # "HOLOVIEW": a segment that is not a SharedView is refused
HEADER_WORDS = 32  # int64 words of the header
SLOTS = 2
SLOT_WORDS = 8  # each slot's words in the header, from SLOT_BASE
SLOT_BASE = 8
TRIES = 8  # a reader's attempts before it gives up on this look
# the header's words: 0 magic, 1 capacity [bytes a slot], 2 the published slot (-1: none),
# 3 pictures published so far; a slot's: 0 its sequence lock, 1 its picture's number, 2 the
# request it answers, 3 width, 4 height, 5 channels, 6 coarse, 7 seconds (float64 bits)
SEQ, NUMBER, REQUEST, WIDTH, HEIGHT, CHANNELS, COARSE, SECONDS = range(SLOT_WORDS)
_created: set = set()  # the segments this process created (and its resource tracker holds)


@dataclass(frozen=True, slots=True, kw_only=True)
class SharedPicture:
    """A picture read out of a :class:`SharedView` (a copy: the segment may be rewritten).

    Attributes
    ----------
    number : int
        Its place among the segment's pictures (1, 2, ...; later pictures have larger ones).
    request : int
        The request it answers.
    rgba : (H, W, 4) float32 array
        Straight radiance and opacity, row 0 at the top.
    depth : (H, W) float32 array or None
        Planar depth [m] (None where the writer sent none).
    coarse : bool
        A coarse view (a quick one while the camera moves).
    seconds : float
        How long the view took to make [s].
    """

    number: int
    request: int
    rgba: np.ndarray
    depth: np.ndarray | None
    coarse: bool
    seconds: float


def session_name() -> str:
    """A segment name unique to this process and call: ``holo-<pid>-<8 hex digits>``
    (31 characters at most, macOS's limit)."""
    return f"holo-{os.getpid()}-{secrets.token_hex(4)}"


def slot_bytes(width: int, height: int, channels: int = 5) -> int:
    """The bytes a slot needs for a (``width``, ``height``) [px] picture of ``channels``."""
    return int(width) * int(height) * int(channels) * 4


class SharedView:
    """A shared-memory segment of two picture slots (see the module's description).

    Use :meth:`create` (the reader's side, which owns the segment) or :meth:`attach` (the
    writer's side); :meth:`close` unmaps it, and the owner's also unlinks it.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.io.shared_view import SharedView, slot_bytes
    >>> shown = SharedView.create(slot_bytes(4, 2))
    >>> writer = SharedView.attach(shown.name)
    >>> writer.write(np.ones((2, 4, 4), np.float32), depth=np.full((2, 4), 3.0), request=7)
    1
    >>> picture = shown.read()
    >>> picture.request, picture.rgba.shape, float(picture.depth[0, 0])
    (7, (2, 4, 4), 3.0)
    >>> writer.close(); shown.close()
    """

    def __init__(self, memory: shared_memory.SharedMemory, *, owner: bool):
        self._memory, self.owner = memory, owner
        self.name = memory.name
        self._header = np.ndarray((HEADER_WORDS,), np.int64, memory.buf)
        self._seconds = np.ndarray((HEADER_WORDS,), np.float64, memory.buf)  # the same words
        self.capacity = int(self._header[1])
        self._data = [
            np.ndarray(
                (self.capacity // 4,),
                np.float32,
                memory.buf,
                offset=HEADER_WORDS * 8 + s * self.capacity,
            )
            for s in range(SLOTS)
        ]

    @classmethod
    def create(cls, capacity: int, *, name: str | None = None) -> SharedView:
        """A new segment whose slots hold ``capacity`` bytes each (:func:`slot_bytes`),
        named ``name`` or :func:`session_name`; this process owns it (unlinks it on
        :meth:`close`)."""
        capacity = validate_capacity(capacity)
        memory = shared_memory.SharedMemory(
            name=name or session_name(), create=True, size=HEADER_WORDS * 8 + SLOTS * capacity
        )
        _created.add(memory.name)
        header = np.ndarray((HEADER_WORDS,), np.int64, memory.buf)
        header[:] = 0
        header[1], header[2], header[0] = capacity, -1, MAGIC
        del header
        return cls(memory, owner=True)

    @classmethod
    def attach(cls, name: str) -> SharedView:
        """The segment ``name`` another process created (:class:`InputError` naming it when
        there is none, or it is not a SharedView). This process never unlinks it: it is
        left out of this process's resource tracker, which would unlink it at exit."""
        try:
            memory = _untracked(name)
        except (FileNotFoundError, ValueError) as e:
            raise InputError(f"shared view {name!r}: no such segment ({e})") from None
        if (
            memory.size < HEADER_WORDS * 8
            or int(np.ndarray((1,), np.int64, memory.buf)[0]) != MAGIC
        ):
            memory.close()
            raise InputError(f"shared view {name!r}: not a segment of pictures")
        return cls(memory, owner=False)

    def slot(self, s: int) -> np.ndarray:
        """Slot ``s``'s header words (a view into the segment)."""
        return self._header[SLOT_BASE + s * SLOT_WORDS : SLOT_BASE + (s + 1) * SLOT_WORDS]

    # -- the writer's side ------------------------------------------------------------------

    @contextlib.contextmanager
    def writing(
        self,
        width: int,
        height: int,
        channels: int,
        *,
        request: int,
        coarse: bool = False,
        started: float | None = None,
    ):
        """A slot's (``height``, ``width``, ``channels``) float32 array to fill, published
        when the block ends without an error; a block that raises (or a writer that dies
        in it) leaves the slot's lock odd and the published picture as it was. The slot is
        the one not published, so a reader of the published one is not disturbed. The
        picture's seconds are those since ``started`` (a ``time.perf_counter()`` of this
        process: when its view began), else the block's own."""
        channels = validate_channels(channels)
        need = slot_bytes(width, height, channels)
        if need > self.capacity:
            raise InputError(
                f"picture of {width} x {height} px x {channels} channels needs "
                f"{need} bytes; the shared view {self.name!r} holds {self.capacity}"
                f" a slot"
            )
        published = int(self._header[2])
        s = 0 if published < 0 else 1 - published
        words = self.slot(s)
        words[SEQ] += 2 if words[SEQ] & 1 else 1  # odd: being written (a new odd value
        # where a write before was left unfinished, so a reader that saw it sees a change)
        words[REQUEST], words[WIDTH], words[HEIGHT], words[CHANNELS], words[COARSE] = (
            request,
            width,
            height,
            channels,
            bool(coarse),
        )
        start = float(time.perf_counter() if started is None else started)
        yield self._data[s][: need // 4].reshape(height, width, channels)
        number = int(self._header[3]) + 1
        words[NUMBER] = number
        self._seconds[SLOT_BASE + s * SLOT_WORDS + SECONDS] = time.perf_counter() - start
        words[SEQ] += 1  # even: complete
        self._header[3] = number
        self._header[2] = s

    def write(
        self, rgba, *, depth=None, request: int, coarse: bool = False, seconds: float | None = None
    ) -> int:
        """Write and publish one picture: ``rgba`` (H, W, 4) straight radiance and opacity,
        row 0 at the top, and ``depth`` (H, W) [m] or None; ``seconds`` [s] how long its
        view took (default: the copy's own time). Returns its number. Non-finite values are
        refused (:class:`InputError`): nothing is published."""
        rgba = np.asarray(rgba, np.float32)
        if rgba.ndim != 3 or rgba.shape[2] != 4:
            raise InputError(f"rgba must be (H, W, 4); got shape {rgba.shape}")
        planes = (rgba,) if depth is None else (rgba, np.asarray(depth, np.float32)[..., None])
        if depth is not None and planes[1].shape[:2] != rgba.shape[:2]:
            raise InputError(f"depth must be (H, W) = {rgba.shape[:2]}; got {np.shape(depth)}")
        if not all(np.isfinite(p).all() for p in planes):
            raise InputError("the picture holds NaN or infinite values: nothing is published")
        h, w, _ = rgba.shape
        with self.writing(w, h, 4 if depth is None else 5, request=request, coarse=coarse) as out:
            out[..., :4] = rgba
            if depth is not None:
                out[..., 4] = planes[1][..., 0]
        s = int(self._header[2])
        if seconds is not None:
            self._seconds[SLOT_BASE + s * SLOT_WORDS + SECONDS] = float(seconds)
        return int(self.slot(s)[NUMBER])

    # -- the reader's side ------------------------------------------------------------------

    @property
    def published(self) -> int:
        """How many pictures were published so far (0: none)."""
        return int(self._header[3])

    def read(self, *, after: int = 0) -> SharedPicture | None:
        """A copy of the newest complete picture whose number is above ``after``, or None
        (none yet, none newer, or the writer rewrote the slot through every try: the next
        look finds it). Never blocks."""
        for _ in range(TRIES):
            s = int(self._header[2])
            if s < 0:
                return None
            words = self.slot(s)
            lock = int(words[SEQ])
            if lock & 1:
                continue  # the writer came round to this slot again: it is the other's turn
            meta = words.copy()
            if meta[NUMBER] <= after:
                return None
            w, h, c = int(meta[WIDTH]), int(meta[HEIGHT]), int(meta[CHANNELS])
            if slot_bytes(w, h, c) > self.capacity or c not in (4, 5):
                continue
            pixels = self._data[s][: w * h * c].reshape(h, w, c).copy()
            seconds = float(self._seconds[SLOT_BASE + s * SLOT_WORDS + SECONDS])
            if int(words[SEQ]) != lock:
                continue  # rewritten while it was copied
            return SharedPicture(
                number=int(meta[NUMBER]),
                request=int(meta[REQUEST]),
                rgba=np.ascontiguousarray(pixels[..., :4]),
                depth=pixels[..., 4].copy() if c == 5 else None,
                coarse=bool(meta[COARSE]),
                seconds=seconds,
            )
        return None

    def close(self) -> None:
        """Unmap the segment; the owner also unlinks it (its name is gone for every process;
        one still attached keeps its mapping until it closes)."""
        if self._memory is None:
            return
        self._header = self._seconds = self._data = None  # no view may outlive the mapping
        memory, self._memory = self._memory, None
        memory.close()
        if self.owner:
            with contextlib.suppress(FileNotFoundError):
                memory.unlink()
            _created.discard(self.name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def validate_capacity(capacity) -> int:
    """A slot's capacity [bytes]: an integer from 16 to 2**34 (a 16k x 16k x 5 picture)."""
    value = integer("capacity", capacity, 16, 2**34)
    return int(math.ceil(value / 8) * 8)  # each slot starts on a word


def validate_channels(channels) -> int:
    """A picture's planes: 4 (R, G, B, A) or 5 (and the depth [m])."""
    if channels not in (4, 5):
        raise InputError(f"channels must be 4 (RGBA) or 5 (RGBA and depth); got {channels!r}")
    return int(channels)


def _untracked(name: str) -> shared_memory.SharedMemory:
    """The segment ``name`` attached without this process's resource tracker, which would
    unlink it when this process ends (Python before 3.13 registers every attached segment)."""
    if sys.version_info >= (3, 13):
        return shared_memory.SharedMemory(name=name, track=False)
    memory = shared_memory.SharedMemory(name=name)
    if os.name == "posix" and name not in _created:  # this process's own stays registered
        from multiprocessing import resource_tracker

        resource_tracker.unregister(memory._name, "shared_memory")
    return memory
