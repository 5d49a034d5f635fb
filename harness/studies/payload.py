"""Study `payload`: the load a robot carries, named by `closeloop --data` on simulated 6- and
7-joint arms (the in-repo targets).

Per arm (UR5, Panda): the bench's payload case (harness.closeloop.payload_case: a 2.7 kg
gripper-like load for an 18 kg arm on the flange, MuJoCo inverse dynamics with the friction
the model declares, 5 % torque noise and generate's sensor bias, seed 8123 drawn once),
without and with dry friction that grows with the load on the wrist (0.05 N m per N m,
the last three joints), and the arm's own plant without a load (the control: no payload and
no rigid-body correction may be named). Scored against the plant's own last body, which the
loop never sees: the mass within 3 %, the centre of mass within 1 cm, the loaded run's RMS
error after the loop within 1.3x the declared model's on the same motion unloaded.

The quick form (the smoke test): the UR5 with the wrist's load friction, on 1500 samples.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from harness.closeloop.payload_case import (
    LOAD_FRICTION,
    SAMPLES,
    SEEDS,
    control_case,
    payload_case,
    payload_checks,
    payload_markdown,
    payload_targets,
)
from harness.report.results import Context, SectionResult, check
from harness.robots.arm import Arm

ROBOTS = ("ur5", "panda")
QUICK_SAMPLES = 1500  # on 1000 (750 trained) the rigid-body correction is named beside the load
# and takes 7.6 % of its mass (UR5 with the wrist's load friction); 0.04 % on 1500


def run(ctx: Context) -> SectionResult:
    robots, samples = (ROBOTS[:1], QUICK_SAMPLES) if ctx.quick else (ROBOTS, SAMPLES)
    frictions = (LOAD_FRICTION,) if ctx.quick else (0.0, LOAD_FRICTION)
    cases, controls, md = [], {}, []
    checks, targets = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for name in robots:
            arm = Arm.of(name)
            for mu in frictions:
                for seed in SEEDS[:1] if ctx.quick else SEEDS:  # draws no setting chose
                    case = payload_case(arm, Path(tmp) / f"{name}_{mu:g}_{seed}", mu, samples,
                                        seed)
                    cases.append(case)
                    md += [payload_markdown(case), ""]
                    checks += payload_checks(case)
                    if not ctx.quick:
                        targets += payload_targets(case)
            if not ctx.quick:
                controls[name] = control_case(arm, Path(tmp) / f"{name}_control", samples)
                md += [f"Control, {name} without a load (same seed): body-level effects named: "
                       f"{', '.join(controls[name]) or 'none'}.", ""]
                checks.append(check(f"control.{name}.no_payload_named", not controls[name],
                                    ", ".join(controls[name]) or "none named"))
    return SectionResult("\n".join(md).rstrip(), {"cases": cases, "controls": controls},
                         checks, targets)
