"""How long a job takes on this machine, before it runs: each stage's cost is a rate of this
machine times its work, plus the set-up a worker process pays once and the set-up a machine
pays the first time (a fresh cache). Pure arithmetic and small files: it imports no OpenCL
or FFT driver, so Blender's process and the planner call it.

- Work, each stage a fixed cost (``*_fixed``: its launches, its buffers) and a rate. A
  plate's recording: its emitters found (``emitter_seconds`` each, and TRIANGLE_SECONDS a
  triangle they are found among) and the zone sum's pairs (emitter, sample, and each
  sample's own: :meth:`holo_core.plate.plan.PlatePlan.pairs`) at ``pairs_per_second``; its
  files written at ``write_bytes_per_second``; a view: the plan's view seconds
  (:func:`holo_core.plate.plan.plan_view`, its window samples and fine pixels at the
  development machine's rates) times ``view_factor``. A camera pass with Speckle: Exact (one
  incoherent pass): its fine pixels (W·H·s²) at ``exact_pixel_seconds``; with Looks: its
  fine pixels once (``camera_pixel_seconds``) and for each look (``camera_look_seconds``: a
  look's pupil fields and transforms are the grid's, whatever the emitters; the
  calibration's two sizes agree within 10 %). The renderer's radiance (Lighting: Scene):
  Cycles' start and its pixels. Every job: ``job_seconds`` (handing it over, the pass
  written).
- A worker process's set-up (``process_plate_seconds``, ``process_camera_seconds``): Python,
  the core, the OpenCL context, the programs read from the kernel cache, the FFT plans read
  from their wisdom. Paid by every new worker: a render's first frame, each frame of a farm;
  a render's later frames share the worker that made the first.
- The first time on this machine (``first_plate_seconds``, ``first_camera_seconds``): the
  programs compiled and the FFT plans measured, where the kernel cache is cold; a camera pass's FFT plans counted apart, from
  the lengths it transforms (:func:`fft_plans`: FFTW's measuring of a length takes from
  0.01 s to 0.8 s by the ways it factors, more than the rest of a camera pass's first time
  at 640x360). Whether it is warm is known from the cache:
  a worker leaves a stamp (this version, this device, the route) beside the FFT wisdom once a
  job of the route has run, and the stamp counts while the kernel cache it filled is there.
  An image size the FFT wisdom has not seen measures its plans once more on a warm cache
  too: that is not counted (seconds for a new size, once).

- The load. Every part is as on an idle machine, times :func:`slowdown`: 1 + the CPUs other
  work keeps busy as the estimate is made (sampled for a tenth of a second), over the CPUs
  (a job that would use every CPU gets its fair share beside other work); the words give
  the factor where it is 1.2 or more.

The rates are a :class:`Calibration`: measured on this machine by ``python -m holo_core
calibrate`` and kept in the user cache directory (``holo/estimates.json``, beside the FFT
wisdom; the worker's cache folder when the add-on names one), for this version of Holo and
this device; without one, or with one of another version or device, :data:`DEFAULT` (measured
on the development machine, the slow side of its runs under load). A file that cannot be read
is refused with a warning naming it, and :data:`DEFAULT` taken.
"""

from __future__ import annotations

import json
import logging
import math
import os
import time
import warnings
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path

log = logging.getLogger(__name__)

FILE = "estimates.json"
# [B/s] BLAKE2b on one core of the 2-core Zen 4 EPYC (623 MB/s): a set's files are hashed as
# written, beside the next part's sum
DIGEST_BYTES_PER_SECOND = 6.0e8
# [s] a set's part beyond its work: its plan, buffers and kernels' set-up, its files' sync, the
# manifest rewritten (the 90° orbit's 64 small parts)
PART_SECONDS = 1.5
# [s] an emitter of a set's part: its visibility from the part's zone (the set's emitters found once
# a lattice; 0.8 s a 1 m dolly part's 443k emitters, bench/shot.py --set)
VISIBILITY_SECONDS = 2e-6
STAMP = "warm-{kind}-{key}.stamp"
# [s] a triangle the emitters are found among: its crossings with the zone centre's rays,
# whatever emitters it holds (the development machine: the shot's 36,876 triangles 0.37 s)
TRIANGLE_SECONDS = 1e-5
FFT_PROBLEMS = 1.5  # plans measured a transform length (the demo's camera pass: 9 for 6 lengths)
# [s] the present load is sampled over this long: 10 clock ticks a CPU, the estimate a tenth
# of a second later
LOAD_SAMPLE = 0.1
RECENT = 1.0  # [s] a load figure this young serves the next estimate as it is
KINDS = ("plate", "camera")


