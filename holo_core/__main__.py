"""Command line: ``python -m holo_core devices | demo``."""

from __future__ import annotations

import argparse
import logging
import sys


def devices(_args) -> int:
    from .opencl import all_devices, choose_device
    from .opencl.runtime import is_cpu
    for p, d, dev in all_devices():
        kind = "CPU" if is_cpu(dev) else "GPU/other"
        print(f"  {p}:{d} {dev.name} [{kind}] on {dev.platform.name} "
              f"({dev.max_compute_units} compute units)")
    chosen = choose_device()
    print(f"would use: {chosen.name} (set HOLO_DEVICE=gpu|cpu|P:D|name to choose)")
    return 0


def demo(args) -> int:
    from .demo import run
    for path in run(args.output):
        print(path)
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m holo_core", description=__doc__)
    parser.add_argument("-v", "--verbose", action="store_true")
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("devices", help="list OpenCL devices and the one Holo would use")
    p = sub.add_parser("demo", help="render the built-in demo to image files")
    p.add_argument("-o", "--output", default="out", help="output folder (default: out)")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    try:
        return {"devices": devices, "demo": demo}[args.command](args)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
