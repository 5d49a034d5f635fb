"""Multi-start cold plans: the energy landscape has local optima (a motion can swing a joint
either way round a gravity-neutral pose, pass an obstacle above or below), so a cold plan
solves from several start points and keeps the best.

Start 0 is the planner's initial guess (a cubic to the goal); start i > 0 adds to it bumps
that vanish at both ends, drawn from a fixed seed (the same problem always gets the same
starts), with amplitudes of half each joint's range. Every start solves the obstacle problem
from itself (planning.penalty.loop.plan_segment, planning.anytime.planner): the unobstructed
optimum is nearly always unique, so passing through it would bring every start to the same detour.
"""

from __future__ import annotations

import numpy as np

from planning.formulation.energy import dense_energy
from planning.formulation.limits import LIMIT_TOLERANCE, limit_excess
from planning.formulation.problem import ProblemNumbers
from planning.types import SegmentPlan

SEED = 20240515


def start_points(planner: ProblemNumbers, q0, qd0, duration: float, goal, count: int,
                 seed: int = SEED) -> list[np.ndarray]:
    """`count` cold start points x0 of the planning NLP (the first: the initial guess)."""
    config = planner.config
    rng = np.random.default_rng(seed)
    scale = 0.5 * (np.asarray(config.upper) - np.asarray(config.lower))
    points = [planner.initial_guess(q0, qd0, duration, goal)]
    for _ in range(count - 1):
        bumps = rng.normal(size=(planner.model.dof, config.degree - 2)) * scale[:, None]
        points.append(planner.initial_guess(q0, qd0, duration, goal, bumps))
    return points


def rank(planner: ProblemNumbers, plan: SegmentPlan) -> tuple[bool, bool, float]:
    """Sort key of candidate plans: converged first, then within the joint limits (a cold
    plan is returned unchecked when its rounds end beyond one, planning.replanning), then the
    lower energy actually spent (planning.formulation.energy.dense_energy, not the plan's own
    quadrature, which can under-count it enough to rank a dearer start first
    (docs/realtime.md, 'planning.starts')) plus the clearance penalty (J)."""
    config = planner.config
    beyond = limit_excess(plan.trajectory, config.lower, config.upper) > LIMIT_TOLERANCE
    return (not plan.success, beyond, dense_energy(planner.model, plan.trajectory) + plan.penalty)
