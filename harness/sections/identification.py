"""Bench section "identification": the robot's torque model learned from noisy data.

For any robot: independent draws at 5 % noise (`generate(robot, 4000, 0.05, seed)`, each its
own excitation and noise; the first 75 % trains), identified with every library the robot's
registry entry offers (the kinematic base atoms for any arm; the Lynxmotion also its
prior-knowledge and published libraries) and by the oracle on the same samples
(harness.experiments.identification). All are judged on two motions never fitted: a fresh
run of the project's excitation and a motion of another family (random sines).

Checks (must hold): Pinocchio's RNEA and MuJoCo's inverse dynamics agree on the judge motion
(two implementations of one model); noise-free data are identified exactly by the robot's
default library and by the oracle. Targets: the default library's error within 1.1 x the
oracle's at the median over joints and 1.6 x on every joint, on the motion of the other
family. The model of the default library on the first draw is handed to planning.
"""

from __future__ import annotations

import numpy as np

from harness.data.generate import generate
from harness.experiments.identification import (
    HOLDOUT,
    NOISE,
    SAMPLES,
    closed_form_gap,
    generated_motion,
    ratios,
    score_draw,
    sines_motion,
)
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import load_pinocchio
from harness.robots.torque_models import library_named
from harness.sections.base import Context, Row, SectionResult, Target, check
from harness.sections.paper import EXTRAS
from identification.identify import identify

SEEDS, QUICK_SEEDS, FRESH_SEED = (1, 2, 3, 4, 5), (1, 2), 1005
EXACT = 1e-6  # noise-free held-out relative error
AGREEMENT = 1e-9  # Pinocchio vs MuJoCo, relative to the largest torque
MEDIAN_TARGET, JOINT_TARGET = 1.1, 1.6  # x oracle on the other family's motion


def run(ctx: Context) -> SectionResult:
    robot = ctx.robot.name
    libraries = {name: library_named(name, robot) for name in ctx.robot.libraries}
    default = ctx.robot.libraries[0]
    baseline = PinocchioModel(load_pinocchio(robot))
    judges = [generated_motion(robot, SAMPLES, FRESH_SEED), sines_motion(robot, SAMPLES, FRESH_SEED)]
    clean = generate(robot, SAMPLES, 0.0, 1, "inverse")
    exact = identify(clean.q, clean.qd, clean.qdd, clean.tau, libraries[default], HOLDOUT,
                     clean.tau_clean)
    exact_oracle = score_draw(clean, {}, baseline, judges[:1])["oracle"]["fresh"]
    draws = [score_draw(generate(robot, SAMPLES, NOISE, seed, "inverse"), libraries, baseline,
                        judges) for seed in (QUICK_SEEDS if ctx.quick else SEEDS)]
    model = draws[0]["models"][default]
    gap = closed_form_gap(robot, judges[1])
    checks = [
        check("pinocchio_agrees_with_mujoco", gap <= AGREEMENT,
              f"max |RNEA - mj_inverse| / max |tau| = {gap:.1e} (bar {AGREEMENT:g})"),
        check(f"noise_free_exact_{default}", np.max(exact.heldout_rel_rmse) <= EXACT,
              f"held-out error {np.max(exact.heldout_rel_rmse):.1e} (bar {EXACT:g})"),
        check("noise_free_exact_oracle", max(exact_oracle) <= EXACT,
              f"fresh-motion error {max(exact_oracle):.1e} (bar {EXACT:g})"),
    ]
    summary = {name: {judge: _summary(ratios(draws, name, judge)) for judge in ("fresh", "sines")}
               for name in libraries}
    worst = summary[default]["sines"]
    targets = [
        Target(f"{default} / oracle error, median over joints (worst draw, other excitation)",
               worst["worst_median"], MEDIAN_TARGET, "x"),
        Target(f"{default} / oracle error, worst joint (worst draw, other excitation)",
               worst["worst_joint"], JOINT_TARGET, "x"),
        Target(f"{default} identification CPU time, median over draws",
               float(np.median([d[default]["timing"]["cpu_s"] for d in draws])), 30.0, "s",
               timing=True),
    ]
    errors = np.median([d[default]["sines"] for d in draws], axis=0)
    oracle = np.median([d["oracle"]["sines"] for d in draws], axis=0)
    headline = [Row(f"Identified torque model ({default} library, {NOISE:.0%} noise, {SAMPLES} "
                    "samples): error on a motion of another excitation family, per joint "
                    "(median over draws), against the oracle's",
                    ", ".join(f"{100 * e:.2f} %" for e in errors) + " (oracle "
                    + ", ".join(f"{100 * o:.2f} %" for o in oracle) + ")")]
    results = {"robot": robot, "libraries": list(libraries), "default_library": default,
               "samples": SAMPLES, "noise": NOISE, "closed_form_gap": gap,
               "noise_free_heldout": exact.heldout_rel_rmse.tolist(),
               "oracle_parameters": draws[0]["oracle_parameters"],
               "draws": [{k: v for k, v in d.items() if k != "models"} for d in draws],
               "summary": summary}
    out = SectionResult(_markdown(results, libraries), results, checks, targets, headline,
                        outputs={"model": model, "draws": draws})
    for extra in ctx.robot.extras:
        out.extend(EXTRAS[extra].identification(ctx), extra)
    return out


def _summary(r: np.ndarray) -> dict:
    return {"median_ratio_per_joint": np.median(r, axis=0).tolist(),
            "worst_median": float(np.median(r, axis=1).max()), "worst_joint": float(r.max())}


def _markdown(r: dict, libraries: dict) -> str:
    md = [f"Robot `{r['robot']}`: {len(r['draws'])} draws at {NOISE:.0%} torque noise, "
          f"{SAMPLES} samples each (first {1 - HOLDOUT:.0%} trains). Errors: relative RMS "
          "against the clean torque on two motions never fitted: `fresh` (the project's "
          "excitation, another seed) and `sines` (another family: random sines per joint). "
          f"The oracle fits {r['oracle_parameters']} base parameters + joint terms on the "
          "same samples.", "",
          "| library | features | motion | ratio to the oracle per joint (median over draws) | "
          "worst draw: median / worst joint |", "|---|---|---|---|---|"]
    for name, by_judge in r["summary"].items():
        for judge, s in by_judge.items():
            md.append(f"| {name} | {len(libraries[name])} | {judge} | "
                      + ", ".join(f"{x:.2f}" for x in s["median_ratio_per_joint"])
                      + f" | {s['worst_median']:.2f} / {s['worst_joint']:.2f} |")
    return "\n".join(md)
