"""Study `prior_metric`: the consistent fit's prior metric, ridge (the default) against
entropic, under a perturbed URDF prior and under the URDF as the truth, on fresh draws
(harness.identify.prior_metric). Robots: the Lynxmotion, the UR5 and
example-robot-data's Kinova (the arm the entropic metric was added for). Quick: the
Lynxmotion, one draw at 5 %.
"""

from __future__ import annotations

from harness.identify.prior_metric import LEVELS, SEEDS, markdown, prior_metric_study
from harness.report.results import Context, SectionResult, Target
from harness.robots.arm import Arm
from harness.robots.registry import erd_robots_dir

JOINT_TARGET = 1.6  # x oracle, the bench's identification bar
KINOVA = "kinova_description/robots/kinova.urdf"


def run(ctx: Context) -> SectionResult:
    if ctx.quick:
        results = [prior_metric_study(Arm.of("lynxmotion"), SEEDS[:1], (0.05,))]
    else:
        results = [prior_metric_study(Arm.of(name), SEEDS, LEVELS)
                   for name in ("lynxmotion", "ur5", str(erd_robots_dir() / KINOVA))]
    targets = [Target(f"{r['robot'].rsplit('/', 1)[-1]} at {float(level):.0%}, {name}: worst "
                      "joint / oracle", s["worst_joint"], JOINT_TARGET, "x")
               for r in results for level, by in r["levels"].items()
               for name, s in by["summary"].items()]
    md = ["`generate`'s excitation, the first 75 % fitted by the consistent fit (plausible) with "
          f"each prior metric, under a perturbed URDF prior and under the URDF itself (the "
          f"truth here); judged on random sines (judge seed {results[0]['judge']}) against the "
          "oracle fitted on the same samples; worst draw's median over joints / worst joint. "
          f"Seeds {', '.join(map(str, results[0]['seeds']))}, drawn once, no setting chosen "
          "on them.", "", *markdown(results)]
    return SectionResult("\n".join(md), {"robots": results}, [], targets)
