"""The designed excitation's criteria side by side, at the same sensor noise.

`python -m harness.identify.excitation_criteria ROBOT`: per criterion of `excite`
(identification.excitation.criteria.CRITERIA), the design over the bench's duration (seed 1),
its condition number against the default excitation's, and for draws 101-103 the robot's
default fit's error on the bench's sines motion, trained along the design / along the
default excitation (median over joints). Two noise models: the bench's (a fraction of each
dataset's own torque std) and the same sensor (the default draw's noise samples added to the
design's clean torque: a torque sensor's noise does not grow with the motion).
"""

from __future__ import annotations

import sys

from harness.data.excite import design_for
from harness.data.generate import SAMPLE_RATE
from harness.identify.excitation import along_design
from harness.identify.fits import arm_identification
from harness.identify.scoring import SAMPLES, fixed_fit, sines_motion
from harness.robots.arm import Arm
from identification.excitation.criteria import CRITERIA

# the development draws the criterion was chosen on (the bench scores the design on fresh
# ones: harness.identify.excitation.FRESH_DRAWS)
SEEDS, JUDGE = (101, 102, 103), 1005


def compare(arm: Arm) -> dict:
    """Per criterion: conditions and the error ratios per draw under both noise models."""
    baseline, judge = arm.nominal, sines_motion(arm, SAMPLES, JUDGE)
    fit = fixed_fit(*arm_identification(arm))
    out = {}
    for criterion in CRITERIA:
        designed = design_for(arm, SAMPLES / SAMPLE_RATE, SAMPLE_RATE, seed=1, criterion=criterion)
        rows = []
        for seed in SEEDS:
            r = along_design(arm, designed, fit, "fit", baseline, judge, seed)
            rows.append({"seed": seed, "bench": r["median_ratio"],
                         "same": r["same_sensor_median_ratio"]})
        out[criterion] = {"condition": designed.condition,
                          "default_condition": designed.default_condition, "draws": rows}
    return out


if __name__ == "__main__":
    for criterion, r in compare(Arm.of(sys.argv[1] if len(sys.argv) > 1 else "lynxmotion")).items():
        ratios = "; ".join(f"seed {d['seed']}: {d['bench']:.2f}x bench noise, {d['same']:.2f}x "
                           "same sensor" for d in r["draws"])
        print(f"{criterion}: condition {r['condition']:.3g} (default {r['default_condition']:.3g}); "
              f"error / default's: {ratios}")
