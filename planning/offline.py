"""Offline plans (a first plan that need not be real time, or a plan followed throughout):
every start solved to convergence by one segment planner and, when none of its plans is
feasible, by the other, so a plan is found wherever either method finds one."""

from __future__ import annotations

import dataclasses
import math

from planning.formulation.clearance import predicted_clearance
from planning.formulation.limits import LIMIT_TOLERANCE, limit_excess
from planning.replanning import bank_account
from planning.timing import collection_deferred
from planning.types import Segment, SegmentPlan, SegmentPlanner


class Offline:
    """`primary` (a SegmentPlanner) whose cold plans run without budget (each start to
    convergence) and fall back to `fallback`'s (the other method's) when the primary's best
    is not feasible; its re-plans are the primary's, as they are."""

    def __init__(self, primary: SegmentPlanner, fallback: SegmentPlanner | None,
                 fallback_name: str | None = None):
        """fallback_name: PLAN.json's name of the fallback's method ("fatrop", "sqp")."""
        self.primary, self.fallback, self.config = primary, fallback, primary.config
        self.fallback_name = fallback_name
        # the fallback's name when the last cold plan is the fallback's, else None
        self.first_plan_fallback: str | None = None

    @property
    def solver_ms(self) -> float:
        return self.primary.solver_ms + (0.0 if self.fallback is None else
                                         self.fallback.solver_ms)

    @property
    def search_failures(self) -> int:
        return getattr(self.primary, "search_failures", 0)

    def offers(self, t: float) -> bool:
        return self.primary.offers(t)

    def account(self) -> dict | None:
        """The primary's bank account (planning.replanning.bank_account)."""
        return bank_account(self.primary)

    def prepare(self, goal) -> None:
        self.primary.prepare(goal)  # the fallback's built only if a plan needs it

    def plan(self, problem: Segment, warm: SegmentPlan | None = None) -> SegmentPlan:
        if warm is None and not problem.realtime:
            problem = dataclasses.replace(problem, budget_ms=math.inf)
        return self.primary.plan(problem, warm)

    @collection_deferred
    def plan_cold(self, problem: Segment, starts: int | None = None
                  ) -> tuple[SegmentPlan, list[SegmentPlan]]:
        problem = dataclasses.replace(problem, budget_ms=math.inf)
        self.first_plan_fallback = None
        best, plans = self.primary.plan_cold(problem, starts)
        if self.fallback is None or feasible(self.config, best, problem):
            return best, plans
        other, more = self.fallback.plan_cold(problem, starts)
        chosen = other if feasible(self.config, other, problem) else best
        if chosen is other:  # its status says how its solve went, not whose it is
            self.first_plan_fallback = self.fallback_name or "other"
        return dataclasses.replace(chosen, solve_ms=best.solve_ms + other.solve_ms,
                                   solve_cpu_ms=best.solve_cpu_ms + other.solve_cpu_ms,
                                   clock_ms=best.clock_ms + other.clock_ms), plans + more


def feasible(config, plan: SegmentPlan, problem: Segment) -> bool:
    """Whether a plan is one to follow: its solve succeeded (the goal and the torque limits
    kept), within the joint limits and keeping the threshold (within the penalty tolerance)
    of the forecast it was planned for."""
    if not plan.success or limit_excess(plan.trajectory, config.lower, config.upper) \
            > LIMIT_TOLERANCE:
        return False
    if problem.forecast is None:
        return True
    clearance = predicted_clearance(config.geometry, plan.trajectory, problem.forecast)
    return clearance >= config.threshold - config.penalty_tolerance
