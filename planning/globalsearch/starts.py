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


def turned_away(numbers: ProblemNumbers, q0, qd0, duration: float, goal,
                config: PlannerConfig) -> np.ndarray:
    """The initial guess with the base (joint 1) backed off mid-horizon (s = 2/3) to
    detour_rad against its way to the goal from where it starts: the way round that waits
    turned away (planning.bank.classes, 'turned away'), which a detour of the base around the
    cubic does not reach once the cubic has gone on by more than detour_rad."""
    q0, qd0, goal = (np.asarray(a, float) for a in (q0, qd0, goal))
    s, v = 2.0 / 3.0, qd0[0] * duration
    d = goal[0] - q0[0] - v
    progress = v * s + (3 * d + v) * s**2 - (v + 2 * d) * s**3  # the cubic's, at s
    way = 1.0 if goal[0] >= q0[0] else -1.0
    bumps = np.zeros((len(q0), config.degree - 2))
    bumps[0, 0] = PEAK * (-way * config.global_search.detour_rad - progress)
    return numbers.initial_guess(q0, qd0, duration, goal, bumps)


def all_starts(numbers: ProblemNumbers, q0, qd0, duration: float, goal,
               config: PlannerConfig, away: bool = False) -> list[np.ndarray]:
    """The detours and 1 + random_starts points of planning.starts (the initial guess first);
    with the base turned away after the detours if away."""
    random = start_points(numbers, q0, qd0, duration, goal,
                          1 + config.global_search.random_starts, seed=SEED)
    turned = [turned_away(numbers, q0, qd0, duration, goal, config)] if away else []
    return random[:1] + detours(numbers, q0, qd0, duration, goal, config) + turned + random[1:]
