"""The global search's multi-start: the start points (planning.globalsearch.starts) on one
forecast, by the anytime SQP without budget or settling (planning.anytime.solver.Anytime,
converge=True: every start a few iterations, the best on to convergence) or by IPOPT
(planning.globalsearch.ipopt, every start to convergence), and the best kept by one measure
on the whole forecast (objective)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from identification.torque_model import TorqueModel
from planning.anytime.solver import Anytime
from planning.config import PlannerConfig
from planning.globalsearch.ipopt import IpoptElastic
from planning.globalsearch.starts import all_starts
from planning.timing import Stopwatch, collection_deferred
from planning.types import ObstacleForecast, Segment, SegmentPlan

# the anytime SQP's search: every start SCREEN_ITERATIONS iterations a round, then the best
# FINALISTS on from there to convergence (docs/realtime.md, 'planning.globalsearch')
SCREEN_ITERATIONS, FINALISTS = 20, 2


class MultiStart:
    """Multi-start solves of one torque model and configuration (config.global_search)."""

    def __init__(self, model: TorqueModel, config: PlannerConfig):
        self.config = config
        self.solver = IpoptElastic(model, config) if config.global_search.solver == "ipopt" \
            else Anytime(model, config, converge=True)
        self.check = self.solver.check  # planning.anytime.safety.SafetyCheck

    def prepare(self, goal) -> None:
        self.solver.prepare(goal)

    @collection_deferred
    def search(self, segment: Segment, warm: SegmentPlan | None = None,
               found: Callable[[SegmentPlan, bool], None] | None = None,
               screen: int = SCREEN_ITERATIONS, finalists: int = FINALISTS,
               away: bool = False) -> tuple[SegmentPlan, list[SegmentPlan]]:
        """The best plan (objective) of the segment from the warm plan's shape (if any) and
        every start point, its times those of the whole search, and every plan (each solved
        to convergence, whatever segment.budget_ms). found(plan, better), if given, sees
        every plan as it is solved, better: whether it is usable and scores better than all
        before it (the search's offers as it goes)."""
        clock, solver = Stopwatch(), self.solver
        q0, qd0, t_begin, duration, goal, forecast = (
            segment.q0, segment.qd0, segment.t_begin, segment.duration, segment.goal,
            segment.forecast)
        self.prepare(goal)
        segment = dataclasses.replace(segment, budget_ms=math.inf)
        points = all_starts(solver, q0, qd0, duration, goal, self.config, away)
        if warm is not None:
            points.insert(0, shape_of(warm, t_begin, duration))
        plans, scores = [], []
        offered = [(2, math.inf)]  # an unusable plan (objective's 2) is never offered

        def solved(plan: SegmentPlan) -> SegmentPlan:
            score = objective(self.check, self.config, plan, t_begin, duration, forecast)
            if found is not None:
                found(plan, score < offered[0])
            offered[0] = min(offered[0], score)
            plans.append(plan)
            scores.append(score)
            return plan

        if isinstance(solver, IpoptElastic):
            for x0 in points:
                solved(solver.solve(dataclasses.replace(segment, x0=x0)))
        else:  # every start a few iterations, the best FINALISTS on to convergence
            solver.max_iterations = screen
            for x0 in points:
                solved(solver.solve(dataclasses.replace(segment, x0=x0))[0])
            solver.max_iterations = 200
            for i in sorted(range(len(plans)), key=scores.__getitem__)[:finalists]:
                solved(solver.solve(segment, plans[i])[0])
        best = plans[min(range(len(plans)), key=scores.__getitem__)]
        wall, cpu = clock.read()
        return _timed(best, wall, cpu), plans


def shape_of(plan: SegmentPlan, t_begin: float, duration: float) -> np.ndarray:
    """A start point with the plan's free coefficients on [t_begin, t_begin + duration]
    (its start state replaced by the segment's)."""
    return plan.trajectory.restrict(t_begin, duration).coefficients[:, 2:].ravel()


def objective(check, config: PlannerConfig, plan: SegmentPlan, t_begin: float,
              duration: float, forecast: ObstacleForecast | None) -> tuple[int, float]:
    """One measure for plans that saw different obstacle samples: (2 if it is unusable (its
    solve failed, a joint or torque limit left), 1 if it misses the threshold beyond the
    penalty tolerance at a forecast sample, else 0; its energy
    actually spent (dense integral of |P|, J) plus elastic_weight times its L1 violation of
    the threshold over every forecast sample and link)."""
    energy = check.energy(plan.trajectory)
    if forecast is None:
        return 2 * (not plan.success), energy
    times = np.asarray(forecast.times, float)
    keep = (times > t_begin + 1e-12) & (times <= t_begin + duration + 1e-12)
    links = check(plan.trajectory, times[keep], np.asarray(forecast.centres)[keep]).links
    violation = float(np.sum(np.maximum(config.threshold - links, 0.0)))
    unsafe = config.threshold - float(np.min(links, initial=np.inf)) > config.penalty_tolerance
    return 2 * (not plan.success) or int(unsafe), \
        energy + config.anytime.elastic_weight * violation


def _timed(plan: SegmentPlan, wall: float, cpu: float) -> SegmentPlan:
    return dataclasses.replace(plan, solve_ms=wall, solve_cpu_ms=cpu)


def bank_search(config: PlannerConfig) -> dict:
    """How a search runs for a bank of plans (planning.bank): each start screened
    BankOptions.screen_iterations and no finalists (the bank re-plans every plan it takes to
    convergence itself), so the classes reach it sooner and the next search starts sooner."""
    return {"screen": config.bank.screen_iterations, "finalists": 0, "away": True}