@dataclass(frozen=True, slots=True, kw_only=True)
class Calibration:
    """A machine's rates and set-up times (module docstring); seconds unless named."""

    pairs_per_second: float
    zone_sum_fixed: float
    emitter_seconds: float
    emitters_fixed: float
    view_factor: float
    view_fixed: float
    write_bytes_per_second: float
    camera_pixel_seconds: float
    camera_look_seconds: float
    camera_fixed: float
    exact_pixel_seconds: float
    exact_fixed: float
    radiance_seconds: float
    radiance_pixel_seconds: float
    job_seconds: float
    process_plate_seconds: float
    process_camera_seconds: float
    first_plate_seconds: float
    first_camera_seconds: float
    fft_plan_seconds: float

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if (
                isinstance(value, bool)
                or not isinstance(value, (int, float))
                or not math.isfinite(value)
                or value < 0
                or (f.name == "pairs_per_second" and value == 0)
            ):
                raise ValueError(
                    f"calibration {f.name} must be a finite number >= 0 "
                    f"({'> 0' if f.name == 'pairs_per_second' else 'seconds'}); "
                    f"got {value!r}"
                )

    def process_seconds(self, kind: str) -> float:
        """A new worker's set-up before a ``kind`` ('plate' or 'camera') job's work."""
        return self.process_plate_seconds if kind == "plate" else self.process_camera_seconds

    def first_seconds(self, kind: str) -> float:
        """The set-up a cold kernel cache adds to a ``kind`` ('plate' or 'camera') job."""
        return self.first_plate_seconds if kind == "plate" else self.first_camera_seconds


# as on an idle machine: the development machine's calibration (2-core EPYC, PoCL; under
# load 1.6-11, each time over its load's slowdown) rounded to the slow side; Cycles' radiance
# from bench/estimates.py's demo at 640x360 (5.9-7.1 s at load 16-17: 0.6-0.8 s idle)
DEFAULT = Calibration(
    pairs_per_second=2.0e9,
    zone_sum_fixed=0.05,
    emitter_seconds=6.0e-6,
    emitters_fixed=0.05,
    view_factor=7.0,
    view_fixed=0.1,
    write_bytes_per_second=3.0e8,
    camera_pixel_seconds=2.0e-7,
    camera_look_seconds=7.0e-7,
    camera_fixed=0.1,
    exact_pixel_seconds=1.6e-6,
    exact_fixed=0.1,
    radiance_seconds=0.7,
    radiance_pixel_seconds=5.0e-7,
    job_seconds=0.2,
    process_plate_seconds=1.5,
    process_camera_seconds=1.2,
    first_plate_seconds=8.0,
    first_camera_seconds=1.5,
    fft_plan_seconds=2.0e-3,
)


@dataclass(frozen=True, slots=True, kw_only=True)
class Estimate:
    """A job's time in parts: ``work`` (stage, seconds) that every run pays, ``process`` the
    set-up of a new worker process, ``first`` what a cold kernel cache adds (0 when warm);
    ``calibrated``: whether the rates were measured on this machine; ``slowdown``: the
    factor the machine's present load puts on every part (1: idle; :func:`slowdown`)."""

    work: tuple = ()
    process: float = 0.0
    first: float = 0.0
    calibrated: bool = False
    slowdown: float = 1.0

    @property
    def seconds(self) -> float:
        """Everything: the work, a new worker's set-up and the first time's."""
        return sum(s for _, s in self.work) + self.process + self.first

    def __add__(self, other: Estimate) -> Estimate:
        return Estimate(
            work=self.work + other.work,
            process=max(self.process, other.process),
            first=max(self.first, other.first),
            calibrated=self.calibrated and other.calibrated,
            slowdown=max(self.slowdown, other.slowdown),
        )

    def words(self) -> str:
        """In plain words, the set-up said apart: 'about 11 s (of which 4 s the first time on
        this machine, 2 s starting the worker)', the load's factor and default rates said."""
        parts = []
        if self.first > 0:
            parts.append(f"{duration(self.first)} the first time on this machine")
        if self.process > 0:
            parts.append(f"{duration(self.process)} starting the worker")
        text = f"about {duration(self.seconds)}"
        if parts:
            text += f" (of which {', '.join(parts)})"
        if self.slowdown >= 1.2:
            text += f", {self.slowdown:.2g} times an idle machine's time at its present load"
        if not self.calibrated:
            text += "; by default rates (python -m holo_core calibrate measures this machine's)"
        return text


