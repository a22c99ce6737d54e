"""Every usable OpenCL device side by side: the three benches run once per device (each in a
process of its own with ``HOLO_DEVICE`` set), and their headline figures in one table.

    python bench/runtimes.py            (or: make bench-runtimes)
"""

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import results  # the bench folder's own: the figures as data

HERE = Path(__file__).parent
SCRATCH = tempfile.mkdtemp(prefix="holo-bench-runtimes-")
FIGURES = {  # bench script -> (column, pattern of its figure, unit)
    "propagation.py": ("1024² ASM", r"holo angular_spectrum :\s+([\d.]+) ms", "ms"),
    "record.py": ("point sum", r"([\d.]+e\+\d+) pairs/s in the cones", "pairs/s"),
    "render.py": ("Table I", r"per iteration: ([\d.]+) s", "s/iteration"),
}


def usable_devices():
    from holo_core.opencl import all_devices, device_problem

    return [
        (f"{p}:{d}", f"{dev.name.strip()} ({dev.platform.name.strip()})")
        for p, d, dev in all_devices()
        if not device_problem(dev)
    ]


def run(script, spec):
    env = {
        **os.environ,
        "HOLO_DEVICE": spec,
        "PYTHONUNBUFFERED": "1",
        "HOLO_BENCH_RESULTS": SCRATCH,
    }  # bench/results/ keeps the default device's runs
    r = subprocess.run(
        [sys.executable, str(HERE / script)], env=env, capture_output=True, text=True
    )
    print(
        f"--- {script} on {spec}\n{r.stdout}{r.stderr[-1500:] if r.returncode else ''}", flush=True
    )
    name, pattern, unit = FIGURES[script]
    m = re.search(pattern, r.stdout)
    return f"{m.group(1)} {unit}" if m else f"failed ({r.returncode})"


def main():
    devices = usable_devices()
    rows = [(desc, [run(script, spec) for script in FIGURES]) for spec, desc in devices]
    names = [name for name, _, _ in FIGURES.values()]
    print("device".ljust(50) + "".join(n.rjust(24) for n in names))
    for desc, figures in rows:
        print(desc[:49].ljust(50) + "".join(f.rjust(24) for f in figures))
    results.write("runtimes", {desc: dict(zip(names, figures)) for desc, figures in rows})


if __name__ == "__main__":
    main()
