"""What both segment planners (the penalty loop, planning.penalty, and the anytime SQP,
planning.anytime) share: the obstacle as a solve sees it, the plan of one segment and the
statuses Algorithm 2 (planning.replanning) reads."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from planning.formulation.trajectory import PolynomialTrajectory

ITERATE = "feasible iterate"  # status of a re-plan stopped short of convergence, followed
DEADLINE = "deadline exceeded"  # status of a re-plan abandoned at its deadline
LATE = " (converged late)"  # ... whose last solve succeeded (converged, or a real-time
# iterate within the constraints): the next re-plan starts from it


@dataclass(frozen=True)
class ObstacleForecast:
    """Predicted obstacle centres (k, 3) in m at times (k,) in s, as the planner sees them."""

    times: np.ndarray
    centres: np.ndarray


@dataclass(frozen=True)
class SegmentPlan:
    """One solve: the segment, its objective parts (J) and how the solve went."""

    trajectory: PolynomialTrajectory
    energy: float  # sigma/N sum |P|, J
    penalty: float  # alpha sum of squared threshold violations, J
    success: bool
    status: str
    iterations: int
    solve_ms: float  # wall time
    solve_cpu_ms: float  # CPU time of this thread (insensitive to other load on the machine)
    penalty_weight: float  # alpha this solve used, J/m^2 per obstacle sample
    x: np.ndarray  # primal solution, for warm starts
    multipliers: tuple[np.ndarray, np.ndarray]  # (lam_g, lam_x)
    breaks: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))  # "split" rule's
    layout: tuple = ()  # the NLP's energy rule (Planner.layout): its multipliers fit only it
    # the elastic SQP's (planning.anytime): the obstacle sample times of its clearance slots
    # (its multipliers follow them to the next re-plan) and whether a clearance row bound it
    slot_times: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    detour: bool = False
