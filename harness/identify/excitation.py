"""The designed excitation (`torquebench excite`) against generate's default, for the bench.

For the bench's robot: the excitation designed (excite's default criterion) over the draws'
duration (SAMPLES at SAMPLE_RATE, seed 1) and its condition number (the identification's
atoms and offsets, columns normalized) against the default excitation's; then draws
generated along the designed excitation and along the default one (same samples, noise and
seed), identified with the default library and judged on a motion of another family.

The draws and the judge motion are fresh: FRESH_DRAWS and FRESH_JUDGE were drawn once and
never used while choosing the excitation's settings (its top frequency and its criterion
were chosen on the bench's draws 101-103 and judge 1005, which therefore do not score it).

Two noises, both reported and both targets: generate's (NOISE x each dataset's own torque
std: a faster motion gets more noise) and one sensor's (the default draw's noise samples on
the design's torque: a sensor's noise does not grow with the motion).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from harness.data.excite import design_for
from harness.data.generate import SAMPLE_RATE, generate
from harness.errors import UserError
from harness.identify.scoring import NOISE, SAMPLES, Motion, score_draw, sines_motion
from harness.report.results import Target
from harness.robots.arm import Arm

DESIGN_SEED = 1
# drawn once on 2026-11-28 (numpy.random.default_rng().integers(10_000, size=6), then 5
# more for ten draws: the spread between draws is wide, 0.5x to 2x) and written here; no
# setting of the excitation or of the identification was chosen on them
FRESH_DRAWS = (2999, 6087, 3615, 3916, 8819, 4322, 4608, 9075, 7296, 555)
QUICK_FRESH_DRAWS = (2999,)
FRESH_JUDGE = 4512
CONDITION = ("designed excitation's condition number (atoms + offsets, columns normalized), "
             "against the default excitation's")
ERROR = ("{name} error on the other excitation's motion, trained along the designed excitation "
         "/ along the default, {noise} (median over joints; median over the fresh draws of "
         "seeds {seeds}, judge motion seed {judge})")
NOISES = {"median_ratio": "generate's noise (5 % of each dataset's own torque std)",
          "same_sensor_median_ratio": "one sensor's noise (the default draw's noise samples)"}
QUICK_ITERATIONS = 20  # the design's SLSQP iterations in --quick
CONVERGED = "excitation design: SLSQP converged to an optimum (1) rather than its iteration limit (0)"


def along_design(arm: Arm, designed, fit, name: str, baseline, judge: Motion, seed: int) -> dict:
    """The draw of seed generated along the design and along the default excitation: errors
    per joint, and their median ratio, with generate's noise and with the same sensor's (the
    default draw's noise on the design's torque: a sensor's noise does not grow with the
    motion, generate's does)."""
    data = generate(arm, SAMPLES, NOISE, seed, "inverse", excitation=designed.trajectory)
    default = generate(arm, SAMPLES, NOISE, seed, "inverse")
    same = replace(data, tau=data.tau_clean + (default.tau - default.tau_clean))
    errors, same_errors, default_errors = (
        np.array(score_draw(d, {name: fit}, baseline, [judge])[name][judge.name])
        for d in (data, same, default))
    ratio, same_ratio = (float(np.median(e / np.maximum(default_errors, 1e-300)))
                         for e in (errors, same_errors))
    return {"seed": seed, "errors": errors.tolist(), "default_errors": default_errors.tolist(),
            "median_ratio": ratio, "same_sensor_errors": same_errors.tolist(),
            "same_sensor_median_ratio": same_ratio}


def excitation_comparison(arm: Arm, fit, name: str, baseline, quick: bool
                          ) -> tuple[list[Target], dict]:
    """Targets (designed condition <= default's; designed-draw error <= default-draw error on
    the fresh judge motion, median over joints, median over the fresh draws, under each
    noise) and the figures behind them."""
    seeds = QUICK_FRESH_DRAWS if quick else FRESH_DRAWS
    judge = sines_motion(arm, SAMPLES, FRESH_JUDGE)
    errors = {key: ERROR.format(name=name, noise=noise, seeds=", ".join(map(str, seeds)),
                                judge=FRESH_JUDGE) for key, noise in NOISES.items()}
    try:
        designed = design_for(arm, SAMPLES / SAMPLE_RATE, SAMPLE_RATE, seed=DESIGN_SEED,
                              **({"iterations": QUICK_ITERATIONS} if quick else {}))
    except UserError as exc:  # e.g. no collision-free start: the targets are unmeasured
        return [Target(CONDITION, None, 1.0, note=str(exc)),
                *(Target(label, None, 1.0, "x") for label in errors.values()),
                Target(CONVERGED, None, 1.0, lower_is_better=False)], {"error": str(exc)}
    along = [along_design(arm, designed, fit, name, baseline, judge, seed) for seed in seeds]
    ratios = {key: float(np.median([a[key] for a in along])) for key in NOISES}
    design = designed.design
    targets = [Target(CONDITION, designed.condition, designed.default_condition,
                      note="" if design.converged else "not a converged optimum"),
               *(Target(errors[key], ratios[key], 1.0, "x") for key in NOISES),
               Target(CONVERGED, float(design.converged), 1.0, lower_is_better=False,
                      note=design.convergence())]
    results = {"condition": designed.condition, "default_condition": designed.default_condition,
               "iterations": designed.design.iterations,
               # SLSQP's last exit status and message, and whether it left its random start
               "optimizer_status": designed.design.status,
               "optimizer_message": designed.design.message,
               "stuck_at_start": designed.design.stuck, "converged": designed.design.converged,
               "convergence": designed.design.convergence(), **along[0], "draws": along,
               "judge_seed": FRESH_JUDGE, "median_over_draws": ratios["median_ratio"],
               "same_sensor_median_over_draws": ratios["same_sensor_median_ratio"]}
    return targets, results


def markdown(r: dict) -> list[str]:
    """The comparison as a paragraph of the section."""
    if "error" in r:
        return [f"Designed excitation: not designed ({r['error']})."]
    pct = lambda xs: ", ".join(f"{100 * x:.2f} %" for x in xs)  # noqa: E731
    per_draw = "; ".join(f"seed {d['seed']}: {d['median_ratio']:.2f}x ({d['same_sensor_median_ratio']:.2f}x)"
                         for d in r.get("draws", [r]))
    return [f"Designed excitation (`torquebench excite`, D-optimal, {SAMPLES / SAMPLE_RATE:g} s, "
            f"seed {DESIGN_SEED}; {r.get('convergence', '')}): condition number "
            f"{r['condition']:.3g} against the default "
            f"excitation's {r['default_condition']:.3g}. Fresh draws (seeds no setting was "
            f"chosen on), judged on a fresh motion of another family (seed {r.get('judge_seed')}). "
            f"Draw of seed {r['seed']} along it: error "
            f"on the other family's motion {pct(r['errors'])} (along the default: "
            f"{pct(r['default_errors'])}). Error along it / along the default, median over "
            f"joints, per draw: {per_draw}; in brackets with the default draw's sensor noise on "
            "its torque instead of generate's, which grows with the motion."]