def duration(seconds: float) -> str:
    """``seconds`` as a person reads it: 0.3 s, 40 s, 3 min, 2.5 h."""
    if seconds < 9.5:
        return f"{max(seconds, 0.1):.1g} s"
    if seconds < 90:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.0f} min" if seconds < 5400 else f"{seconds / 3600:.2g} h"


def _cpus() -> set[int] | None:
    return os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else None


def _cpu_ticks(cpus: set[int]) -> dict[int, tuple[int, int]] | None:
    """(busy, all) clock ticks of each of ``cpus`` since boot, from /proc/stat (None where
    the system has none)."""
    try:
        with open("/proc/stat", encoding="ascii") as f:
            lines = f.read().splitlines()
    except OSError:
        return None
    ticks = {}
    for line in lines:
        name, *values = line.split()
        if name.startswith("cpu") and name[3:].isdigit() and int(name[3:]) in cpus:
            t = [int(v) for v in values[:8]]  # user nice system idle iowait irq softirq steal
            ticks[int(name[3:])] = (sum(t) - t[3] - t[4], sum(t))
    return ticks or None


_said = None  # the last (monotonic [s], busy CPUs)


def _own_ticks() -> float:
    """Clock ticks this process has run, its threads and the children it has waited for."""
    t = os.times()
    return (t.user + t.system + t.children_user + t.children_system) * os.sysconf("SC_CLK_TCK")


def busy_cpus(seconds: float | None = None) -> float | None:
    """How many of this process's CPUs other work keeps busy now: the busy ticks of
    /proc/stat over ``seconds`` [s] less this process's own, over the span (None where the
    system has no /proc/stat). None: the figure said less than RECENT ago (the parts of one
    estimate share one), else sampled over LOAD_SAMPLE. Not the ticks since an earlier
    reading: a process's children it has not waited for (Blender's worker) would count as
    other work, as the load average counts the jobs that have just ended."""
    global _said
    now = time.monotonic()
    if seconds is None and _said is not None and now - _said[0] < RECENT:
        return _said[1]
    cpus = _cpus()
    before = _cpu_ticks(cpus) if cpus else None
    if before is None:
        return None
    own = _own_ticks()
    time.sleep(LOAD_SAMPLE if seconds is None else seconds)
    after = _cpu_ticks(cpus) or {}
    own = _own_ticks() - own
    busy = sum(after.get(c, v)[0] - v[0] for c, v in before.items()) - own
    span = sum(after.get(c, v)[1] - v[1] for c, v in before.items()) / len(before)
    figure = max(busy, 0.0) / span if span > 0 else 0.0
    _said = (time.monotonic(), figure)
    return figure


def slowdown(load: float | None = None, cpus: int | None = None) -> float:
    """The factor other work puts on a job's time: 1 + ``load`` / ``cpus``, ``load`` the
    CPUs other work keeps busy (default: :func:`busy_cpus` now; where the system cannot say,
    the 1-minute load average), over the CPUs this process may use: a job that would use
    every CPU gets a fair share of them. The load average is not the default because it
    counts the work of the jobs that have just ended (a farm's previous frame, a bench's
    previous run) as if it went on."""
    if load is None:
        load = busy_cpus()
    if load is None:
        try:
            load = os.getloadavg()[0]
        except OSError:  # no load average (Windows): taken as idle
            load = 0.0
    if cpus is None:
        mine = _cpus()
        cpus = len(mine) if mine else (os.cpu_count() or 1)
    return 1.0 + max(float(load), 0.0) / max(cpus, 1)


# --- the cache: the calibration and the stamps --------------------------------------------------


def cache_folder(cache_dir=None) -> Path:
    """Holo's folder in the user cache directory (the FFT wisdom's), or in ``cache_dir`` (the
    worker's ``XDG_CACHE_HOME`` when the add-on names one)."""
    if cache_dir:
        return Path(cache_dir) / "holo"
    from platformdirs import user_cache_dir

    return Path(user_cache_dir("holo"))


