"""The designed excitation (`torquebench excite`) against generate's default, for the bench.

For the bench's robot: the excitation designed (excite's default criterion) over the draws'
duration (SAMPLES at SAMPLE_RATE, seed 1) and its condition number (the identification's
atoms and offsets, columns normalized) against the default excitation's; then the draw of the first seed
generated again along the designed excitation (same samples, noise and seed), identified
with the default library and judged on the motion of another family, against the same
draw along the default excitation; and, for information, the same with the default draw's
noise samples on the design's torque (the same sensor).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from harness.data.excite import design_for
from harness.data.generate import SAMPLE_RATE, generate
from harness.errors import UserError
from harness.identify.scoring import NOISE, SAMPLES, Motion, score_draw
from harness.report.results import Target
from harness.robots.arm import Arm

DESIGN_SEED = 1
CONDITION = ("designed excitation's condition number (atoms + offsets, columns normalized), "
             "against the default excitation's")
ERROR = ("{name} error on the other excitation's motion, trained along the designed excitation "
         "/ along the default (median over joints; median over the draws of seeds {seeds})")
QUICK_ITERATIONS = 20  # the design's SLSQP iterations in --quick


def along_design(arm: Arm, designed, fit, name: str, baseline, judge: Motion, draw: dict) -> dict:
    """One draw generated again along the design: errors per joint, and their median ratio to
    the same draw along the default excitation, with generate's noise and with the same
    sensor's (the default draw's noise on the design's torque: a sensor's noise does not grow
    with the motion, generate's does)."""
    data = generate(arm, SAMPLES, NOISE, draw["seed"], "inverse", excitation=designed.trajectory)
    default = generate(arm, SAMPLES, NOISE, draw["seed"], "inverse")
    same = replace(data, tau=data.tau_clean + (default.tau - default.tau_clean))
    errors, same_errors = (np.array(score_draw(d, {name: fit}, baseline, [judge])[name][judge.name])
                           for d in (data, same))
    default_errors = np.array(draw[name][judge.name])
    ratio, same_ratio = (float(np.median(e / np.maximum(default_errors, 1e-300)))
                         for e in (errors, same_errors))
    return {"seed": draw["seed"], "errors": errors.tolist(), "default_errors": default_errors.tolist(),
            "median_ratio": ratio, "same_sensor_errors": same_errors.tolist(),
            "same_sensor_median_ratio": same_ratio}


def excitation_comparison(arm: Arm, fit, name: str, baseline, judge: Motion, draws: list[dict],
                          quick: bool) -> tuple[list[Target], dict]:
    """Targets (designed condition <= default's; designed-draw error <= default-draw error on
    the judge, median over joints, median over draws) and the figures behind them; `draws`
    are score_draw's results on the default excitation's data of seeds draw['seed'] with
    `name` scored on `judge`."""
    error = ERROR.format(name=name, seeds=", ".join(str(d["seed"]) for d in draws))
    try:
        designed = design_for(arm, SAMPLES / SAMPLE_RATE, SAMPLE_RATE, seed=DESIGN_SEED,
                              **({"iterations": QUICK_ITERATIONS} if quick else {}))
    except UserError as exc:  # e.g. no collision-free start: the targets are unmeasured
        return [Target(CONDITION, None, 1.0, note=str(exc)),
                Target(error, None, 1.0, "x")], {"error": str(exc)}
    along = [along_design(arm, designed, fit, name, baseline, judge, d) for d in draws]
    ratio = float(np.median([a["median_ratio"] for a in along]))
    targets = [Target(CONDITION, designed.condition, designed.default_condition),
               Target(error, ratio, 1.0, "x")]
    results = {"condition": designed.condition, "default_condition": designed.default_condition,
               "iterations": designed.design.iterations, **along[0], "draws": along,
               "median_over_draws": ratio,
               "same_sensor_median_over_draws": float(np.median(
                   [a["same_sensor_median_ratio"] for a in along]))}
    return targets, results


def markdown(r: dict) -> list[str]:
    """The comparison as a paragraph of the section."""
    if "error" in r:
        return [f"Designed excitation: not designed ({r['error']})."]
    pct = lambda xs: ", ".join(f"{100 * x:.2f} %" for x in xs)  # noqa: E731
    per_draw = "; ".join(f"seed {d['seed']}: {d['median_ratio']:.2f}x ({d['same_sensor_median_ratio']:.2f}x)"
                         for d in r.get("draws", [r]))
    return [f"Designed excitation (`torquebench excite`, D-optimal, {SAMPLES / SAMPLE_RATE:g} s, "
            f"seed {DESIGN_SEED}): condition number {r['condition']:.3g} against the default "
            f"excitation's {r['default_condition']:.3g}. Draw of seed {r['seed']} along it: error "
            f"on the other family's motion {pct(r['errors'])} (along the default: "
            f"{pct(r['default_errors'])}). Error along it / along the default, median over "
            f"joints, per draw: {per_draw}; in brackets with the default draw's sensor noise on "
            "its torque instead of generate's, which grows with the motion."]
