"""Bench section: closing the loop on any arm (`bench --robot NAME`).

Plants: the arm with joint effects its declared (Pinocchio) model lacks - viscous friction
on joint 2, Coulomb friction on joint 3, rotor armature on joint 1, a spring on joint 4 -
and a point payload at the flange (harness.closeloop.arm_plants), and the arm as declared
(control: nothing to name). Measured data (`generate(plant, 4000, 0.05, seed 0, "measured")`:
MuJoCo forward simulation tracking an excitation, encoder and torque-sensor noise, states
estimated from the encoder) go through the same loop as the Lynxmotion's
(harness.closeloop.run): residual of the declared model, effects traced and named, held-out
errors against the clean torque before and after. Scored against the plant's true effects
(read from its MJCF, never used by the estimation): each named with its coefficient within
COEFFICIENT_TOL, nothing named on the control plant.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.closeloop.arm_plants import write_arm_variant
from harness.closeloop.plants import Variant
from harness.closeloop.run import run_closeloop
from harness.robots.registry import DEFAULT_ROBOT

SAMPLES = 4000  # measured samples per plant
NOISE = 0.05  # torque noise std / torque std

COEFFICIENT_TOL = 0.10  # relative
PLANTS = (Variant((("viscous", 2, 0.8), ("coulomb", 3, 1.5), ("armature", 1, 0.1),
                   ("spring", 4, 3.0)), payload=1.0, name="effects"),
          Variant(name="control"))


def _score(run) -> dict:
    named = {(t.effect, t.joint): t.coefficient for t in run.result.terms}
    truth = {(t.effect, t.joint): t.coefficient for t in run.truth}
    effects = []
    for (effect, joint), value in truth.items():
        found = named.get((effect, joint))
        error = None if found is None else abs(found - value) / abs(value)
        effects.append({"effect": effect, "joint": joint, "true": value, "named": found,
                        "relative_error": error})
    spurious = [f"{e} j{j}" for (e, j) in named if (e, j) not in truth]
    r = run.result
    return {"effects": effects, "spurious": spurious,
            "error_before": r.error_before.tolist(), "error_after": r.error_after.tolist(),
            "unexplained": bool(r.unexplained),
            "acceptance": {
                "every_true_effect_named_within_10pct": all(
                    e["relative_error"] is not None and e["relative_error"] <= COEFFICIENT_TOL
                    for e in effects),
                "nothing_spurious": not spurious,
                "never_worse_after": bool(np.all(r.error_after <= r.error_before * 1.0001))}}


def run(out_dir: Path, quick: bool = False, robot: str = DEFAULT_ROBOT) -> dict:
    plant_dir = Path(out_dir) / "plants"
    results: dict = {"robot": robot, "plants": {}}
    for variant in PLANTS:
        path = write_arm_variant(robot, variant, plant_dir)
        results["plants"][variant.name] = _score(run_closeloop(path, SAMPLES, NOISE, robot=robot))
    md = [f"Closing the loop on `{robot}` (declared model: Pinocchio on its URDF; measured data "
          f"at {100 * NOISE:g} % noise, {SAMPLES} samples; coefficient bar "
          f"{COEFFICIENT_TOL:.0%}).", "",
          "| plant | effect | joint | true | named | error | ", "|---|---|---|---|---|---|"]
    for name, s in results["plants"].items():
        for e in s["effects"]:
            named = "not named" if e["named"] is None else f"{e['named']:.4g}"
            err = "–" if e["relative_error"] is None else f"{e['relative_error']:.1%}"
            md.append(f"| {name} | {e['effect']} | {e['joint']} | {e['true']:.4g} | {named} | "
                      f"{err} |")
        md.append(f"| {name} | spurious | | | {', '.join(s['spurious']) or 'none'} | |")
    for name, s in results["plants"].items():
        md.append("")
        md.append(f"{name}: held-out error before [{', '.join(f'{x:.2e}' for x in s['error_before'])}]"
                  f", after [{', '.join(f'{x:.2e}' for x in s['error_after'])}]; unexplained: "
                  f"{str(s['unexplained']).lower()}.")
    effects = results["plants"]["effects"]["effects"]
    worst = max((e["relative_error"] for e in effects if e["relative_error"] is not None),
                default=float("nan"))
    within = sum(1 for e in effects
                 if e["relative_error"] is not None and e["relative_error"] <= COEFFICIENT_TOL)
    results["headline"] = {"effects named within 10 %": f"{within} of {len(effects)}",
                           "worst coefficient error": worst}
    return {"markdown": "\n".join(md), "results": results, "figures": []}
