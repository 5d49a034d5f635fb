"""Start points of the global search (planning.globalsearch.multistart): the motion to the
goal swung round the obstacle each way (detours), seeded random starts (planning.starts)
and the last plan's shape (the warm start)."""

from __future__ import annotations

import numpy as np

from planning.config import PlannerConfig
from planning.formulation.problem import ProblemNumbers
from planning.starts import start_points

SEED = 46  # the random starts' (fixed: the same forecast always gets the same starts)
PEAK = 27 / 4  # 1 / max of s^2 (1 - s): a bump of amplitude a peaks at a rad (s = 2/3)


def detours(numbers: ProblemNumbers, q0, qd0, duration: float, goal,
            config: PlannerConfig) -> list[np.ndarray]:
    """The initial guess (a cubic to the goal) with each of the first side_joints joints
    swung by +detour_rad and by -detour_rad (rad) mid-horizon, within half its range: the
    base turned either side of the obstacle, shoulder and elbow over and under it."""
    options, dof = config.global_search, numbers.model.dof
    span = 0.5 * (np.asarray(config.upper) - np.asarray(config.lower))
    points = []
    for joint in range(min(options.side_joints, dof)):
        for sign in (1.0, -1.0):
            bumps = np.zeros((dof, config.degree - 2))
            bumps[joint, 0] = sign * PEAK * min(options.detour_rad, span[joint])
            points.append(numbers.initial_guess(q0, qd0, duration, goal, bumps))
    return points


def all_starts(numbers: ProblemNumbers, q0, qd0, duration: float, goal,
               config: PlannerConfig) -> list[np.ndarray]:
    """The detours and 1 + random_starts points of planning.starts (the initial guess first)."""
    random = start_points(numbers, q0, qd0, duration, goal,
                          1 + config.global_search.random_starts, seed=SEED)
    return random[:1] + detours(numbers, q0, qd0, duration, goal, config) + random[1:]
