"""The choice among a solve's accepted iterates (planning.anytime): each one checked on the
whole forecast, the joint limits and the torques (planning.anytime.safety), ranked within the hard
limits first, then keeping the threshold, then by the objective the SQP minimizes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planning.anytime.elastic_qp import Point
from planning.anytime.safety import Safety
from planning.config import PlannerConfig
from planning.formulation.limits import LIMIT_TOLERANCE
from planning.formulation.trajectory import PolynomialTrajectory

HARD_TOLERANCE = 1e-6  # L1 violation of the goal and limit rows an iterate may keep
TORQUE_TOLERANCE = 1e-6  # N m


@dataclass
class Candidate:
    """A checked iterate: how far it leaves the hard limits (goal rows, joint limits in rad,
    torques in N m), whether it misses the threshold beyond the penalty tolerance."""

    hard: float
    unsafe: bool
    x: np.ndarray
    safety: Safety
    point: Point
    trajectory: PolynomialTrajectory  # the motion x stands for

    @property
    def rank(self) -> tuple:
        """Within the hard limits first, then keeping the threshold, then the objective (for
        one that misses the threshold: the energy plus its L1 violation weighed by
        elastic_weight, which the SQP minimizes)."""
        return (self.hard > 0, self.unsafe, self.hard, self.point.f)


def choose(points: list[Point], motion, check, config: PlannerConfig,
           slacks: slice | None = None) -> tuple[Candidate, int]:
    """The best of points by Candidate.rank, and how many were checked; motion(x) is an
    iterate's trajectory, check a SafetyCheck.against, slacks where a point's clearance
    slacks sit (v = max(0, lambda - D) of the rows its solve had). They are checked from the
    lowest objective up: the first that keeps the threshold and the hard limits is the best
    (any later one has a larger objective). Once a candidate within the hard limits misses
    the threshold, a later one can only be better by keeping it (a common end of a re-plan,
    (docs/realtime.md, 'planning.anytime.candidates')): one whose own rows
    already miss it is passed over unchecked, the others have their clearance alone checked
    first."""
    best, checked = None, 0
    for point in sorted(points, key=lambda point: point.f):
        keeping_only = best is not None and not best.hard  # only keeping the threshold wins
        if keeping_only and misses(point, slacks, config):
            continue
        trajectory, checked = motion(point.x), checked + 1
        links = check.links(trajectory.coefficients) if keeping_only else None
        if keeping_only and not keeps(links.min(initial=np.inf), config):
            continue
        safety = check(trajectory.coefficients, links)
        hard = max(safety.limit_excess - LIMIT_TOLERANCE, 0.0) + \
            max(safety.torque_excess - TORQUE_TOLERANCE, 0.0) + \
            max(point.violation - HARD_TOLERANCE, 0.0)
        candidate = Candidate(hard, not keeps(safety.lowest, config), point.x, safety, point,
                              trajectory)
        if best is None or candidate.rank < best.rank:
            best = candidate
        if not candidate.unsafe and not candidate.hard:
            break
    return best, checked


def misses(point: Point, slacks: slice | None, config: PlannerConfig) -> bool:
    """Whether a point's clearance rows (D + v >= lambda at its solve's samples, which the
    whole-forecast check repeats) already miss the threshold beyond the penalty tolerance:
    a slack above it (1e-9 m of rounding kept for the check to decide)."""
    if slacks is None or slacks.stop == slacks.start:
        return False
    return float(np.max(point.x[slacks])) > config.penalty_tolerance + 1e-9


def keeps(lowest: float, config: PlannerConfig) -> bool:
    """Whether a lowest clearance (m) keeps the threshold within the penalty tolerance."""
    return config.threshold - lowest <= config.penalty_tolerance
