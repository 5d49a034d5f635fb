"""Polishing (PenaltyOptions.polish) of another segment planner's cold plans: the best
distinct ones solved again, warm, by the penalty loop with the split quadrature
(planning.penalty.loop._polished; the penalty loop's own multi-start polishes itself)."""

from __future__ import annotations

import dataclasses

from planning.penalty.loop import _polished
from planning.penalty.solver import Planner
from planning.starts import rank
from planning.timing import Stopwatch, collection_deferred
from planning.types import Segment, SegmentPlan, SegmentPlanner


class Polished:
    """`inner` (a SegmentPlanner) whose cold plans are polished by `planner.polisher`."""

    def __init__(self, inner: SegmentPlanner, planner: Planner):
        self.inner, self.planner, self.config = inner, planner, inner.config

    @property
    def solver_ms(self) -> float:
        return self.inner.solver_ms

    def offers(self, t: float) -> bool:
        return self.inner.offers(t)

    def prepare(self, goal) -> None:
        self.inner.prepare(goal)
        self.planner.polisher.prepare(goal)

    def plan(self, problem: Segment, warm: SegmentPlan | None = None) -> SegmentPlan:
        return self.inner.plan(problem, warm)

    @collection_deferred
    def plan_cold(self, problem: Segment, starts: int | None = None
                  ) -> tuple[SegmentPlan, list[SegmentPlan]]:
        self.planner.polisher.prepare(problem.goal)  # its build is not part of a plan's time
        best, plans = self.inner.plan_cold(problem, starts)
        clock = Stopwatch()
        ranked = sorted(plans, key=lambda plan: rank(self.planner, plan))
        segment = Segment(problem.q0, problem.qd0, problem.t_begin, problem.duration,
                          problem.goal, problem.forecast)  # warm solves, with no deadline
        polished = _polished(self.planner, best, ranked, segment)
        ms, cpu = clock.read()
        return dataclasses.replace(polished, solve_ms=best.solve_ms + ms,
                                   solve_cpu_ms=best.solve_cpu_ms + cpu), plans
