"""The quality model's two constants fitted to bench/closeup.py's figures, and how well the
model then predicts each measured setting.

:mod:`holo_core.plate.quality` predicts a plate view's PSNR against the camera hologram as

    PSNR = 10·log10(size / (EDGE_ERROR + SPECKLE_SCALE · (σ/⟨I⟩)²)).

bench/closeup.py (two seeds) splits each view's error into the speckle's part and the part no
seed changes, and writes beside them what the model takes: the objects' size [px] and the
setting's (σ/⟨I⟩)². Here the speckle's mean square times the size is fitted as SPECKLE_SCALE
times (σ/⟨I⟩)², the seed-free mean square times the size as EDGE_ERROR (each a geometric mean:
the errors are compared in decibels), over the FITTED results; every result listed is then
predicted with the fitted constants beside the ones in the code, and the most the model
predicts above a fitted setting is printed (Auto's MODEL_MARGIN).

    python bench/quality_fit.py [RESULT ...]   (default: the close-up at 320x180 and the
                                                shot's scene at 640x360; the full-size close-up
                                                predicted, not fitted)
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np
import results  # the bench folder's own: the figures as data

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT)]

from holo_core.plate import quality  # noqa: E402

FITTED = ("closeup_scale0.5", "closeup_shot_scene_scale0.5")
CHECKED = ("closeup",)


def rows(name: str):
    """(size [px], the rows that carry the model's inputs) of bench/results/NAME.json."""
    figures = json.loads((results.RESULTS / f"{name}.json").read_text())["figures"]
    size = figures.get("objects' size [px]")
    taken = [
        r
        for r in figures.values()
        if isinstance(r, dict) and "(σ/⟨I⟩)²" in r and "speckle part [dB]" in r
    ]
    if size is None or not taken:
        raise SystemExit(
            f"{name}.json holds no two-seed rows with the model's inputs: run "
            f"bench/closeup.py (--seeds 2) again"
        )
    return size, taken


def mean_square(db: float) -> float:
    return 10 ** (-db / 10)


def predicted(size, row, scale, edge) -> float:
    return 10 * math.log10(size / (edge + scale * row["(σ/⟨I⟩)²"]))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "fitted", nargs="*", default=list(FITTED), help="results fitted (bench/results/NAME.json)"
    )
    args = p.parse_args()
    speckle, edge = [], []
    for name in args.fitted:
        size, taken = rows(name)
        speckle += [mean_square(r["speckle part [dB]"]) * size / r["(σ/⟨I⟩)²"] for r in taken]
        edge += [mean_square(r["seed-free part [dB]"]) * size for r in taken]
    scale, error = float(np.exp(np.mean(np.log(speckle)))), float(np.exp(np.mean(np.log(edge))))
    print(
        f"fitted over {', '.join(args.fitted)}: SPECKLE_SCALE {scale:.3g} (the code's "
        f"{quality.SPECKLE_SCALE:g}), EDGE_ERROR {error:.3g} px (the code's "
        f"{quality.EDGE_ERROR:g})"
    )
    figures = {
        "fitted over": ", ".join(args.fitted),
        "SPECKLE_SCALE": scale,
        "EDGE_ERROR [px]": error,
    }
    over = 0.0  # the most the fitted model predicts above a measured setting of the fitted
    for name in dict.fromkeys([*args.fitted, *CHECKED]):
        try:
            size, taken = rows(name)
        except SystemExit as e:
            print(e)
            continue
        off = [r["PSNR [dB]"] - predicted(size, r, scale, error) for r in taken]
        now = [
            r["PSNR [dB]"] - predicted(size, r, quality.SPECKLE_SCALE, quality.EDGE_ERROR)
            for r in taken
        ]
        role = "fitted" if name in args.fitted else "not fitted"
        if name in args.fitted:
            over = max(over, -min(off))
        print(
            f"{name} ({role}, {size:.0f} px objects): measured minus predicted "
            f"{min(off):+.2f} to {max(off):+.2f} dB (the code's constants "
            f"{min(now):+.2f} to {max(now):+.2f})"
        )
        figures[name] = {
            "role": role,
            "objects' size [px]": size,
            "measured - predicted, least [dB]": min(off),
            "measured - predicted, most [dB]": max(off),
        }
    print(
        f"the model predicts at most {over:.2f} dB above a fitted setting (Auto aims "
        f"MODEL_MARGIN {quality.MODEL_MARGIN:g} dB above its target)"
    )
    figures["most predicted above a fitted setting [dB]"] = over
    results.write("quality_fit", figures)


if __name__ == "__main__":
    main()
