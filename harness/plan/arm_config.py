"""The planner's configuration and the motions planned on an Arm: geometry and limits come
from the arm, nothing from another robot's defaults; `plan`'s default obstacle path."""

from __future__ import annotations

import dataclasses

import numpy as np

from harness.robots.arm import Arm
from planning.config import PlannerConfig, Scenario, true_energy_config
from planning.formulation.obstacle import LinearObstacle

DURATION = 2.0  # s: the motion's time in `plan` and the bench
# `plan`'s obstacle path on a robot that registers none (its centre at t = 0 and at the end,
# m): the paper scenario's, the Lynxmotion's registered path (with a notice: harness.plan.messages)
OBSTACLE_PATH = ((0.15, 0.40, 0.22), (0.18, -0.35, 0.28))


def default_obstacle(duration: float = DURATION, samples: int | None = None,
                     arm: Arm | None = None) -> LinearObstacle:
    """The arm's registered obstacle path (else OBSTACLE_PATH) over `duration` (s), in
    `samples` samples (default LinearObstacle's)."""
    path = (arm.entry.obstacle if arm is not None else None) or OBSTACLE_PATH
    return LinearObstacle(*path, duration, **({} if samples is None else {"samples": samples}))


def planner_config(arm: Arm, **changes) -> PlannerConfig:
    """The default planner configuration on arm, what `plan` and the bench plan with: the
    true energy, several starts and the arrival at rest of planning.config.true_energy_config,
    the arm's links, joint and torque limits, and the solver its registry entry names (IPOPT
    unless said; docs/realtime.md, 'Solvers')."""
    lower, upper = arm.joint_limits
    base = dict(geometry=arm.geometry, lower=lower, upper=upper, torque_limit=arm.torque_limit)
    return true_energy_config(**{**base, **changes}).with_penalty(solver=arm.entry.solver)


def motion_scenario(arm: Arm, duration: float = DURATION) -> Scenario:
    """The arm's registered motion (bench_motion) past the default obstacle path: on the
    Lynxmotion, the paper's scenario."""
    return dataclasses.replace(bench_motion(arm, duration)[0],
                               obstacle=default_obstacle(duration, arm=arm))


def bench_motion(arm: Arm, duration: float = DURATION) -> tuple[Scenario, int]:
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
