"""What both segment planners (the penalty loop, planning.penalty, and the anytime SQP,
planning.anytime) share: the obstacle as a solve sees it, the plan of one segment and the
statuses Algorithm 2 (planning.replanning) reads."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from planning.formulation.trajectory import PolynomialTrajectory

if TYPE_CHECKING:
    from planning.config import PlannerConfig, Scenario

ITERATE = "feasible iterate"  # status of a re-plan stopped short of convergence, followed
DEADLINE = "deadline exceeded"  # status of a re-plan abandoned at its deadline
KEPT = "kept"  # status of a bank's re-plan that re-planned other classes only: the arm goes
# on with the plan it follows (planning.bank.planner)
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
    # wall and CPU time (ms, this thread: insensitive to other load on the machine); of the
    # whole plan, end to end, as a SegmentPlanner returns it
    solve_ms: float
    solve_cpu_ms: float
    penalty_weight: float  # alpha this solve used, J/m^2 per obstacle sample
    x: np.ndarray  # primal solution, for warm starts
    multipliers: tuple[np.ndarray, np.ndarray]  # (lam_g, lam_x)
    breaks: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))  # "split" rule's
    layout: tuple = ()  # the NLP's energy rule (Planner.layout): its multipliers fit only it
    # the elastic SQP's (planning.anytime): the obstacle sample times of its clearance slots
    # (its multipliers follow them to the next re-plan) and whether a clearance row bound it
    slot_times: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    detour: bool = False
    # what the plan spent on its budget's clock (ms): nominal iterations (AnytimeOptions.
    # iteration_ms) or CPU; the anytime SQP's (0 for the penalty loop, which has no budget)
    clock_ms: float = 0.0


@dataclass(frozen=True)
class Segment:
    """One segment to plan: from (q0 rad, qd0 rad/s) at t_begin (s) to goal (rad) at
    t_begin + duration (s), past the obstacle as forecast (None: no obstacle)."""

    q0: np.ndarray
    qd0: np.ndarray
    t_begin: float
    duration: float
    goal: np.ndarray
    forecast: ObstacleForecast | None = None
    x0: np.ndarray | None = None  # a cold plan's start point (default: the initial guess)
    # what the plan may spend on the budget's clock (ms; default: the config's; inf: an
    # offline plan, solved to convergence)
    budget_ms: float | None = None
    deadline_ms: float | None = None  # ms after which a re-plan is abandoned (status DEADLINE)
    # a re-plan of Algorithm 2, which may follow an iterate short of convergence (ITERATE)
    realtime: bool = False
    # a re-plan held in the class of the plan it starts from (planning.formulation.guidance)
    guided: bool = False

    @classmethod
    def from_rest(cls, start, duration: float, goal,
                  forecast: ObstacleForecast | None = None) -> Segment:
        """The segment from rest at start at time 0 to goal at `duration`."""
        return cls(np.asarray(start, float), np.zeros(len(start)), 0.0, duration,
                   np.asarray(goal, float), forecast)

    @classmethod
    def of(cls, scenario: Scenario, forecast: ObstacleForecast | None = None,
           **fields) -> Segment:
        """The scenario's whole motion as one segment, past the obstacle as forecast; fields:
        the segment's other fields (x0, budget_ms, ...)."""
        return cls(scenario.start, scenario.start_velocity, 0.0, scenario.duration,
                   scenario.goal, forecast, **fields)


@runtime_checkable
class SegmentPlanner(Protocol):
    """What plans one segment (the penalty loop, planning.penalty.planner; the anytime SQP,
    planning.anytime.planner): Algorithm 2 takes either and never looks inside."""

    config: PlannerConfig

    def prepare(self, goal) -> None:
        """Build what plans to this goal need, ahead of the plans (not plan time)."""

    def plan(self, problem: Segment, warm: SegmentPlan | None = None) -> SegmentPlan:
        """One plan (cold) or re-plan (warm: from the last plan), its times end to end."""

    def plan_cold(self, problem: Segment, starts: int | None = None
                  ) -> tuple[SegmentPlan, list[SegmentPlan]]:
        """The best of `starts` (default config.starts) cold plans (planning.starts), its
        times those of the whole search, and every plan of the search."""

    def offers(self, t: float) -> bool:
        """Whether it has a plan to offer at sample time t (a global search's,
        planning.globalsearch): Algorithm 2 re-plans then even if its plan is safe."""

    @property
    def solver_ms(self) -> float:
        """Time (ms) in the solver's own calls so far: timing breakdowns."""
