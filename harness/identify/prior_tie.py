"""The consistent fit's TIE margin (identification.physical.choose_weight), chosen on draws
and a judge motion no bench section scores, then re-scored on fresh ones.

Per draw (generate's excitation at a noise level, a perturbed URDF prior seeded by the draw,
the first 75 % fitted) the fit is made at every ridge weight alone, once each, and judged on
a motion of another family (random sines) against the oracle fitted on the same samples;
each candidate margin then picks its weight from the same validation errors, so every
margin is scored on the same fits.
"""

from __future__ import annotations

import numpy as np

from harness.data.generate import generate
from harness.identify.scoring import (
    HOLDOUT,
    SAMPLES,
    oracle_design,
    oracle_fit,
    perturbed_nominal,
    sines_motion,
)
from harness.robots.arm import Arm
from identification.metrics import rel_error
from identification.physical import LAMBDAS, TIE, choose_weight, fit_physical
from identification.regression.consistent import ConsistentRegressor

TIES = (0.001, 0.005, 0.01, 0.02, 0.05, 0.1)
# draws and judge motions the bench never scores (its seeds: 101-105, 201-203, 301-303, 401,
# 402, judge 1005): one set to choose on, another to re-score on
CHOOSE = {"seeds": {0.02: (611, 612), 0.05: (601, 602, 603, 604), 0.10: (621, 622)}, "judge": 1601}
RESCORE = {"seeds": {0.02: (631, 632), 0.05: (641, 642, 643, 644), 0.10: (651, 652)}, "judge": 1602}


def draw_ratios(arm: Arm, level: float, seed: int, judge, baseline, library,
                ellipsoids=None) -> dict:
    """Per ridge weight, the fit's error / the oracle's on the judge (dof,); the weights'
    validation errors. ellipsoids: the bodies' bounds (identify's plausible default)."""
    data = generate(arm, SAMPLES, level, seed, "inverse")
    n = int(round(SAMPLES * (1 - HOLDOUT)))
    oracle, _ = oracle_fit(baseline, data, n)
    floor = rel_error(oracle.predict(oracle_design(baseline, judge.q, judge.qd, judge.qdd)),
                      judge.tau_clean)
    atoms = library.evaluate_every(data.q[:n], data.qd[:n], data.qdd[:n])
    judged = library.evaluate_every(judge.q, judge.qd, judge.qdd)
    nominal = perturbed_nominal(baseline, seed)
    held = ConsistentRegressor(nominal, ellipsoids=ellipsoids).bounds(library.dof)
    bounds = None if held is None else [b.matrix for b in held]
    errors = fit_physical(atoms, data.qd[:n], data.tau[:n], nominal,
                          bounds=bounds).validation["lambda_errors"]
    ratios = {}
    for lam in LAMBDAS:
        fit = fit_physical(atoms, data.qd[:n], data.tau[:n], nominal, lambdas=(lam,), bounds=bounds)
        ratios[lam] = rel_error(fit.torque(judged, judge.qd, offsets=False), judge.tau_clean) / floor
    return {"errors": errors, "ratios": ratios}


def scan(arm: Arm, draws: dict = CHOOSE, ties=TIES) -> dict:
    """Per margin: the worst draw's median ratio over joints and the worst joint's ratio."""
    baseline, library = arm.nominal, arm.library
    judge = sines_motion(arm, SAMPLES, draws["judge"])
    made = [draw_ratios(arm, level, seed, judge, baseline, library, arm.ellipsoids)
            for level, seeds in draws["seeds"].items() for seed in seeds]
    out = {}
    for tie in ties:
        picked = np.array([d["ratios"][choose_weight(LAMBDAS, d["errors"], tie)] for d in made])
        out[tie] = {"worst_median": float(np.median(picked, axis=1).max()),
                    "worst_joint": float(picked.max())}
    return out


def best_ties(scans: list[dict], ties=TIES) -> list[float]:
    """The margins whose worst joint over every robot's draws is smallest, and among those
    the worst median (to 0.01x: below that the draws cannot tell them apart)."""
    def score(t):
        return (round(max(s[t]["worst_joint"] for s in scans), 2),
                round(max(s[t]["worst_median"] for s in scans), 2))
    best = min(score(t) for t in ties)
    return [t for t in ties if score(t) == best]


def tie_study(arms, quick: bool = False) -> dict:
    """The margins best on CHOOSE's draws and judge over arms, every margin re-scored on
    RESCORE's; and whether the code's TIE is among the best."""
    pick = {"seeds": {0.05: (601,)}, "judge": CHOOSE["judge"]} if quick else CHOOSE
    again = {"seeds": {0.05: (641,)}, "judge": RESCORE["judge"]} if quick else RESCORE
    chosen_on = {arm.reference: scan(arm, pick) for arm in arms}
    rescored = {arm.reference: scan(arm, again) for arm in arms}
    return {"robots": list(chosen_on), "ties": list(TIES), "best": best_ties(list(chosen_on.values())),
            "code": TIE, "chosen_on": chosen_on, "rescored": rescored}
