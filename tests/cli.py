"""The command line run in the test's process."""


def run_cli(capsys, *args):
    """``python -m holo_core ARGS`` in this process: (exit status, stdout, stderr)."""
    from holo_core.__main__ import main
    try:
        status = main([str(a) for a in args])
    except SystemExit as e:  # argparse's errors
        status = e.code
    out = capsys.readouterr()
    return status, out.out, out.err
