"""The planner's configuration and the bench's motion on an Arm: geometry and limits come
from the arm, nothing from another robot's defaults."""

from __future__ import annotations

import numpy as np

from harness.robots.arm import Arm
from planning.config import PlannerConfig, Scenario, true_energy_config


def planner_config(arm: Arm, **changes) -> PlannerConfig:
    """The default planner configuration on arm, what `plan` and the bench plan with: the
    true energy, several starts and the arrival at rest of planning.config.true_energy_config,
    the arm's links, joint and torque limits, and the solver its registry entry names (IPOPT
    unless said; docs/realtime.md, 'Solvers')."""
    lower, upper = arm.joint_limits
    base = dict(geometry=arm.geometry, lower=lower, upper=upper, torque_limit=arm.torque_limit)
    return true_energy_config(**{**base, **changes}).with_penalty(solver=arm.entry.solver)


def bench_motion(arm: Arm, duration: float = 2.0) -> tuple[Scenario, int]:
    """The arm's planning motion (its registry entry's; else from 30 % to 70 % of every
    joint's range) at rest, without obstacle, and the index (into the geometry's links) of the
    link an obstacle should cross: the registered body's, else the last link."""
    geometry = arm.geometry
    if arm.entry.motion is not None:
        start, goal, body = arm.entry.motion
    else:
        lower, upper = (np.maximum(arm.position_limits[0], -np.pi),
                        np.minimum(arm.position_limits[1], np.pi))
        start, goal, body = tuple(lower + 0.3 * (upper - lower)), \
            tuple(lower + 0.7 * (upper - lower)), ""
    owners = [geometry.bodies[i] for i, _ in geometry.links]
    link = owners.index(body) if body in owners else len(owners) - 1
    return Scenario(tuple(map(float, start)), tuple(map(float, goal)), duration, None,
                    (0.0,) * geometry.dof), link
