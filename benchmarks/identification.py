"""Identification benchmark: paper per-joint vs coupled vs oracle vs pysindy, over noise draws.

    python benchmarks/identification.py [--draws 3] [--samples 4000 8000] [--out FILE.json]

The bench section runs one noise draw (the default data). This script repeats
the comparison over several independent noise draws (the first is the default
data), so a ratio to the oracle is not one lucky draw, and over data sizes, so
a true term lost at 5 % noise can be shown to come back with more data. Prints
one markdown table per data size and the per-level mean over draws; nothing is
tuned here (every choice is made on the training part of each dataset).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

# run as a script, this file's folder leads sys.path and its name would shadow the
# `identification` package
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

import numpy as np  # noqa: E402

from harness.datagen import generate  # noqa: E402
from harness.io import write_json  # noqa: E402
from harness.pinocchio_baseline import PinocchioModel  # noqa: E402
from harness.robots import load_pinocchio  # noqa: E402
from harness.sections import identification as section  # noqa: E402


def _context(samples: int) -> dict:
    ctx = section.context()
    if samples != len(ctx["clean"].q):  # more data: same robot, same excitation design
        clean = generate("lynxmotion", samples, 0.0, seed=0)
        lib = ctx["library"]
        ctx.update(clean=clean, theta=lib.evaluate(clean.q, clean.qd, clean.qdd),
                   truth=section.true_terms(lib, clean), atoms=section.true_atoms(ctx["basis"], clean),
                   regressor=PinocchioModel(load_pinocchio("lynxmotion")).regressor(
                       clean.q, clean.qd, clean.qdd))
    return ctx


def _summary(c: dict) -> dict:
    out = {m: {"rel": [j["rel"] for j in c[m]["joints"]],
               "recall": [j["recall"] for j in c[m]["joints"]],
               "precision": [j["precision"] for j in c[m]["joints"]],
               "fresh": [j["fresh"] for j in c[m]["joints"]],
               "seconds": c[m]["seconds"]} for m in section.METHODS}
    out["oracle"] = c["oracle"]
    out["pysindy"] = {k: v["rel"] for k, v in c.get("pysindy", {}).items()}
    out["atoms"] = c["coupled"]["lagrangian"]["atoms"]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=3, help="independent noise draws (1 = default data)")
    parser.add_argument("--samples", type=int, nargs="+", default=[4000])
    parser.add_argument("--levels", type=float, nargs="+", default=list(section.LEVELS))
    parser.add_argument("--out", help="write all numbers as JSON")
    args = parser.parse_args()
    results: dict = {}
    for samples in args.samples:
        ctx = _context(samples)
        print(f"\n### {samples} samples, last 25 % held out\n")
        print("\n".join(section.TABLE_HEAD))
        per_level: dict = {}
        for level in args.levels:
            for draw in range(args.draws):
                # draw 0: noise seed 1, the default data of generate(..., seed=0)
                c = section.compare(level, ctx, with_pysindy=True, seed=1 + 1000 * draw)
                print("\n".join(r.replace(f"| {100 * level:g} % |", f"| {100 * level:g} % #{draw} |")
                                for r in section.table_rows(level, c)))
                per_level.setdefault(f"{level:g}", []).append(_summary(c))
        results[str(samples)] = per_level
        print("\nOver draws: ratio of mean held-out errors to the oracle's (and the worst "
              "single-draw ratio), mean recall, per joint:")
        for level, runs in per_level.items():
            if float(level) == 0:
                continue
            orc = np.array([r["oracle"] for r in runs])
            for m in section.METHODS:
                rel = np.array([r[m]["rel"] for r in runs])
                rec = np.mean([r[m]["recall"] for r in runs], axis=0)
                print(f"  {100 * float(level):g} % {m:9s}: {np.round(rel.mean(0) / orc.mean(0), 2).tolist()} "
                      f"(worst {np.round(np.max(rel / orc, axis=0), 2).tolist()}), recall "
                      f"{np.round(rec, 2).tolist()}")
    if args.out:
        write_json(args.out, results)


if __name__ == "__main__":
    main()
