"""Study `prior_tie`: the consistent fit's TIE margin (identification.physical.choose_weight)
chosen on draws and a judge motion no bench section scores, every margin re-scored on fresh
draws and a fresh judge (harness.identify.prior_tie). Robots: the UR5 and the two light
wristed arms the margin was raised for (xArm7, SO-101, example-robot-data's URDFs). Quick:
the UR5, one draw each way.
"""

from __future__ import annotations

from harness.identify.prior_tie import tie_study
from harness.report.results import Context, SectionResult, Target, check
from harness.robots.arm import Arm
from harness.robots.registry import erd_robots_dir

ARMS = ("xarm_description/urdf/xarm7.urdf", "so_arm_description/urdf/so101.urdf")
JOINT_TARGET = 1.6  # x oracle, the bench's identification bar


def arms(quick: bool) -> list[Arm]:
    names = ["ur5"] if quick else ["ur5", *(str(erd_robots_dir() / a) for a in ARMS)]
    return [Arm.of(name) for name in names]


def run(ctx: Context) -> SectionResult:
    r = tie_study(arms(ctx.quick), ctx.quick)
    md = ["Each draw: `generate`'s excitation (seeds 601-652, never scored by a bench section), "
          "a perturbed URDF prior, the fit at every ridge weight; each margin picks its weight "
          "from the same validation errors. Judged on random sines (judge seeds 1601 to "
          "choose, 1602 to re-score) against the oracle fitted on the same samples.", "",
          "Best margins on the choosing draws (equal to 0.01x): "
          + ", ".join(f"{t:g}" for t in r["best"]) + f"; the code's TIE: {r['code']:g}.", "",
          "| robot | draws | margin | worst draw's median / oracle | worst joint / oracle |",
          "|---|---|---|---|---|"]
    for name in ("chosen_on", "rescored"):
        for robot, by_tie in r[name].items():
            for tie, s in by_tie.items():
                md.append(f"| {robot.rsplit('/', 1)[-1]} | {name.replace('_', ' ')} | {tie:g} | "
                          f"{s['worst_median']:.2f} | {s['worst_joint']:.2f} |")
    worst = max(by_tie[r["code"]]["worst_joint"] for by_tie in r["rescored"].values())
    # one draw each way (quick) chooses nothing: the check is the full study's
    best = ", ".join(f"{t:g}" for t in r["best"])
    checks = [] if ctx.quick else [check("code_tie_among_the_best", r["code"] in r["best"],
                                         f"best on unscored draws {best}, code {r['code']:g}")]
    targets = [Target("TIE re-scored on fresh draws: worst joint / oracle over robots", worst,
                      JOINT_TARGET, "x")]
    return SectionResult("\n".join(md), r, checks, targets)
