"""Fuzzing (tools/fuzz.py): each mutated file, hostile hologram, hostile API call, damaged
tiled store or display layout ends in a sane result (finite; a hologram that reads also
reconstructs and renders finite; a store reads back exactly what was recorded) or InputError
(a reader's naming its file or store).

``make test`` runs HOLO_FUZZ_CASES (300) cases per target; ``make fuzz`` runs 5000.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

FUZZ = Path(__file__).resolve().parents[3] / "tools" / "fuzz.py"
CASES = int(os.environ.get("HOLO_FUZZ_CASES", "300"))


@pytest.mark.parametrize(
    "reader", ["hologram", "ply", "obj", "scan", "lab", "write", "api", "store", "layout"]
)
def test_every_mutated_file_ends_in_a_result_or_the_clear_error(reader):
    run = subprocess.run(
        [sys.executable, str(FUZZ), reader, str(CASES), "20261122"],
        capture_output=True,
        text=True,
        timeout=60 + CASES,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    report = json.loads(run.stdout.strip().splitlines()[-1])
    print(json.dumps(report))
    outcomes = report["outcomes"]
    assert sum(outcomes.values()) == CASES
    assert set(outcomes) <= {"ok", "InputError"}, report["examples"]
    # the suite is not idle: the valid files (and calls) pass and most mutations are refused
    assert outcomes.get("ok", 0) >= CASES // 10 and outcomes.get("InputError", 0) >= CASES // 3
