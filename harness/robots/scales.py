"""The scales of a robot that bound what the measured loop may name of it
(identification.closeloop.verdicts.ranges): its torque and speed limits, joint spans and mass, the
data's torques and speeds where it declares none."""

from __future__ import annotations

import numpy as np

from harness.robots.arm import Arm
from identification.closeloop.verdicts.ranges import Scales


def robot_scales(arm: Arm, runs: list[tuple]) -> Scales:
    """The scales that bound arm's named coefficients (identification.closeloop.verdicts.ranges): its
    torque and speed limits, joint spans and mass, the runs' torques and speeds where it
    declares none."""
    tau, qd, q = (np.concatenate([r[i] for r in runs]) for i in (3, 1, 0))
    mass = float(sum(body.mass for body in arm.pinocchio.inertias))
    return Scales.of(arm.torque_limit, arm.speed_bounds, *arm.position_limits, mass, tau, qd, q)
