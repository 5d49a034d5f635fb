"""One segment of Algorithm 2, planned by the penalty loop (paper III.G: alpha raised while
the plan dips below the threshold, obstacle samples screened, limits at the turning points
settled); and the multi-start cold plan, polished or not.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from planning.formulation import breaks
from planning.formulation.clearance import predicted_clearance
from planning.formulation.limits import LIMIT_TOLERANCE, limit_excess
from planning.formulation.screening import screen
from planning.penalty.solver import Planner
from planning.starts import rank, start_points
from planning.timing import Stopwatch, collection_deferred
from planning.types import DEADLINE, ITERATE, LATE, ObstacleForecast, Segment, SegmentPlan

LIMIT_SETTLED = 1e-8  # rad: a plan this close to its limits (dense grid) needs no re-solve
UNCHANGED = 1e-9  # rad: a re-solve that moves no coefficient further has settled


@collection_deferred
def plan_segment(planner: Planner, segment: Segment, warm: SegmentPlan | None = None,
                 rounds: int = 4, settle_breaks: bool = True) -> tuple[SegmentPlan, float, float]:
    """Plan one segment: screened solves (see _screened), with the penalty weight raised
    while the solution still dips below the threshold (exterior penalty method).

    segment.deadline_ms: CPU time (ms) after which no further solve starts; a plan that took longer
    is returned unsuccessful with status DEADLINE (it would arrive too late to be followed).
    Under a deadline no solve goes on with IPOPT when the fast solver cannot finish it (its
    answer would come too late: planning.penalty.solver.Planner._solve).
    settle_breaks: re-solve until the split quadrature's breaks are the plan's own power sign
    changes (False: solved once with those of the start; plan_multistart settles the best).
    segment.realtime: a re-plan of Algorithm 2 with real-time iterations
    (config.penalty.replan_iterations):
    its warm solve is capped and its iterate (status ITERATE) returned if it keeps the
    threshold and the limits; otherwise it is solved out from there as without them.

    Without a warm start, the problem with the obstacle is solved directly from a start
    point segment.x0 (default: the planner's initial guess), whose motion is the screening
    reference (solving the unobstructed optimum first and going on from it was slower,
    (docs/realtime.md, 'planning.penalty.loop')). Returns
    the plan and the wall and CPU time (ms, planning thread) of the whole call, end to end:
    solves, screening, checks and bookkeeping.
    """
    q0, qd0, t_begin, duration, goal, forecast, x0 = (
        segment.q0, segment.qd0, segment.t_begin, segment.duration, segment.goal,
        segment.forecast, segment.x0)
    deadline_ms, iterate = segment.deadline_ms, segment.realtime
    planner.prepare(goal)  # the solvers for this goal, built once: not part of a plan's time
    clock = Stopwatch()
    config = planner.config
    alpha = config.penalty_weight if warm is None else warm.penalty_weight
    replan = warm is not None  # a warm plan beyond the limits is refused: its caller keeps one
    if warm is None and forecast is not None:
        x0 = planner.initial_guess(q0, qd0, duration, goal) if x0 is None else x0
        # each start point of its own: the obstacle problem solved from it directly (solving
        # the unobstructed problem first would bring every start to the same optimum)
        reference = planner.trajectory(x0, q0, qd0, t_begin, duration)
        subset = screen(forecast, reference, config.geometry, config.threshold,
                        config.obstacle_slots).subset
        warm = planner.solve(dataclasses.replace(segment, forecast=subset, x0=x0),
                             reference=reference, alpha=alpha)
        seen = set(subset.times) if warm.success else None
    elif warm is None:
        warm = planner.solve(segment, alpha=alpha)
        seen = set()  # a failed unobstructed solve is reported as it is
    else:
        seen = None
    budget = np.inf if deadline_ms is None else deadline_ms
    iterate = iterate and replan and config.penalty.replan_iterations is not None
    while True:
        plan, lowest = _screened(planner, segment, warm, seen, alpha, rounds,
                                 lambda: clock.cpu_ms() > budget, settle_breaks,
                                 rescue=deadline_ms is None, iterate=iterate)
        if clock.cpu_ms() > budget:
            status = DEADLINE + (LATE if plan.success else "")
            return dataclasses.replace(plan, success=False, status=status), *clock.read()
        if plan.status == ITERATE:
            if _keeps_clear(planner, plan, forecast, lowest) and \
                    _within_limits(plan, config, replan).success:
                return plan, *clock.read()
            # it dips below the threshold or leaves a limit: solved out from it, as without
            # real-time iterations (docs/realtime.md, 'planning.penalty.loop')
            iterate, warm, seen = False, plan, None
            continue
        if forecast is None or alpha >= config.penalty.max_weight or not plan.success:
            return _within_limits(plan, config, replan), *clock.read()
        if _keeps_clear(planner, plan, forecast, lowest):
            return _within_limits(plan, config, replan), *clock.read()
        alpha = min(alpha * config.penalty.growth, config.penalty.max_weight)
        warm, seen = plan, None


def _keeps_clear(planner: Planner, plan: SegmentPlan, forecast: ObstacleForecast | None,
                 lowest: float | None) -> bool:
    """True if the plan keeps the threshold (within the penalty tolerance) of the forecast;
    lowest: its smallest clearance if the screening already knows it."""
    if forecast is None:
        return True
    if lowest is None:
        lowest = predicted_clearance(planner.config.geometry, plan.trajectory, forecast)
    return lowest >= planner.config.threshold - planner.config.penalty_tolerance


def _within_limits(plan: SegmentPlan, config, warm: bool) -> SegmentPlan:
    """The plan, unsuccessful if it leaves the joint limits by more than LIMIT_TOLERANCE: its
    rounds (_screened) can end before the limits at its turning points settle
    (docs/realtime.md, 'planning.penalty.loop').
    Applied to warm plans (re-plans, polishing, settling), whose callers keep the plan they
    started from; a cold plan is returned as it is and the result's checks report it."""
    if not warm or not plan.success:
        return plan
    excess = limit_excess(plan.trajectory, config.lower, config.upper)
    if excess <= LIMIT_TOLERANCE:
        return plan
    return dataclasses.replace(plan, success=False,
                               status=f"joint limits exceeded by {excess:.2e} rad")


@collection_deferred
def plan_multistart(planner: Planner, segment: Segment, count: int | None = None
                    ) -> tuple[SegmentPlan, float, float, list[SegmentPlan]]:
    """The best of `count` (default config.starts) cold plans of one segment (plan_segment
    from each start point of planning.starts), ranked converged first, then within the joint
    limits, then by the energy they spend (planning.starts.rank); total wall and CPU ms; all
    the cold plans. With the split quadrature only the best start's plan is re-solved until
    its breaks settle (settling every start's is costly: (docs/realtime.md, 'planning.penalty.loop')).
    With config.penalty.polish the best distinct plans are re-solved by planner.polisher (see
    _polished)."""
    count = planner.config.starts if count is None else count
    goal = segment.goal
    split = planner.config.energy_quadrature == "split"
    if planner.polisher is not None:
        planner.polisher.prepare(goal)  # its solvers' build is not part of a plan's time
    plans, wall, cpu = [], 0.0, 0.0
    for x0 in start_points(planner, segment.q0, segment.qd0, segment.duration, goal, count):
        plan, ms, cpu_ms = plan_segment(planner, dataclasses.replace(segment, x0=x0),
                                        settle_breaks=not split)
        plans.append(plan)
        wall, cpu = wall + ms, cpu + cpu_ms
    clock = Stopwatch()  # the ranking (a dense integral per plan) and polishing are plan time
    ranked = sorted(plans, key=lambda plan: rank(planner, plan))
    best = ranked[0]
    if split and best.success:
        settled, _, _ = plan_segment(planner, segment, warm=best)
        best = settled if settled.success else best
    if planner.polisher is not None:
        best = _polished(planner, best, ranked, segment)
    ms, cpu_ms = clock.read()
    return best, wall + ms, cpu + cpu_ms, plans


DISTINCT = 1e-3  # rad: cold plans whose coefficients all agree this closely are one optimum


def _polished(planner: Planner, best: SegmentPlan, ranked: list[SegmentPlan],
              segment: Segment) -> SegmentPlan:
    """The plan that spends least of `best` and the config.penalty.polish best distinct converged
    plans of `ranked`, each solved again, warm from its motion, by planner.polisher (the
    split quadrature at config.penalty.polish_samples nodes, breaks settled). The many starts
    search on the planner's cheaper rule; the few that are polished spend what they plan."""
    picked: list[SegmentPlan] = []
    for plan in ranked:
        if len(picked) == planner.config.penalty.polish or not plan.success:
            break
        if all(np.max(np.abs(plan.trajectory.coefficients - other.trajectory.coefficients))
               > DISTINCT for other in picked):
            picked.append(plan)
    candidates = [best]
    for plan in picked:
        polished, _, _ = plan_segment(planner.polisher, segment, warm=plan)
        if polished.success:
            candidates.append(polished)
    return min(candidates, key=lambda plan: rank(planner, plan))


def _screened(planner: Planner, segment: Segment, plan: SegmentPlan,
              seen: set | None, alpha: float, rounds: int,
              late=lambda: False, settle_breaks: bool = True,
              rescue: bool = True, iterate: bool = False) -> tuple[SegmentPlan, float | None]:
    """Solve with the obstacle samples screened on a reference (`plan`, re-expressed on
    this horizon) and the limits at its turning points; re-screen on the result until
    the samples where it dips were seen by its solves (Screen.covered), it keeps the
    limits and (settle_breaks) the split quadrature's breaks are its own (planning.formulation.breaks).
    seen: the obstacle sample times `plan` was solved with, if it solves this very problem
    (same horizon and alpha: then it may be settled without a further solve); None if not.
    late(): True once no further solve may start (a deadline); rescue: whether a solve the
    fast solver cannot finish goes on with IPOPT (not under a deadline); iterate: the warm
    solve is a real-time iteration (Planner.solve), and an iterate that stops short of
    convergence ends the rounds (the next sample goes on from it). Returns the plan and
    its smallest clearance over the forecast when the last screen was of it (None: not
    known)."""
    config, forecast = planner.config, segment.forecast
    reference = plan.trajectory.restrict(segment.t_begin, segment.duration)
    chosen = set(seen or ())
    for round_ in range(rounds):
        screened = screen(forecast, reference, config.geometry, config.threshold,
                          config.obstacle_slots) if forecast is not None else None
        subset = None if screened is None else screened.subset
        settled = (screened is None or screened.covered(np.fromiter(chosen, float))) and \
            limit_excess(plan.trajectory, config.lower, config.upper) <= LIMIT_SETTLED and \
            (not settle_breaks or breaks.settled(planner.model, plan.trajectory, plan.breaks))
        if (settled and (round_ > 0 or seen is not None)) or late():
            return plan, None if screened is None else screened.lowest
        chosen |= set() if subset is None else set(subset.times)
        screened_segment = dataclasses.replace(segment, forecast=subset, x0=None)
        attempt = planner.solve(screened_segment, warm=plan, reference=reference, alpha=alpha,
                                rescue=rescue, iterate=iterate)
        if attempt.status == ITERATE:
            return attempt, None
        if not attempt.success and not late():  # a warm start far from the optimum can stall
            attempt = planner.solve(screened_segment, reference=reference, alpha=alpha,
                                    rescue=rescue)
        unchanged = attempt.success and plan.success and np.allclose(
            attempt.trajectory.coefficients, reference.coefficients, rtol=0.0, atol=UNCHANGED)
        plan, reference = attempt, attempt.trajectory
        if unchanged:
            break  # the same problem again: another round would return the same plan
    return plan, None
