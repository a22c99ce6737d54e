"""FFTW on host arrays, for CPU devices: in-place 2-D transforms and the padded spectral
convolution, each a few passes over fixed blocks of columns and rows.

Blocks. A pass transforms a block of columns (about ``BLOCK_BYTES`` of them: the block stays in
the core's cache while FFTW walks its strided columns) or of rows at a time, with the
element-wise work of that pass done on the block while it is in cache: the zeros of the
padding written only where the field is not, the transfer function's multiply between the
forward and the inverse row transforms, the crop written straight into the result. The blocks
depend on the grid alone; threads (``HOLO_FFT_THREADS``, default the CPUs this process may
use) take them in any order, and each block is transformed by the same one-thread plan, so
the result is bit-identical whatever the thread count or the machine's load.

Plans. A problem (a block's length, count, strides and alignment) is measured once per machine
(FFTW_MEASURE) and kept as FFTW wisdom in the user's cache directory, under a file lock; every
later plan of it, in this process or another, comes from that wisdom (FFTW_WISDOM_ONLY) and is
never timed again. The first process that needs a problem measures it before it transforms
anything, so it computes with the very plan every later process reads: results are
bit-identical across processes, the first run included, as long as the wisdom file is kept
(deleting it measures again, and the last bits may then differ). ``HOLO_FFTW_PLANNER=estimate``
takes FFTW_ESTIMATE plans instead: no wisdom and no timing, the same bits on every machine of
one kind, several times slower on the strided column passes.

Pruning. Zero padding leaves columns of zeros: a forward transform told where its input is
non-zero (``nonzero``) transforms only those columns first and then every row, and an inverse
one told which columns will be read (``read``) transforms every row first and then only those
columns. The padded convolution does both: 3/4 of the work of two full 2-D transforms.
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import os
import pickle
import platform
import threading
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ..validate import InputError

log = logging.getLogger(__name__)

BLOCK_BYTES = 1 << 18  # a block of columns or rows: 256 KiB, within any current core's L2
ALIGN = 8  # column blocks start on multiples of 8 samples (64 bytes)
WORK_GRIDS = 2  # padded work arrays kept, the most recently used
PARALLEL_SAMPLES = 1 << 19  # grids of fewer samples are transformed on the caller's thread
FORWARD, BACKWARD = "FFTW_FORWARD", "FFTW_BACKWARD"


def thread_count() -> int:
    """``HOLO_FFT_THREADS``, else the CPUs this process may run on."""
    value = os.environ.get("HOLO_FFT_THREADS", "").strip()
    if value:
        if not value.isdigit() or not 1 <= int(value) <= 256:
            raise InputError(f"HOLO_FFT_THREADS={value!r}; allowed: an integer in [1, 256]")
        return int(value)
    return (
        len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    )


def spans(ranges, n: int, align: int = 1) -> list[tuple[int, int]]:
    """``ranges`` ((start, stop), …) clipped to [0, n), widened to multiples of ``align`` and
    merged where they touch; None: the whole axis."""
    if ranges is None:
        return [(0, n)]
    out = []
    for a, b in sorted(
        (max(0, a // align * align), min(n, -(-b // align) * align)) for a, b in ranges
    ):
        if a >= b:
            continue
        if out and a <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], b))
        else:
            out.append((a, b))
    return out


def blocks(ranges, size: int) -> list[tuple[int, int]]:
    """The ranges cut into consecutive blocks of at most ``size``."""
    return [(a, min(a + size, hi)) for lo, hi in ranges for a in range(lo, hi, size)]


def gaps(ranges, n: int) -> list[tuple[int, int]]:
    """The parts of [0, n) outside the sorted, disjoint ``ranges``."""
    out, at = [], 0
    for a, b in ranges:
        if a > at:
            out.append((at, a))
        at = b
    return out + ([(at, n)] if at < n else [])


class Wisdom:
    """FFTW plans of single-precision problems: measured once per machine and kept read-only
    (module docstring), or estimated (``planner='estimate'``)."""

    def __init__(self, planner: str):
        import pyfftw

        self.fftw = pyfftw
        planner = planner.strip().upper()
        if planner not in ("ESTIMATE", "MEASURE", "PATIENT"):
            raise InputError(
                f"HOLO_FFTW_PLANNER={planner.lower()!r}; allowed: 'measure' "
                f"(default), 'patient' or 'estimate'"
            )
        self.rigour = f"FFTW_{planner}"
        self.known = set()  # problems whose plan this process's wisdom holds
        self.lock = threading.Lock()  # FFTW's planner is not thread-safe
        if self.rigour != "FFTW_ESTIMATE":
            self.load()

    @property
    def path(self) -> str:
        from platformdirs import user_cache_dir

        suffix = "" if self.rigour == "FFTW_MEASURE" else "-patient"
        name = f"fftw-wisdom-{platform.node()}{suffix}.pickle"
        return os.path.join(user_cache_dir("holo"), name)

    def load(self) -> None:
        try:
            with open(self.path, "rb") as f:
                self.fftw.import_wisdom(pickle.load(f))
        except (OSError, pickle.UnpicklingError, EOFError, TypeError, ValueError):
            pass  # none yet: problems are measured as they come

    def plan(self, view, axis: int, direction: str, unaligned: bool):
        """A one-thread plan of the 1-D transforms along ``axis`` of ``view``, in place."""
        flags = (("FFTW_UNALIGNED",) if unaligned else ()) + (self.rigour,)
        with self.lock:
            if self.rigour == "FFTW_ESTIMATE":
                return self.fftw.FFTW(
                    view, view, axes=(axis,), direction=direction, flags=flags, threads=1
                )
            key = (view.shape, view.strides, axis, direction, unaligned)
            if key not in self.known:
                self._measure_once(view, axis, direction, flags)
                self.known.add(key)
            try:
                return self.fftw.FFTW(
                    view,
                    view,
                    axes=(axis,),
                    direction=direction,
                    flags=flags + ("FFTW_WISDOM_ONLY",),
                    threads=1,
                )
            except RuntimeError:  # the wisdom did not carry over from the scratch array
                log.warning(
                    "FFTW: no wisdom for %s transforms of %d along axis %d after "
                    "measuring them; estimating instead",
                    view.shape[1 - axis],
                    view.shape[axis],
                    axis,
                )
                return self.fftw.FFTW(
                    view,
                    view,
                    axes=(axis,),
                    direction=direction,
                    flags=flags[:-1] + ("FFTW_ESTIMATE",),
                    threads=1,
                )

    def _measure_once(self, view, axis, direction, flags) -> None:
        """Measure the problem of ``view`` unless some process has: on a scratch array of the
        same layout (measuring overwrites), under the wisdom file's lock."""
        scratch = self._like(view)
        if self._known(scratch, axis, direction, flags):
            return
        with self._file_lock():
            self.load()  # another process may have measured it meanwhile
            if self._known(scratch, axis, direction, flags):
                return
            log.info(
                "FFTW: measuring a plan for %s transforms of %d along axis %d (kept for "
                "later processes on this machine)",
                view.shape[1 - axis],
                view.shape[axis],
                axis,
            )
            self.fftw.FFTW(
                scratch, scratch, axes=(axis,), direction=direction, flags=flags, threads=1
            )
            self._save()

    def _known(self, scratch, axis, direction, flags) -> bool:
        try:
            self.fftw.FFTW(
                scratch,
                scratch,
                axes=(axis,),
                direction=direction,
                flags=flags + ("FFTW_WISDOM_ONLY",),
                threads=1,
            )
            return True
        except RuntimeError:
            return False

    def _like(self, view) -> np.ndarray:
        """A view of fresh memory with ``view``'s shape, strides and offset from FFTW's
        alignment (which its plans, and their wisdom, depend on)."""
        rows, cols = view.shape
        pitch = view.strides[0] // view.itemsize
        shift = view.ctypes.data % self.fftw.simd_alignment // view.itemsize
        flat = self.fftw.empty_aligned(rows * pitch + shift + cols, np.complex64)
        return flat[shift : shift + rows * pitch].reshape(rows, pitch)[:, :cols]

    @contextlib.contextmanager
    def _file_lock(self):
        """The wisdom file's lock, where the system has advisory locks and the cache can be
        written (else none: the atomic replace still keeps the file whole)."""
        try:
            import fcntl

            os.makedirs(os.path.dirname(self.path), exist_ok=True)
            f = open(self.path + ".lock", "a")
        except (ImportError, OSError):
            yield
            return
        with f:
            fcntl.flock(f, fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(f, fcntl.LOCK_UN)

    def _save(self) -> None:
        tmp = f"{self.path}.{os.getpid()}.tmp"
        try:
            with open(tmp, "wb") as f:
                pickle.dump(self.fftw.export_wisdom(), f)
            os.replace(tmp, self.path)
        except OSError as e:  # a read-only cache: the plan serves this process only
            log.warning("FFTW wisdom not saved (%s): later processes measure again", e)


class HostFFT:
    """The passes (module docstring) on a pool of threads, their plans from :class:`Wisdom`."""

    def __init__(self, threads: int | None = None, planner: str | None = None):
        self.wisdom = Wisdom(planner or os.environ.get("HOLO_FFTW_PLANNER", "measure"))
        self.threads = threads or thread_count()
        # the caller takes blocks too: one fewer thread to wake on a loaded machine
        self.pool = ThreadPoolExecutor(self.threads - 1) if self.threads > 1 else None
        self.plans = {}  # by problem: a plan object per thread (update_arrays is per object)
        self.local = threading.local()
        self.slots = itertools.count()
        self.making = threading.Lock()
        self.work = OrderedDict()  # padded grids of the convolution, by shape

    # --- the passes -----------------------------------------------------------------------

    def run(self, tasks, job, samples: int) -> None:
        """``job(task)`` for every task, the threads taking the next one as they come free; a
        grid of fewer than ``PARALLEL_SAMPLES`` stays on the caller's thread (waking others
        costs more there, on a loaded machine most of all)."""
        tasks = list(tasks)
        if self.pool is None or len(tasks) < 2 or samples < PARALLEL_SAMPLES:
            for t in tasks:
                job(t)
            return
        counter = itertools.count()

        def worker():
            for i in iter(lambda: next(counter), None):
                if i >= len(tasks):
                    return
                job(tasks[i])

        helpers = [self.pool.submit(worker) for _ in range(min(self.threads, len(tasks)) - 1)]
        worker()
        for f in helpers:
            f.result()

    def execute(self, view, axis: int, direction: str) -> None:
        """The 1-D transforms along ``axis`` of the block ``view``, in place."""
        simd = self.wisdom.fftw.simd_alignment
        unaligned = view.ctypes.data % simd != 0 or view.strides[0] % simd != 0
        key = (view.shape, view.strides, axis, direction, unaligned)
        copies = self.plans.get(key)
        if copies is None:  # one per thread that may run a block, all made now from the
            with self.making:  # same wisdom: whatever FFTW learns later changes none of them
                copies = self.plans.get(key) or [
                    self.wisdom.plan(view, axis, direction, unaligned) for _ in range(self.threads)
                ]
                self.plans[key] = copies
        slot = self._slot()
        if slot >= len(copies):  # a caller thread beyond the first (a runtime is per thread)
            with self.making:
                copies.extend(
                    self.wisdom.plan(view, axis, direction, unaligned)
                    for _ in range(slot + 1 - len(copies))
                )
        plan = copies[slot]
        plan.update_arrays(view, view)
        plan.execute()

    def _slot(self) -> int:
        """This thread's own index into each problem's plan copies (the caller's and the
        pool's threads)."""
        slot = getattr(self.local, "slot", None)
        if slot is None:
            with self.making:
                slot = self.local.slot = next(self.slots)
        return slot

    @staticmethod
    def column_width(rows: int) -> int:
        return max(ALIGN, BLOCK_BYTES // (8 * rows) // ALIGN * ALIGN)

    @staticmethod
    def row_height(cols: int) -> int:
        return max(1, BLOCK_BYTES // (8 * cols))

    def columns(self, a, direction, cols, before=None, after=None) -> None:
        """Transform the columns ``cols`` (sorted, disjoint, aligned spans) of ``a`` in place,
        block by block; ``before(c0, c1)`` and ``after(c0, c1)`` run on each block around
        its transform."""

        def job(span):
            c0, c1 = span
            if before is not None:
                before(c0, c1)
            self.execute(a[:, c0:c1], 0, direction)
            if after is not None:
                after(c0, c1)

        self.run(blocks(cols, self.column_width(a.shape[0])), job, a.size)

    def rows(self, a, directions, before=None, between=None) -> None:
        """Transform every row of ``a`` in place by each of ``directions`` in turn, block by
        block; ``before(r0, r1)`` runs before the first, ``between(r0, r1)`` after it."""

        def job(span):
            r0, r1 = span
            if before is not None:
                before(r0, r1)
            for i, d in enumerate(directions):
                if i and between is not None:
                    between(r0, r1)
                self.execute(a[r0:r1], 1, d)

        self.run(blocks([(0, a.shape[0])], self.row_height(a.shape[1])), job, a.size)

    # --- 2-D transforms ---------------------------------------------------------------------

    def transform(self, a: np.ndarray, direction: str, nonzero=None, read=None) -> None:
        """The unnormalised 2-D DFT of ``a`` (H, W, complex64) in place.

        nonzero : (row ranges, column ranges) outside which the input counts as zero, whatever
            ``a`` holds there (the passes write those zeros where they need them).
        read : column ranges of the result that will be read; the others are left unfinished.
        """
        h, w = a.shape
        if nonzero is not None:
            rows, exact = spans(nonzero[0], h), spans(nonzero[1], w)
            cols = spans(exact, w, ALIGN)
            row_gaps, col_gaps, widened = gaps(rows, h), gaps(cols, w), gaps(exact, w)

            def zero_rows(c0, c1):  # and the columns the alignment added to the block
                for r0, r1 in row_gaps:
                    a[r0:r1, c0:c1] = 0
                for g0, g1 in widened:
                    if g0 < c1 and g1 > c0:
                        a[:, max(g0, c0) : min(g1, c1)] = 0

            def zero_cols(r0, r1):
                for c0, c1 in col_gaps:
                    a[r0:r1, c0:c1] = 0

            self.columns(a, direction, cols, before=zero_rows)
            self.rows(a, (direction,), before=zero_cols)
        elif read is not None:
            self.rows(a, (direction,))
            self.columns(a, direction, spans(read, w, ALIGN))
        else:
            self.columns(a, direction, [(0, w)])
            self.rows(a, (direction,))

    # --- the padded convolution -----------------------------------------------------------

    def convolve(
        self, field: np.ndarray, transfer: np.ndarray, out: np.ndarray, padded=None
    ) -> complex:
        """``out`` (h, w) ← the centre of IFFT(FFT(``field`` zero-padded to (H, W)) · T):
        ``transfer`` is T (H, W) in FFT order, with the inverse FFT's 1/(H·W), or, given the
        grid's shape ``padded``, T's first quadrant (H//2 + 1, W//2 + 1) of a T even in both
        frequencies (read mirrored). Returns the padded field's DC term (its sum: not finite
        where the field is not)."""
        (h, w), (H, W) = field.shape, padded or transfer.shape
        r0, c0 = (H - h) // 2, (W - w) // 2
        x = self._work((H, W))
        cols = spans([(c0, c0 + w)], W, ALIGN)
        col_gaps = gaps(cols, W)
        dc = []
        half = W // 2 + 1
        mirrored = np.abs(np.fft.fftfreq(H, 1 / H)).astype(np.intp)  # |signed index| per row

        def pad(a, b):  # the field's columns in [a, b) into the block, zeros around them
            lo, hi = max(a, c0), min(b, c0 + w)
            if lo >= hi:
                x[:, a:b] = 0
                return
            x[:r0, a:b] = 0
            x[r0 + h :, a:b] = 0
            if lo > a:
                x[r0 : r0 + h, a:lo] = 0
            if hi < b:
                x[r0 : r0 + h, hi:b] = 0
            x[r0 : r0 + h, lo:hi] = field[:, lo - c0 : hi - c0]

        def zero_margins(a, b):
            for g0, g1 in col_gaps:
                x[a:b, g0:g1] = 0

        def multiply(a, b):
            if a == 0:
                dc.append(complex(x[0, 0]))
            if padded is None:
                np.multiply(x[a:b], transfer[a:b], out=x[a:b])
                return
            rows = transfer[mirrored[a:b]]
            np.multiply(x[a:b, :half], rows, out=x[a:b, :half])
            np.multiply(x[a:b, half:], rows[:, (W - 1) // 2 : 0 : -1], out=x[a:b, half:])

        def crop(a, b):
            lo, hi = max(a, c0), min(b, c0 + w)
            out[:, lo - c0 : hi - c0] = x[r0 : r0 + h, lo:hi]

        self.columns(x, FORWARD, cols, before=pad)
        self.rows(x, (FORWARD, BACKWARD), before=zero_margins, between=multiply)
        self.columns(x, BACKWARD, cols, after=crop)
        return dc[0]

    def _work(self, shape) -> np.ndarray:
        """The (H, W) work grid of a convolution: rows ``ALIGN``-aligned and a pitch off the
        powers of two (a power-of-two row pitch maps a column's samples onto few cache sets)."""
        if shape in self.work:
            self.work.move_to_end(shape)
            return self.work[shape]
        h, w = shape
        pitch = -(-w // ALIGN) * ALIGN + 2 * ALIGN
        self.work[shape] = self.wisdom.fftw.empty_aligned((h, pitch), np.complex64)[:, :w]
        while len(self.work) > WORK_GRIDS:
            self.work.popitem(last=False)
        return self.work[shape]
