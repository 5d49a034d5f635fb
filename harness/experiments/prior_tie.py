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
from harness.experiments.identification import (
    HOLDOUT,
    SAMPLES,
    oracle_design,
    oracle_fit,
    perturbed_nominal,
    sines_motion,
)
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import load_pinocchio
from harness.robots.torque_models import robot_library
from identification.metrics import rel_error
from identification.physical import LAMBDAS, choose_weight, fit_physical

TIES = (0.001, 0.005, 0.01, 0.02, 0.05, 0.1)
# draws and judge motions the bench never scores (its seeds: 101-105, 201-203, 301-303, 401,
# 402, judge 1005): one set to choose on, another to re-score on
CHOOSE = {"seeds": {0.02: (611, 612), 0.05: (601, 602, 603, 604), 0.10: (621, 622)}, "judge": 1601}
RESCORE = {"seeds": {0.02: (631, 632), 0.05: (641, 642, 643, 644), 0.10: (651, 652)}, "judge": 1602}


def draw_ratios(robot: str, level: float, seed: int, judge, baseline, library) -> dict:
    """Per ridge weight, the fit's error / the oracle's on the judge (dof,); the weights'
    validation errors."""
    data = generate(robot, SAMPLES, level, seed, "inverse")
    n = int(round(SAMPLES * (1 - HOLDOUT)))
    oracle, _ = oracle_fit(baseline, data, n)
    floor = rel_error(oracle.predict(oracle_design(baseline, judge.q, judge.qd, judge.qdd)),
                      judge.tau_clean)
    atoms = library.evaluate_every(data.q[:n], data.qd[:n], data.qdd[:n])
    judged = library.evaluate_every(judge.q, judge.qd, judge.qdd)
    nominal = perturbed_nominal(baseline, seed)
    errors = fit_physical(atoms, data.qd[:n], data.tau[:n], nominal).validation["lambda_errors"]
    ratios = {}
    for lam in LAMBDAS:
        fit = fit_physical(atoms, data.qd[:n], data.tau[:n], nominal, lambdas=(lam,))
        ratios[lam] = rel_error(fit.torque(judged, judge.qd, offsets=False), judge.tau_clean) / floor
    return {"errors": errors, "ratios": ratios}


def scan(robot: str, draws: dict = CHOOSE, ties=TIES) -> dict:
    """Per margin: the worst draw's median ratio over joints and the worst joint's ratio."""
    baseline, library = PinocchioModel(load_pinocchio(robot)), robot_library(robot)
    judge = sines_motion(robot, SAMPLES, draws["judge"])
    made = [draw_ratios(robot, level, seed, judge, baseline, library)
            for level, seeds in draws["seeds"].items() for seed in seeds]
    out = {}
    for tie in ties:
        picked = np.array([d["ratios"][choose_weight(LAMBDAS, d["errors"], tie)] for d in made])
        out[tie] = {"worst_median": float(np.median(picked, axis=1).max()),
                    "worst_joint": float(picked.max())}
    return out
