"""A bench's figures as data: ``write(name, figures)`` puts them in ``bench/results/NAME.json``
with the machine (the CPU's model name, its cores, the CPUs this process may use), its load
when the bench began and when it ended, the date and the command, so that the documentation's
Performance page renders the latest run of each bench into a table (docs/_ext/bench_results.py).

``figures`` maps a figure's name to its value (a number or a short text), or a row's name to
a mapping of column to value (a table). Names carry their unit (``"sweep step [ms]"``).
History lives in git: each run replaces the file.
"""

from __future__ import annotations

import datetime
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

# HOLO_BENCH_RESULTS: another folder (runtimes.py sends its per-device runs there, keeping
# bench/results/ for the default device's)
RESULTS = Path(os.environ.get("HOLO_BENCH_RESULTS") or Path(__file__).resolve().parent / "results")
# the load as the bench process began (this module is imported at its start)
_LOAD_AT_START = os.getloadavg()


def cpu_name() -> str:
    """The CPU's model name as lscpu gives it (else the platform's processor string)."""
    try:
        out = subprocess.run(["lscpu"], check=False, capture_output=True, text=True).stdout
        return next(
            line.split(":", 1)[1].strip()
            for line in out.splitlines()
            if line.startswith("Model name")
        )
    except (OSError, StopIteration):
        return platform.processor() or "unknown CPU"


def machine() -> dict:
    """The machine a result was measured on and its load average (1, 5, 15 minutes)."""
    return {
        "cpu": cpu_name(),
        "cores": os.cpu_count(),
        "usable_cpus": len(os.sched_getaffinity(0))
        if hasattr(os, "sched_getaffinity")
        else os.cpu_count(),
        "load_at_start": [round(x, 2) for x in _LOAD_AT_START],
        "load_at_end": [round(x, 2) for x in os.getloadavg()],
        "python": platform.python_version(),
        "system": platform.platform(),
    }


def _plain(value):
    """NumPy scalars and tuples as JSON takes them."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item"):  # a NumPy scalar
        return value.item()
    return value


def write(name: str, figures: dict, *, device: str | None = None) -> Path:
    """Write ``bench/results/<name>.json``: the figures, the machine and its load, the date,
    the command that ran the bench and, where given, the OpenCL device. Atomic (a temporary
    file renamed over the last result)."""
    record = {
        "bench": name,
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "command": " ".join([Path(sys.argv[0]).name, *sys.argv[1:]]),
        "machine": machine(),
        "device": device,
        "figures": _plain(figures),
    }
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{name}.json"
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(record, indent=1, ensure_ascii=False) + "\n")
    os.replace(tmp, path)
    print(f"figures written to {path}")
    return path