def kernel_cache(cache_dir=None) -> Path:
    """pyopencl's program cache folder (where it puts it; :func:`holo_core.opencl.runtime.
    cache_lock`'s folder's parent)."""
    if cache_dir:
        return Path(cache_dir) / "pyopencl"
    from platformdirs import user_cache_dir

    return Path(user_cache_dir("pyopencl", "pyopencl"))


def device_key(device: str | None = None) -> str:
    """The device a calibration holds for: the choice (``HOLO_DEVICE`` or the add-on's),
    '' for automatic."""
    return (os.environ.get("HOLO_DEVICE", "") if device is None else device).strip()


def _version() -> str:
    from . import __version__

    return __version__


def _slug(text: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in text) or "auto"


def load(*, device: str | None = None, cache_dir=None) -> tuple[Calibration, bool]:
    """(the calibration, whether it was measured here): the file's where it is this version's
    and this ``device``'s, else :data:`DEFAULT` (a file that cannot be read: with a warning
    naming it)."""
    path = cache_folder(cache_dir) / FILE
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return DEFAULT, False
    except (OSError, UnicodeDecodeError) as e:
        log.warning(
            "estimates: the calibration %s cannot be read (%s): default rates taken; "
            "python -m holo_core calibrate measures it again",
            path,
            e,
        )
        return DEFAULT, False
    try:
        data = json.loads(text)
        version, dev = data["version"], data["device"]
        rates = data["rates"]
        if not isinstance(rates, dict) or set(rates) != {f.name for f in fields(Calibration)}:
            raise ValueError("its rates are not the calibration's fields")
        cal = Calibration(**rates)
    except (ValueError, KeyError, TypeError) as e:
        log.warning(
            "estimates: the calibration %s is refused (%s): default rates taken; "
            "python -m holo_core calibrate measures it again",
            path,
            str(e)[:200],
        )
        return DEFAULT, False
    if version != _version() or dev != device_key(device):
        log.info(
            "estimates: the calibration %s is of Holo %s on device %r, not %s on %r: "
            "default rates taken",
            path,
            version,
            dev,
            _version(),
            device_key(device),
        )
        return DEFAULT, False
    return cal, True


def save(cal: Calibration, *, device: str | None = None, cache_dir=None) -> Path:
    """Keep ``cal`` as this version's and ``device``'s calibration (atomically)."""
    folder = cache_folder(cache_dir)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / FILE
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(
        json.dumps(
            {"version": _version(), "device": device_key(device), "rates": asdict(cal)}, indent=1
        ),
        encoding="utf-8",
    )
    os.replace(tmp, path)
    return path


def _stamp(kind: str, device, cache_dir) -> Path:
    key = _slug(f"{_version()}-{device_key(device)}")
    return cache_folder(cache_dir) / STAMP.format(kind=kind, key=key)


def is_warm(kind: str, *, device: str | None = None, cache_dir=None) -> bool:
    """Whether a ``kind`` ('plate', 'camera') job of this version on ``device`` has run with
    this cache, and the kernel cache it filled is still there."""
    cache = kernel_cache(cache_dir)
    return _stamp(kind, device, cache_dir).is_file() and cache.is_dir() and any(cache.iterdir())


def mark_warm(kind: str, *, device: str | None = None, cache_dir=None) -> None:
    """A ``kind`` job has run: its programs are in the kernel cache and its FFT plans in
    the wisdom (the worker calls this after each job; an unwritable cache is left as it is)."""
    path = _stamp(kind, device, cache_dir)
    if path.is_file():
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.touch()
    except OSError as e:
        log.debug("estimates: stamp %s not written (%s)", path, e)


# --- the stages ------------------------------------------------------------------------------


def _loaded(est: Estimate, load_average) -> Estimate:
    """``est`` (idle seconds) at the machine's ``load_average`` (:func:`slowdown`'s)."""
    k = slowdown(load_average)
    return replace(
        est,
        work=tuple((n, s * k) for n, s in est.work),
        process=est.process * k,
        first=est.first * k,
        slowdown=k,
    )


def _warm(kind, device, cache_dir, warm) -> bool:
    return is_warm(kind, device=device, cache_dir=cache_dir) if warm is None else warm


