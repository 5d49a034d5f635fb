"""The consistent fit's prior metric, ridge against entropic (identify --prior-metric),
re-decided on fresh draws.

Per draw: `generate`'s excitation at a noise level (the bench's kind of draw), the first 75 %
fitted by the consistent fit (plausible, identify's default) with each metric under two
priors: the URDF perturbed as a roboticist's is wrong (perturbed_nominal, seeded by the
draw: masses and inertias x0.7-1.3, centres of mass moved 2 cm) and the URDF itself, here
the truth; judged on a fresh motion of random sines against the oracle fitted on the same
samples. SEEDS and JUDGE were drawn once (numpy.random.default_rng().integers(10_000),
2026-11-28); no setting was chosen on them.
"""

from __future__ import annotations

from harness.data.generate import generate
from harness.identify.scoring import (
    SAMPLES,
    Fit,
    perturbed_nominal,
    ratio_summary,
    score_draw,
    sines_motion,
)
from harness.robots.arm import Arm
from identification.physical import PRIOR_METRICS
from identification.regression.consistent import ConsistentRegressor

SEEDS, JUDGE = (4913, 4430, 9686), 8884  # drawn 2026-11-28
LEVELS = (0.02, 0.05)
PRIORS = ("perturbed URDF", "URDF (the truth)")


def fits(arm: Arm) -> dict[str, Fit]:
    """Each metric under each prior, named 'metric, prior'."""
    baseline, ellipsoids = arm.nominal, arm.ellipsoids
    truth = baseline.atom_parameters()

    def fit(metric: str, prior: str) -> Fit:
        def regressor(seed: int) -> ConsistentRegressor:
            nominal = perturbed_nominal(baseline, seed) if prior == PRIORS[0] else truth
            return ConsistentRegressor(nominal, ellipsoids=ellipsoids, prior_metric=metric)
        return Fit(arm.library, regressor)

    return {f"{metric}, {prior}": fit(metric, prior) for prior in PRIORS for metric in PRIOR_METRICS}


def prior_metric_study(arm: Arm, seeds=SEEDS, levels=LEVELS, judge: int = JUDGE) -> dict:
    """Per noise level and fit, the ratio summary to the oracle on the judge motion over the
    draws; the draws' per-joint errors."""
    candidates = fits(arm)
    motion = sines_motion(arm, SAMPLES, judge)
    out = {"robot": arm.reference, "seeds": list(seeds), "judge": judge, "levels": {}}
    for level in levels:
        draws = [score_draw(generate(arm, SAMPLES, level, seed, "inverse"), candidates,
                            arm.nominal, [motion]) for seed in seeds]
        out["levels"][f"{level:g}"] = {
            "summary": {name: ratio_summary(draws, name, motion.name) for name in candidates},
            "draws": [{k: v for k, v in d.items() if k != "models"} for d in draws]}
    return out


def markdown(results: list[dict]) -> list[str]:
    """One row per robot, level and prior: ridge's and entropic's worst median / worst joint."""
    md = ["| robot | noise | prior | ridge: worst median / worst joint | entropic: worst median "
          "/ worst joint |", "|---|---|---|---|---|"]
    for r in results:
        for level, by in r["levels"].items():
            for prior in PRIORS:
                cells = [by["summary"][f"{m}, {prior}"] for m in PRIOR_METRICS]
                md.append(f"| {r['robot'].rsplit('/', 1)[-1]} | {float(level):.0%} | {prior} | "
                          + " | ".join(f"{c['worst_median']:.2f} / {c['worst_joint']:.2f}"
                                       for c in cells) + " |")
    return md
