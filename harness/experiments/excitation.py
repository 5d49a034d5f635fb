"""The designed excitation (`torquebench excite`) against generate's default, for the bench.

For the bench's robot: the excitation designed over the draws' duration (SAMPLES at
SAMPLE_RATE, seed 1) and its condition number (the identification's atoms and offsets,
columns normalized) against the default excitation's; then the draw of the first seed
generated again along the designed excitation (same samples, noise and seed), identified
with the default library and judged on the motion of another family, against the same
draw along the default excitation.
"""

from __future__ import annotations

import numpy as np

from harness.data.excite import design_for
from harness.data.generate import SAMPLE_RATE, generate
from harness.errors import UserError
from harness.experiments.identification import NOISE, SAMPLES, Motion, score_draw
from harness.sections.base import Target

DESIGN_SEED = 1
CONDITION = ("designed excitation's condition number (atoms + offsets, columns normalized), "
             "against the default excitation's")
ERROR = ("{name} error on the other excitation's motion, trained along the designed excitation "
         "/ along the default (seed {seed}, median over joints)")
QUICK_ITERATIONS = 20  # the design's SLSQP iterations in --quick


def excitation_comparison(robot: str, fit, name: str, baseline, judge: Motion, draw: dict,
                          quick: bool) -> tuple[list[Target], dict]:
    """Targets (designed condition <= default's; designed-draw error <= default-draw error on
    the judge, median over joints) and the figures behind them; `draw` is score_draw's result
    on the default excitation's data of seed draw['seed'] with `name` scored on `judge`."""
    try:
        designed = design_for(robot, SAMPLES / SAMPLE_RATE, SAMPLE_RATE, seed=DESIGN_SEED,
                              **({"iterations": QUICK_ITERATIONS} if quick else {}))
    except UserError as exc:  # e.g. no collision-free start: the targets are unmeasured
        return [Target(CONDITION, None, 1.0, note=str(exc)),
                Target(ERROR.format(name=name, seed=draw["seed"]), None, 1.0, "x")], {"error": str(exc)}
    data = generate(robot, SAMPLES, NOISE, draw["seed"], "inverse", excitation=designed.trajectory)
    along = score_draw(data, {name: fit}, baseline, [judge])
    errors = np.array(along[name][judge.name])
    default_errors = np.array(draw[name][judge.name])
    ratio = float(np.median(errors / np.maximum(default_errors, 1e-300)))
    targets = [
        Target(CONDITION, designed.condition, designed.default_condition),
        Target(ERROR.format(name=name, seed=draw["seed"]), ratio, 1.0, "x")]
    results = {"condition": designed.condition, "default_condition": designed.default_condition,
               "iterations": designed.design.iterations, "seed": draw["seed"],
               "errors": errors.tolist(), "default_errors": default_errors.tolist(),
               "median_ratio": ratio}
    return targets, results


def markdown(r: dict) -> list[str]:
    """The comparison as a paragraph of the section."""
    if "error" in r:
        return [f"Designed excitation: not designed ({r['error']})."]
    pct = lambda xs: ", ".join(f"{100 * x:.2f} %" for x in xs)  # noqa: E731
    return [f"Designed excitation (`torquebench excite`, {SAMPLES / SAMPLE_RATE:g} s, seed "
            f"{DESIGN_SEED}): condition number {r['condition']:.3g} against the default "
            f"excitation's {r['default_condition']:.3g}. Draw of seed {r['seed']} along it: error "
            f"on the other family's motion {pct(r['errors'])} (along the default: "
            f"{pct(r['default_errors'])}; median ratio {r['median_ratio']:.2f})."]