def _setup(kind, cal, calibrated, device, cache_dir, warm, plans=0.0) -> Estimate:
    """A new worker's set-up and, on a cold cache, the first time's (``plans``: its FFT
    plans' seconds where they are counted apart)."""
    return Estimate(
        process=cal.process_seconds(kind),
        first=0.0 if _warm(kind, device, cache_dir, warm) else cal.first_seconds(kind) + plans,
        calibrated=calibrated,
    )


def _found(p, cal: Calibration) -> float:
    """Seconds finding the emitters of the plan ``p``: their count, and the triangles they
    are found among (TRIANGLE_SECONDS each, where the plan knows them)."""
    return cal.emitters_fixed + p.emitters * cal.emitter_seconds + p.triangles * TRIANGLE_SECONDS


def divisors(n: int) -> int:
    """How many divisors the integer ``n`` >= 1 has."""
    count, k = 0, 1
    while k * k <= n:
        if n % k == 0:
            count += 1 if k * k == n else 2
        k += 1
    return count


def fft_plans(lengths, cal: Calibration) -> float:
    """Seconds FFTW takes to measure the plans of transforms of ``lengths`` (each once): per
    length FFT_PROBLEMS problems (a pass's blocks: a full one and the last), each
    ``cal.fft_plan_seconds`` × τ(L)^1.5, τ the number of divisors (the planner tries the
    ways a length factors: over the 7-smooth lengths 100-4000 on the development machine
    within a factor 1.5 rms of its measure, whatever the length)."""
    return FFT_PROBLEMS * cal.fft_plan_seconds * sum(divisors(n) ** 1.5 for n in set(lengths))


def camera_lengths(j) -> tuple[int, ...]:
    """The FFT lengths the camera pass of the job ``j`` transforms
    (:func:`holo_core.camera.optics.transform_lengths` of the optics it will choose for its
    emitters' depths); none where no emitter lies in front of its camera (the job refuses
    that itself)."""
    from .camera.optics import choose_optics, transform_lengths
    from .camera.raster import depth_range
    from .validate import InputError

    meshes = list(j.points + j.triangles)
    try:
        with warnings.catch_warnings():  # the pass warns of its own sampling itself
            warnings.simplefilter("ignore")
            optics = choose_optics(
                j.camera, depth_range(meshes, j.camera), supersample=j.route.supersample
            )
    except InputError:
        return ()
    return transform_lengths(optics, j.route.speckle)


def plate(
    p,
    view=None,
    *,
    record=True,
    channels=4,
    device=None,
    cache_dir=None,
    warm=None,
    calibration=None,
    load_average=None,
) -> Estimate:
    """The estimate of a plate's job from its plan ``p`` (:class:`~holo_core.plate.plan.
    PlatePlan`): the recording when ``record`` (its emitters, the zone sum, its files) and
    the view ``view`` (a :class:`~holo_core.plate.plan.ViewPlan`, None: no view), in a new
    worker. ``warm``: whether the kernel cache is warm (None: as the cache says);
    ``calibration``: (Calibration, measured) (None: :func:`load`'s); ``load_average``: the
    load the job will share the machine with (None: now's; 0: idle; :func:`slowdown`)."""
    cal, calibrated = calibration or load(device=device, cache_dir=cache_dir)
    work = [("job", cal.job_seconds)]
    if record:
        work += [
            ("emitters", _found(p, cal)),
            ("zone sum", cal.zone_sum_fixed + p.pairs(channels) / cal.pairs_per_second),
            ("files", p.disk_bytes(channels) / cal.write_bytes_per_second),
        ]
    if view is not None:
        work.append(("view", cal.view_fixed + view.seconds * cal.view_factor))
    return _loaded(
        replace(_setup("plate", cal, calibrated, device, cache_dir, warm), work=tuple(work)),
        load_average,
    )


