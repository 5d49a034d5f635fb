"""Identification benchmark: paper per-joint vs coupled (symmetric, general) vs the oracle,
over independent noise draws, noise levels and data sizes.

    python -m benchmarks.identification_draws [--draws 20] [--levels 0.01 0.05 0.1]
                                        [--samples 4000 8000] [--out FILE.json]

The bench section runs 20 draws at 5 %; this script repeats that robustness summary at
any level and data size (more data: a true term lost at high noise comes back). Draw k
at level L uses noise seed 1 + 1000 k + round(1000 L) except at 5 %, where it is 1 + 1000 k
(seed 1: the default data of generate(..., seed=0)), so no two levels share a draw.
Nothing is tuned here: every choice is made on the training part of each dataset.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

# run as a script, this file's folder leads sys.path and its name would shadow the
# `identification` package
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

from threadpoolctl import threadpool_limits  # noqa: E402

from harness.data.generate import generate  # noqa: E402
from harness.io import write_json  # noqa: E402
from harness.robots.baseline import PinocchioModel  # noqa: E402
from harness.robots.registry import load_pinocchio  # noqa: E402
from harness.sections.identification import robustness, study  # noqa: E402


def _context(samples: int) -> dict:
    ctx = study.context()
    if samples != len(ctx["clean"].q):  # more data: same robot, same excitation design
        clean = generate("lynxmotion", samples, 0.0, seed=0)
        ctx.update(clean=clean, theta=ctx["library"].evaluate(clean.q, clean.qd, clean.qdd),
                   truth={k: study.true_terms(v, clean) for k, v in ctx["libraries"].items()},
                   atoms={k: study.true_atoms(b, clean) for k, b in ctx["bases"].items()},
                   regressor=PinocchioModel(load_pinocchio("lynxmotion")).regressor(
                       clean.q, clean.qd, clean.qdd))
    return ctx


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=20, help="independent noise draws per level")
    parser.add_argument("--samples", type=int, nargs="+", default=[4000])
    parser.add_argument("--levels", type=float, nargs="+", default=[0.01, 0.05, 0.10])
    parser.add_argument("--out", help="write all numbers as JSON")
    args = parser.parse_args()
    results: dict = {}
    with threadpool_limits(limits=1, user_api="blas"):
        for samples in args.samples:
            ctx = _context(samples)
            for level in args.levels:
                shift = 0 if level == 0.05 else round(1000 * level)
                seeds = tuple(1 + 1000 * k + shift for k in range(args.draws))
                rob = robustness.robustness(ctx, seeds, level)
                print(f"\n### {samples} samples, last 25 % held out")
                print("\n".join(robustness.robustness_markdown(rob)))
                results[f"{samples}/{level:g}"] = rob
    if args.out:
        write_json(args.out, results)


if __name__ == "__main__":
    main()
