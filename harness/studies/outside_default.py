"""Study `outside_default`: the default identification on data made outside `identify`'s own
path (multisines of another spectrum, a Fourier series of other harmonics; 5 % and 10 %
torque noise), judged on fresh motions against the oracle (harness.identify.outside_default,
). Scored on FRESH_SEEDS (drawn once, no setting chosen on them); the
development draws the issue was bisected on beside them. Quick: one fresh draw.
"""

from __future__ import annotations

from harness.identify.outside_default import (
    DEV_JUDGE,
    DEV_SEEDS,
    FRESH_JUDGE,
    FRESH_SEEDS,
    markdown,
    outside_default,
)
from harness.report.results import Context, SectionResult, Target

MEDIAN_TARGET, JOINT_TARGET = 1.1, 1.6  # x oracle, as the bench's identification section


def run(ctx: Context) -> SectionResult:
    arm = ctx.arm
    fresh = outside_default(arm, FRESH_SEEDS[:1] if ctx.quick else FRESH_SEEDS, FRESH_JUDGE)
    dev = None if ctx.quick else outside_default(arm, DEV_SEEDS, DEV_JUDGE)
    targets = []
    for key, s in fresh["summary"].items():
        targets += [Target(f"default identification on outside {key}: median / oracle (fresh "
                           "draws)", s["median"], MEDIAN_TARGET, "x"),
                    Target(f"default identification on outside {key}: worst joint / oracle "
                           "(fresh draws)", s["worst"], JOINT_TARGET, "x")]
    md = [f"`identify`'s defaults on {arm.label}: data along motions none of the project's "
          "code chose, the first 75 % fitted; judged on three fresh motions (the bench's sines "
          "spectrum and one of each training family) against the oracle fitted on the same "
          "samples (below 1: prior knowledge beat it).", "",
          f"Fresh draws (seeds {', '.join(map(str, fresh['seeds']))}, judge {FRESH_JUDGE}):", "",
          *markdown(fresh)]
    if dev is not None:
        md += ["", f"Development draws (seeds {', '.join(map(str, DEV_SEEDS))}, judge {DEV_JUDGE}; "
               "the issue was bisected on them):", "", *markdown(dev)]
    return SectionResult("\n".join(md), {"fresh": fresh, "development": dev}, [], targets)
