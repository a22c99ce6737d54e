"""The command line run in the test's process, or in a process of its own."""

import os
import subprocess
import sys

CUBE_OBJ = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n"  # a unit square


def run_cli(capsys, *args):
    """``python -m holo_core ARGS`` in this process: (exit status, stdout, stderr)."""
    from holo_core.__main__ import main

    try:
        status = main([str(a) for a in args])
    except SystemExit as e:  # argparse's errors
        status = e.code
    out = capsys.readouterr()
    return status, out.out, out.err


def run_process(*args, env=None):
    """``python -m holo_core ARGS`` in a process of its own (a subprocess.CompletedProcess)."""
    return subprocess.run(
        [sys.executable, "-m", "holo_core", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, **(env or {})},
    )