def plate_set(
    s, *, channels=4, device=None, cache_dir=None, warm=None, calibration=None, load_average=None
) -> Estimate:
    """The estimate of recording a plate set from its plan ``s`` (:class:`~holo_core.plate.
    path.SetPlan`) in a new worker (``warm``, ``calibration``, ``load_average``: as
    :func:`plate`'s): the emitters found once a lattice (``s.lattices``), each part's own
    set-up (``PART_SECONDS``), its emitters' visibility (``VISIBILITY_SECONDS`` each), zone
    sum and files, a part's files written while the next part is summed (the part of the
    writing that outlasts the next sum counted; the last part's whole), their digest on the
    CPU beside the sum."""
    cal, calibrated = calibration or load(device=device, cache_dir=cache_dir)
    found = max(_found(p, cal) for p in s.plans)
    seen = sum(p.emitters * VISIBILITY_SECONDS for p in s.plans)
    sums = [cal.zone_sum_fixed + p.pairs(channels) / cal.pairs_per_second for p in s.plans]
    files = [p.disk_bytes(channels) / cal.write_bytes_per_second for p in s.plans]
    digests = [p.disk_bytes(channels) / DIGEST_BYTES_PER_SECOND for p in s.plans]
    waits = [max(f - z, 0.0) for f, z in zip(files, sums[1:])] + files[-1:]
    work = (
        ("job", cal.job_seconds),
        ("parts", PART_SECONDS * len(s.plans)),
        ("emitters", s.lattices * found + seen),
        ("zone sums", sum(sums) + sum(digests)),
        ("files", sum(waits)),
    )
    return _loaded(
        replace(_setup("plate", cal, calibrated, device, cache_dir, warm), work=work), load_average
    )


def camera(
    resolution,
    *,
    samples,
    supersample,
    speckle="EXACT",
    device=None,
    cache_dir=None,
    warm=None,
    calibration=None,
    load_average=None,
    lengths=(),
) -> Estimate:
    """The estimate of a camera pass of ``resolution`` (W, H) pixels and ``supersample``
    fine pixels a pixel, with ``speckle`` 'EXACT' (one incoherent pass) or 'LOOKS'
    (``samples`` looks), in a new worker (``warm``, ``calibration``, ``load_average``: as
    :func:`plate`'s); ``lengths``: the FFT lengths it transforms (:func:`camera_lengths`),
    whose plans a cold cache measures."""
    cal, calibrated = calibration or load(device=device, cache_dir=cache_dir)
    fine = resolution[0] * resolution[1] * supersample**2
    passed = (
        cal.exact_fixed + fine * cal.exact_pixel_seconds
        if speckle == "EXACT"
        else cal.camera_fixed
        + fine * (cal.camera_pixel_seconds + samples * cal.camera_look_seconds)
    )
    work = (("job", cal.job_seconds), ("camera pass", passed))
    plans = fft_plans(lengths, cal)
    return _loaded(
        replace(_setup("camera", cal, calibrated, device, cache_dir, warm, plans), work=work),
        load_average,
    )


def radiance(
    pixels: int, *, device=None, cache_dir=None, calibration=None, load_average=None
) -> Estimate:
    """Cycles' radiance of the emitters over ``pixels`` pixels: its process's start and its
    render (the same each run: Blender's own caches are not Holo's)."""
    cal, calibrated = calibration or load(device=device, cache_dir=cache_dir)
    return _loaded(
        Estimate(
            work=(("radiance", cal.radiance_seconds + pixels * cal.radiance_pixel_seconds),),
            calibrated=calibrated,
        ),
        load_average,
    )


def job(
    j,
    *,
    plan=None,
    view=None,
    device=None,
    cache_dir=None,
    warm=None,
    calibration=None,
    load_average=None,
) -> Estimate:
    """The estimate of a :class:`holo_core.job.Job` in a new worker: its renderer's radiance,
    then its route's; a plate's from its ``plan`` and ``view`` (:func:`plate`'s, which the
    caller makes: the planner is theirs)."""
    from .job import CameraRoute

    calibration = calibration or load(device=device, cache_dir=cache_dir)
    common = {
        "device": device,
        "cache_dir": cache_dir,
        "calibration": calibration,
        "warm": warm,
        "load_average": load_average,
    }
    if isinstance(j.route, CameraRoute):
        common["warm"] = _warm("camera", device, cache_dir, warm)  # the cache read once
        est = camera(
            j.camera.resolution,
            samples=j.route.samples,
            supersample=j.route.supersample,
            speckle=j.route.speckle,
            lengths=() if common["warm"] else camera_lengths(j),
            **common,
        )
    else:
        est = plate(plan, view if j.output.render else None, record=j.route.record, **common)
    if j.radiance is not None:
        w, h = j.radiance.camera.resolution
        est = radiance(w * h, calibration=calibration, load_average=load_average) + est
    return est
