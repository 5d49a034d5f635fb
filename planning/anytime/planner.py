"""The anytime SQP as a SegmentPlanner (planning.types): every plan under a CPU budget
(planning.anytime.solver), a cold plan's starts sharing one budget."""

from __future__ import annotations

import dataclasses
import time

from identification.torque_model import TorqueModel
from planning.anytime.budget import Clock
from planning.anytime.solver import Anytime
from planning.config import PlannerConfig
from planning.starts import start_points
from planning.timing import Stopwatch, collection_deferred
from planning.types import DEADLINE, LATE, Segment, SegmentPlan


class AnytimePlanner:
    """Plans and re-plans by the anytime SQP (PlannerConfig.replanner "anytime"): a re-plan gets
    config.anytime.replan_budget_ms of CPU, a cold plan config.anytime.cold_budget_ms for all its starts."""

    def __init__(self, model: TorqueModel, config: PlannerConfig):
        self.config, self.anytime = config, Anytime(model, config)

    @property
    def solver_ms(self) -> float:
        """CPU ms so far in the SQPs' solves."""
        return float(self.anytime._solver_ms()[1])

    def offers(self, t: float) -> bool:
        return False

    def prepare(self, goal) -> None:
        self.anytime.prepare(goal)

    @collection_deferred
    def plan(self, problem: Segment, warm: SegmentPlan | None = None) -> SegmentPlan:
        config = self.config
        budget = problem.budget_ms  # given: a share of a budget (or inf: to convergence)
        if budget is None:
            budget = config.anytime.replan_budget_ms if warm is not None else \
                config.anytime.cold_budget_ms
        if problem.deadline_ms is not None:
            budget = min(budget, problem.deadline_ms)
        self.anytime.prepare(problem.goal)  # built once: not part of a plan's time
        segment = dataclasses.replace(problem, budget_ms=budget)
        if warm is not None and config.anytime.replan_starts:
            clock = Stopwatch()
            plan = self.anytime.best_of(segment, warm, config.anytime.replan_starts)
            wall, cpu = clock.read()
            plan = dataclasses.replace(plan, solve_ms=wall, solve_cpu_ms=cpu)
        else:
            plan = self.anytime.solve(segment, warm)[0]
        return self._in_time(plan, problem.deadline_ms)

    def _in_time(self, plan: SegmentPlan, deadline_ms: float | None) -> SegmentPlan:
        """The plan, or, if it took longer than deadline_ms (CPU under real-time clocks, else
        on the nominal clock), the plan dropped: unsuccessful with status DEADLINE (LATE if
        it was usable: the next re-plan starts from it), the arm keeps its last plan."""
        spent = plan.solve_cpu_ms if self.config.anytime.iteration_ms is None else plan.clock_ms
        if deadline_ms is None or spent <= deadline_ms:
            return plan
        return dataclasses.replace(plan, success=False,
                                   status=DEADLINE + (LATE if plan.success else ""))

    @collection_deferred
    def plan_cold(self, problem: Segment, starts: int | None = None
                  ) -> tuple[SegmentPlan, list[SegmentPlan]]:
        """The best cold plan (Anytime.rank) of `starts` start points sharing
        config.anytime.cold_budget_ms (or problem.budget_ms; inf: each solved to convergence):
        each gets an even share of what the starts before it left (their checks and
        bookkeeping run past their iterations' budget), and none starts without what a round
        of a plan costs; on the nominal clock what the starts before spent is their nominal
        time, under CPU clocks all the CPU so far (the start points included) and the ranking
        after the starts (docs/realtime.md, 'planning.anytime.planner')."""
        config, anytime = self.config, self.anytime
        count = config.starts if starts is None else starts
        total = config.anytime.cold_budget_ms if problem.budget_ms is None else problem.budget_ms
        plans, wall, cpu, nominal = [], 0.0, 0.0, 0.0
        entered, budget = time.thread_time(), Clock(config.anytime.iteration_ms)
        for i, x0 in enumerate(start_points(anytime, problem.q0, problem.qd0,
                                            problem.duration, problem.goal, count)):
            used = nominal
            if budget.nominal is None:
                used = 1e3 * (time.thread_time() - entered) + anytime.rounds.ranking_ms(budget)
            share = (total - used) / (count - i)
            if plans and share < anytime.round_ms():
                break
            plan = self.plan(dataclasses.replace(problem, x0=x0, budget_ms=share))
            plans.append(plan)
            wall, cpu = wall + plan.solve_ms, cpu + plan.solve_cpu_ms
            nominal += plan.clock_ms
        clock = Stopwatch()  # the ranking (a dense integral per plan) is plan time
        best = min(plans, key=anytime.rank)
        anytime.rounds.record_ranking(budget, clock.cpu_ms())
        ms, cpu_ms = clock.read()
        return dataclasses.replace(best, solve_ms=wall + ms, solve_cpu_ms=cpu + cpu_ms,
                                   clock_ms=nominal), plans
