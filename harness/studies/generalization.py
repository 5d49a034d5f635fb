"""Study `generalization`: identification on data made along another excitation than the
project's (harness.identify.generalization), judged on a fresh motion of the project's
own family, against the oracle; the UR5 and the Panda (registered) and the xArm7 and the
Unitree Z1 (example-robot-data's URDFs), with noise of each joint's torque std and with one
sensor noise in N m on every joint. Quick: the UR5 on one draw, the first.
"""

from __future__ import annotations

from harness.identify.generalization import (
    NOISE_MODELS,
    QUICK_SEEDS,
    SEEDS,
    SENSOR_SEEDS,
    generalization,
    markdown,
)
from harness.identify.scoring import ORACLE
from harness.report.results import Context, SectionResult, Target
from harness.robots.arm import Arm
from harness.robots.registry import erd_robots_dir

MEDIAN_TARGET, JOINT_TARGET = 1.1, 1.6  # x oracle, as the bench's identification section
EXAMPLE_ARMS = ("xarm_description/urdf/xarm7.urdf", "z1_description/urdf/z1.urdf")


def robots(quick: bool) -> list[str]:
    """The arms studied: the UR5 alone when quick."""
    if quick:
        return ["ur5"]
    return ["ur5", "panda", *(str(erd_robots_dir() / path) for path in EXAMPLE_ARMS)]


def run(ctx: Context) -> SectionResult:
    models = ("torque",) if ctx.quick else tuple(NOISE_MODELS)
    seeds = {"torque": QUICK_SEEDS if ctx.quick else SEEDS, "sensor": SENSOR_SEEDS}
    results = [generalization(Arm.of(robot), seeds[noise_model], noise_model)
               for noise_model in models for robot in robots(ctx.quick)]
    targets = []
    for r in results:
        name = r["robot"].rsplit("/", 1)[-1] + ("" if r["noise_model"] == "torque" else
                                                f" ({r['noise_model']} noise)")
        for fit, by_judge in r["summary"].items():
            worst = by_judge["fresh"]
            targets += [Target(f"{name}, {fit} / oracle, median over joints (worst draw, fresh "
                               "motion)", worst["worst_median"], MEDIAN_TARGET, "x"),
                        Target(f"{name}, {fit} / oracle, worst joint (worst draw, fresh motion)",
                               worst["worst_joint"], JOINT_TARGET, "x")]
    md = ["Data along random sines of another spectrum than the bench's (up to 2 Hz, half "
          "of each joint's range), 5 % torque noise with a sensor offset, 4000 samples (the "
          "first 75 % fitted); the consistent fit given a URDF with inertias off by up to "
          "30 % and centres of mass by 2 cm. Judged on a fresh run of `generate`'s excitation "
          "(`fresh`) and on random sines of the bench's spectrum (`sines`); ratios to the oracle "
          f"({ORACLE}) fitted on the same samples: below 1, prior knowledge beat it. Noise "
          "models: " + "; ".join(f"{k}, {v}" for k, v in NOISE_MODELS.items())
          + " (not when quick).", "",
          *markdown(results)]
    return SectionResult("\n".join(md), {"robots": results}, [], targets)
