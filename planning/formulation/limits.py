"""Joint limits along a polynomial segment, including a goal that lies on a limit.

Away from the segment's end, a limit holds if it holds at the motion's turning
points. When the goal sits on a limit (the paper's q1 = -pi/2 does), the motion
may arrive there at rest; then a turning point merges with the end and the
constraint pair (goal equality, limit at the turning point) becomes degenerate.
There the limit is written on the quotient v(s) = sign (q(s) - goal) / (1 - s)^m
(m = 1, or 2 when the motion must arrive at rest): q stays inside the limit on
[0, 1) exactly when v >= 0 on [0, 1], and v's constraints stay regular at s = 1.
"""

from __future__ import annotations

import numpy as np

from planning.formulation.trajectory import PolynomialTrajectory, stationary_points_rows

LIMIT_TOLERANCE = 1e-6  # rad: a plan beyond a limit by more is infeasible (planning.result)
END_MARGIN = 0.02  # normalized time: q's turning points this close to a limit goal are
# left to the quotient constraints


def divide_by_one_minus_s(coefficients):
    """Quotient r of (u(s) - u(1)) / (1 - s) for ascending coefficients u (list-like of
    numbers or CasADi scalars); returns ascending coefficients of degree one less."""
    w = [coefficients[-1]]
    for a in reversed(coefficients[1:-1]):
        w.insert(0, a + w[0])
    return [-x for x in w]


def quotient(coefficients, goal, sign, order: int):
    """Ascending coefficients of v = sign (q - goal) / (1 - s)^order for one joint."""
    u = [coefficients[0] - goal] + list(coefficients[1:])
    for _ in range(order):
        u = divide_by_one_minus_s(u)
    return [sign * x for x in u]


def goal_limit_signs(goal, lower, upper) -> np.ndarray:
    """+1 where the goal is on the lower limit, -1 on the upper, 0 elsewhere (per joint)."""
    goal = np.asarray(goal, float)
    return (np.abs(goal - np.asarray(lower)) < 1e-9).astype(float) \
        - (np.abs(goal - np.asarray(upper)) < 1e-9).astype(float)


def quotient_turning_points(trajectory: PolynomialTrajectory, goal, signs, order: int,
                            slots: int) -> np.ndarray:
    """Turning points (dof, slots) in (0, 1) of each joint's quotient v; NaN if none."""
    out = np.full((len(trajectory.coefficients), slots), np.nan)
    joints = np.flatnonzero(signs)
    if not len(joints):
        return out
    quotients = [quotient(list(trajectory.coefficients[j]), goal[j], signs[j], order)
                 for j in joints]
    roots = stationary_points_rows(np.array(quotients, float))  # sorted, NaN-padded
    width = min(roots.shape[1], slots)
    out[joints, :width] = roots[:, :width]
    return out


def limit_excess(trajectory: PolynomialTrajectory, lower, upper, samples: int = 400) -> float:
    """Worst excursion (rad) beyond the limits on a dense grid plus the turning points."""
    times = np.linspace(0.0, 1.0, samples + 1)
    turning = trajectory.turning_points()
    times = np.concatenate([times, turning[np.isfinite(turning)]])
    q = trajectory.position(trajectory.t_begin + times * trajectory.duration)
    return float(max(0.0, np.max(np.asarray(lower) - q), np.max(q - np.asarray(upper))))
