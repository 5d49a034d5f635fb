"""Study `pushes`: the world pushing a robot, told from the robot by `closeloop --data`
the Lynxmotion, the UR5 and the Panda, each pushed three times a run on three
draws, alone and beside a load and viscous friction (harness.closeloop.push_case).

Reports the detection rate, false events per minute (on the pushed runs and on the same runs
unpushed), the onset errors, and the load and the friction named with the pushes against
without, beside the same loop run without looking for events. The seeds were drawn once on
2026-12-07 (numpy.random.default_rng().integers(10_000)) after every setting of the events
stage (identification.closeloop.events) was fixed; none was chosen on them.

The quick form (the smoke test): the Lynxmotion on one draw, 2000 samples a run.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from harness.closeloop.push_case import push_case
from harness.closeloop.push_scores import push_markdown, push_targets, summary
from harness.report.results import Context, SectionResult, check
from harness.robots.arm import Arm

ROBOTS = ("lynxmotion", "ur5", "panda")
SEEDS = (3083, 4901, 9221)  # drawn once on 2026-12-07, see the docstring
QUICK_SAMPLES = 2000


def run(ctx: Context) -> SectionResult:
    robots, seeds = (ROBOTS[:1], SEEDS[:1]) if ctx.quick else (ROBOTS, SEEDS)
    samples = QUICK_SAMPLES if ctx.quick else None
    cases = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in robots:
            for seed in seeds:
                options = {} if samples is None else {"samples": samples}
                if seed == seeds[0]:
                    options["figure"] = ctx.figures_dir / f"pushes_{name}.png"
                cases.append(push_case(Arm.of(name), seed, Path(tmp) / f"{name}_{seed}",
                                       **options))
    s = summary(cases)
    md = ["Pushes on simulated arms (`closeloop --data` on two pushed training runs and a pushed "
          "held-out run; 5 % torque noise, states estimated from the encoder).", "",
          push_markdown(cases, s)]
    checks = [check("pushes.never_worse_after", not s["worse_joints"],
                    "held-out error after <= before on every joint of every pushed loop")]
    figures = [ctx.figures_dir / c["figure"] for c in cases if "figure" in c]
    return SectionResult("\n".join(md), {"cases": cases, "summary": s}, checks,
                         push_targets(s, f"{', '.join(robots)}; seeds "
                                         f"{', '.join(map(str, seeds))}"), figures=figures)
