"""Dynamic re-planning, paper Algorithm 2.

The obstacle is observed at K samples t_k = k T / K. At each sample its future
path is predicted (constant velocity from the last two observations); when the
current plan would bring a link within the threshold of that prediction, and the
prediction differs from the one the current plan was made with (otherwise the
solve would return the same plan), the arm re-plans from its current state
(position, velocity, remaining time). A re-plan that fails (other than by missing a
deadline) leaves the arm on its last plan and is tried again at the next sample. The
executed trajectory is the concatenation of the segments actually followed.

With real-time iterations (PenaltyOptions.replan_iterations) a re-plan is a capped
feasible-SQP step from the last plan; while the plan followed is such an unconverged
iterate, the arm re-plans at every sample, going on from it until it converges. So it is
with the anytime SQP (PlannerConfig.replanner "anytime", planning.anytime): a re-plan that
reached its CPU budget unconverged is followed and gone on from at the next sample, except
in the last PlannerConfig.settle_horizon seconds, where only a stale plan is re-planned.
Each segment is planned by a SegmentPlanner (planning.planners.segment_planner), whichever
it is.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from planning.config import Scenario
from planning.errors import PlanningError
from planning.formulation.clearance import link_clearances, predicted_clearance
from planning.formulation.obstacle import predict_linear
from planning.types import (
    DEADLINE,
    ITERATE,
    KEPT,
    LATE,
    ObstacleForecast,
    Segment,
    SegmentPlan,
    SegmentPlanner,
)

TRIGGER_TOLERANCE = 1e-3  # m: predicted dips smaller than this do not trigger a re-plan
PREDICTION_TOLERANCE = 1e-3  # m: a forecast this close to the last one brings nothing new


@dataclass(frozen=True)
class Execution:
    """What the arm did: the segments followed and when each was planned (s)."""

    segments: tuple[SegmentPlan, ...]
    replan_times: tuple[float, ...]
    solve_ms: tuple[float, ...]  # wall time of every plan and re-plan, end to end
    failures: tuple[str, ...]  # IPOPT status of a failed first plan (the result is unusable)
    replan_failures: tuple[str, ...] = ()  # failed re-plans: the arm kept its last plan
    solve_cpu_ms: tuple[float, ...] = ()  # CPU time of the planning thread, per solve_ms entry
    clock_ms: tuple[float, ...] = ()  # on the budget's clock (SegmentPlan.clock_ms), per entry
    bank: dict | None = None  # a bank of plans' account (planning.bank.planner), if one planned
    search_failures: int = 0  # global searches that failed (planning.globalsearch.background)
    # the other method's name ("fatrop", "sqp") when the first plan is its (planning.offline)
    first_plan_fallback: str | None = None


def check_start(planner: SegmentPlanner, scenario: Scenario) -> None:
    """Raise PlanningError if the arm starts within the threshold of the obstacle."""
    if scenario.obstacle is None:
        return
    clearance = link_clearances(planner.config.geometry, np.asarray([scenario.start]),
                                scenario.obstacle.position(0.0)).min()
    if clearance < planner.config.threshold:
        raise PlanningError(f"start is inside the obstacle threshold: clearance "
                            f"{clearance:.4f} m < {planner.config.threshold} m")


def execute(planner: SegmentPlanner, scenario: Scenario, replan: bool = True,
            avoid: bool = True, starts: int | None = None,
            first_start: np.ndarray | None = None, paced: bool = False) -> Execution:
    """Run Algorithm 2 on the scenario.

    replan=False follows the first plan throughout; avoid=False ignores the obstacle
    (the energy-optimal motion without obstacle, paper Fig. 9 red line); starts: of the
    first plan (default config.starts, planning.starts), or first_start: its one start point.
    paced: each obstacle sample is taken no sooner than its time after the first plan, on
    the wall clock, as a robot's motion runs (what another process does meanwhile, the
    global search, then has the motion's time, not the re-plans' alone).
    """
    scenario.validate(planner.config)
    obstacle, goal, T = scenario.obstacle if avoid else None, scenario.goal, scenario.duration
    if avoid:
        check_start(planner, scenario)
    forecast = None if obstacle is None else forecast_at(obstacle, 0.0)
    first = Segment(scenario.start, scenario.start_velocity, 0.0, T, goal, forecast,
                    x0=first_start)
    plan = planner.plan_cold(first, starts)[0] if first_start is None else planner.plan(first)
    segments, times = [plan], [0.0]
    solve_ms, solve_cpu, clock_ms = [plan.solve_ms], [plan.solve_cpu_ms], [plan.clock_ms]
    failures, replan_failures = ([] if plan.success else [plan.status]), []
    if obstacle is None or not replan:
        return Execution(tuple(segments), tuple(times), tuple(solve_ms), tuple(failures),
                         (), tuple(solve_cpu), tuple(clock_ms),
                         first_plan_fallback=getattr(planner, "first_plan_fallback", None))
    planned_with, latest = forecast, plan  # latest: the newest successful solve (converged
    # or a real-time iterate, planning.penalty.realtime_iteration.ITERATE), the next re-plan's warm start
    motion = time.perf_counter()  # the motion starts once its first plan is made
    for t in obstacle.sample_times[:-1]:
        if paced:  # the sample is seen at its time (docs/realtime.md, 'planning.replanning')
            time.sleep(max(0.0, motion + t - time.perf_counter()))
        forecast = forecast_at(obstacle, t)
        # it stopped short: go on from it, unless too near the end to gain but a harder stop
        iterating = plan.status.startswith(ITERATE) and \
            T - t > planner.config.settle_horizon + 1e-12
        if not iterating and not planner.offers(t) and (not _stale(planner, plan, forecast)
                              or same_prediction(planned_with, forecast)):
            continue  # safe, or nothing new to plan with: the last plan already saw this
        q, qd, _ = plan.trajectory.state(t)
        new = planner.plan(Segment(q[0], qd[0], t, T - t, goal, forecast, realtime=True,
                                   deadline_ms=planner.config.replan_deadline_ms), warm=latest)
        if new is latest:  # the arm goes on as it was: nothing was planned
            continue
        solve_ms.append(new.solve_ms)
        solve_cpu.append(new.solve_cpu_ms)
        clock_ms.append(new.clock_ms)
        if new.status == KEPT:  # a bank re-planned other classes, the arm goes on as it was
            continue
        if not new.success:
            replan_failures.append(new.status)
            if new.status.startswith(DEADLINE):
                # tried again when the prediction changes (retried at every sample, re-plans
                # that could not meet the deadline made the bench's quick run take minutes)
                planned_with = forecast
            if new.status.endswith(LATE):  # too late to follow, yet the best start point
                latest = new
            # keep following the last good plan; a re-plan that failed otherwise is tried
            # again at the next sample: that plan never saw this forecast
            # (docs/realtime.md, 'planning.replanning')
            continue
        plan = latest = new
        planned_with = forecast
        segments.append(plan)
        times.append(float(t))
    return Execution(tuple(segments), tuple(times), tuple(solve_ms), tuple(failures),
                     tuple(replan_failures), tuple(solve_cpu), tuple(clock_ms),
                     bank_account(planner), getattr(planner, "search_failures", 0),
                     getattr(planner, "first_plan_fallback", None))


def bank_account(planner) -> dict | None:
    """The account of the bank of plans that planned (None: one plan at a time)."""
    account = getattr(planner, "account", None)
    return None if account is None else account()


def forecast_at(obstacle, t: float) -> ObstacleForecast:
    """Prediction at time t of the obstacle at the remaining samples, from what was seen."""
    seen = np.concatenate([[0.0], obstacle.sample_times])
    seen = seen[seen <= t + 1e-12][-2:]
    future = obstacle.sample_times[obstacle.sample_times > t + 1e-12]
    return ObstacleForecast(future, predict_linear(seen, obstacle.position(seen), future))


def same_prediction(old: ObstacleForecast, new: ObstacleForecast) -> bool:
    """True if `new` predicts every remaining sample within PREDICTION_TOLERANCE of `old`."""
    index = np.searchsorted(old.times, new.times)
    if np.any(index >= len(old.times)) or not np.allclose(old.times[index], new.times):
        return False
    return bool(np.max(np.abs(old.centres[index] - new.centres), initial=0.0)
                <= PREDICTION_TOLERANCE)


def _stale(planner: SegmentPlanner, plan: SegmentPlan, forecast: ObstacleForecast) -> bool:
    return stale(planner.config, plan, forecast)


def stale(config, plan: SegmentPlan, forecast: ObstacleForecast | None) -> bool:
    """True if the plan must be re-planned for this forecast: it comes within the threshold
    (Algorithm 2), or it was bent round the obstacle (a positive penalty) and now keeps more
    than the threshold everywhere: the obstacle has moved off its detour, whose energy a
    re-plan can save (docs/realtime.md, 'planning.replanning')."""
    if forecast is None:
        return False
    clearance = predicted_clearance(config.geometry, plan.trajectory, forecast)
    threshold = config.threshold
    return clearance < threshold - TRIGGER_TOLERANCE or \
        ((plan.penalty > 0.0 or plan.detour) and clearance > threshold + TRIGGER_TOLERANCE)


