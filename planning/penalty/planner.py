"""The paper's exterior penalty loop as a SegmentPlanner (planning.types): each segment
planned by planning.penalty.loop with one Planner (its NLP solvers, built once)."""

from __future__ import annotations

import dataclasses

from planning.penalty.loop import plan_multistart, plan_segment
from planning.penalty.solver import Planner
from planning.types import Segment, SegmentPlan


class PenaltyLoop:
    """Plans and re-plans by the penalty loop: alpha raised while the plan dips below the
    threshold (PlannerConfig.replanner "penalty", alias "fatrop")."""

    def __init__(self, planner: Planner):
        self.planner, self.config = planner, planner.config

    @property
    def solver_ms(self) -> float:
        return self.planner.solver_ms

    def offers(self, t: float) -> bool:
        return False

    def prepare(self, goal) -> None:
        self.planner.prepare(goal)

    def plan(self, problem: Segment, warm: SegmentPlan | None = None) -> SegmentPlan:
        plan, wall, cpu = plan_segment(self.planner, problem, warm=warm)
        return dataclasses.replace(plan, solve_ms=wall, solve_cpu_ms=cpu)

    def plan_cold(self, problem: Segment, starts: int | None = None
                  ) -> tuple[SegmentPlan, list[SegmentPlan]]:
        best, wall, cpu, plans = plan_multistart(self.planner, problem, starts)
        return dataclasses.replace(best, solve_ms=wall, solve_cpu_ms=cpu), plans
