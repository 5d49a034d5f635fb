"""Dynamic re-planning, paper Algorithm 2.

The obstacle is observed at K samples t_k = k T / K. At each sample its future
path is predicted (constant velocity from the last two observations); when the
current plan would bring a link within the threshold of that prediction, and the
prediction differs from the one the current plan was made with (otherwise the
solve would return the same plan), the arm re-plans from its current state
(position, velocity, remaining time). A re-plan that fails (other than by missing a
deadline) leaves the arm on its last plan and is tried again at the next sample. The
executed trajectory is the concatenation of the segments actually followed.

With real-time iterations (PlannerConfig.replan_iterations) a re-plan is a capped
feasible-SQP step from the last plan; while the plan followed is such an unconverged
iterate, the arm re-plans at every sample, going on from it until it converges.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from planning import breaks
from planning.clearance import link_clearances
from planning.config import Scenario
from planning.errors import PlanningError
from planning.limits import LIMIT_TOLERANCE, limit_excess
from planning.obstacle import predict_linear
from planning.realtime_iteration import ITERATE
from planning.screening import screen
from planning.solver import ObstacleForecast, Planner, SegmentPlan
from planning.starts import rank, start_points

TRIGGER_TOLERANCE = 1e-3  # m: predicted dips smaller than this do not trigger a re-plan
PREDICTION_TOLERANCE = 1e-3  # m: a forecast this close to the last one brings nothing new
LIMIT_SETTLED = 1e-8  # rad: a plan this close to its limits (dense grid) needs no re-solve
UNCHANGED = 1e-9  # rad: a re-solve that moves no coefficient further has settled
DEADLINE = "deadline exceeded"  # status of a re-plan abandoned at its deadline
LATE = " (converged late)"  # ... whose last solve succeeded (converged, or a real-time
# iterate within the constraints): the next re-plan starts from it


@dataclass(frozen=True)
class Execution:
    """What the arm did: the segments followed and when each was planned (s)."""

    segments: tuple[SegmentPlan, ...]
    replan_times: tuple[float, ...]
    solve_ms: tuple[float, ...]  # wall time of every plan and re-plan, end to end (plan_segment)
    failures: tuple[str, ...]  # IPOPT status of a failed first plan (the result is unusable)
    replan_failures: tuple[str, ...] = ()  # failed re-plans: the arm kept its last plan
    solve_cpu_ms: tuple[float, ...] = ()  # CPU time of the planning thread, per solve_ms entry


def plan_segment(planner: Planner, q0, qd0, t_begin: float, duration: float, goal,
                 forecast: ObstacleForecast | None, warm: SegmentPlan | None = None,
                 rounds: int = 4, x0: np.ndarray | None = None,
                 deadline_ms: float | None = None, settle_breaks: bool = True,
                 iterate: bool = False) -> tuple[SegmentPlan, float, float]:
    """Plan one segment: screened solves (see _screened), with the penalty weight raised
    while the solution still dips below the threshold (exterior penalty method).

    deadline_ms: CPU time (ms) after which no further solve starts; a plan that took longer
    is returned unsuccessful with status DEADLINE (it would arrive too late to be followed).
    Under a deadline no solve goes on with IPOPT when the fast solver cannot finish it (its
    answer would come too late: planning.solver.Planner._solve).
    settle_breaks: re-solve until the split quadrature's breaks are the plan's own power sign
    changes (False: solved once with those of the start; plan_multistart settles the best).
    iterate: a re-plan of Algorithm 2 with real-time iterations (config.replan_iterations):
    its warm solve is capped and its iterate (status ITERATE) returned if it keeps the
    threshold and the limits; otherwise it is solved out from there as without them.

    Without a warm start, the problem with the obstacle is solved directly from a start
    point x0 (default: the planner's initial guess), whose motion is the screening
    reference. (Solving the unobstructed optimum first and going on from it, as before,
    measured on the UR5: 24 iterations, then a warm obstacle solve stalling at its 60-
    iteration cap, then a cold restart, 350 ms; directly: 18 + 6 iterations, 85-113 ms; on
    the Lynxmotion 80-95 -> 50-66 ms.) Returns
    the plan and the wall and CPU time (ms, planning thread) of the whole call, end to end:
    solves, screening, checks and bookkeeping.
    """
    planner.prepare(goal)  # the solvers for this goal, built once: not part of a plan's time
    clock = _Clock()
    config = planner.config
    alpha = config.penalty_weight if warm is None else warm.penalty_weight
    replan = warm is not None  # a warm plan beyond the limits is refused: its caller keeps one
    if warm is None and forecast is not None:
        x0 = planner.initial_guess(q0, qd0, duration, goal) if x0 is None else x0
        # each start point of its own: the obstacle problem solved from it directly (solving
        # the unobstructed problem first would bring every start to the same optimum,
        # measured: 8 start points, one plan on most random scenarios)
        reference = planner.trajectory(x0, q0, qd0, t_begin, duration)
        subset = screen(forecast, reference, config.geometry, config.threshold,
                        config.obstacle_slots).subset
        warm = planner.solve(q0, qd0, duration, goal, subset, t_begin, reference=reference,
                             alpha=alpha, x0=x0)
        seen = set(subset.times) if warm.success else None
    elif warm is None:
        warm = planner.solve(q0, qd0, duration, goal, None, t_begin, alpha=alpha, x0=x0)
        seen = set()  # a failed unobstructed solve is reported as it is
    else:
        seen = None
    budget = np.inf if deadline_ms is None else deadline_ms
    iterate = iterate and replan and config.replan_iterations is not None
    while True:
        plan, lowest = _screened(planner, q0, qd0, t_begin, duration, goal, forecast, warm,
                                 seen, alpha, rounds, lambda: clock.cpu_ms() > budget,
                                 settle_breaks, rescue=deadline_ms is None, iterate=iterate)
        if clock.cpu_ms() > budget:
            status = DEADLINE + (LATE if plan.success else "")
            return dataclasses.replace(plan, success=False, status=status), *clock.read()
        if plan.status == ITERATE:
            if _keeps_clear(planner, plan, forecast, lowest) and \
                    _within_limits(plan, config, replan).success:
                return plan, *clock.read()
            # it dips below the threshold or leaves a limit: solved out from it, as without
            # real-time iterations (measured: following such iterates, the threshold was
            # broken by up to 6.6 cm on 3 of the 20 random scenarios)
            iterate, warm, seen = False, plan, None
            continue
        if forecast is None or alpha >= config.max_penalty_weight or not plan.success:
            return _within_limits(plan, config, replan), *clock.read()
        if _keeps_clear(planner, plan, forecast, lowest):
            return _within_limits(plan, config, replan), *clock.read()
        alpha = min(alpha * config.penalty_growth, config.max_penalty_weight)
        warm, seen = plan, None


def _keeps_clear(planner: Planner, plan: SegmentPlan, forecast: ObstacleForecast | None,
                 lowest: float | None) -> bool:
    """True if the plan keeps the threshold (within the penalty tolerance) of the forecast;
    lowest: its smallest clearance if the screening already knows it."""
    if forecast is None:
        return True
    if lowest is None:
        lowest = _predicted_clearance(planner, plan, forecast)
    return lowest >= planner.config.threshold - planner.config.penalty_tolerance


def _within_limits(plan: SegmentPlan, config, warm: bool) -> SegmentPlan:
    """The plan, unsuccessful if it leaves the joint limits by more than LIMIT_TOLERANCE: its
    rounds (_screened) can end before the limits at its turning points settle (measured: a
    re-plan 1.4 mrad beyond a limit followed in Algorithm 2, its executed motion infeasible).
    Applied to warm plans (re-plans, polishing, settling), whose callers keep the plan they
    started from; a cold plan is returned as it is and the result's checks report it."""
    if not warm or not plan.success:
        return plan
    excess = limit_excess(plan.trajectory, config.lower, config.upper)
    if excess <= LIMIT_TOLERANCE:
        return plan
    return dataclasses.replace(plan, success=False,
                               status=f"joint limits exceeded by {excess:.2e} rad")


class _Clock:
    """Wall and CPU time (ms, this thread) since it was made."""

    def __init__(self):
        self.wall, self.cpu = time.perf_counter(), time.thread_time()

    def cpu_ms(self) -> float:
        return 1e3 * (time.thread_time() - self.cpu)

    def read(self) -> tuple[float, float]:
        return 1e3 * (time.perf_counter() - self.wall), self.cpu_ms()


def plan_multistart(planner: Planner, q0, qd0, t_begin: float, duration: float, goal,
                    forecast: ObstacleForecast | None, count: int | None = None
                    ) -> tuple[SegmentPlan, float, float, list[SegmentPlan]]:
    """The best of `count` (default config.starts) cold plans of one segment (plan_segment
    from each start point of planning.starts), ranked converged first, then within the joint
    limits, then by the energy they spend (planning.starts.rank); total wall and CPU ms; all
    the cold plans. With the split quadrature only the best start's plan is re-solved until
    its breaks settle (measured on the random scenarios: settling every start's took 2-10
    times the CPU of a Gauss plan).
    With config.polish the best distinct plans are re-solved by planner.polisher (see
    _polished)."""
    count = planner.config.starts if count is None else count
    split = planner.config.energy_quadrature == "split"
    if planner.polisher is not None:
        planner.polisher.prepare(goal)  # its solvers' build is not part of a plan's time
    plans, wall, cpu = [], 0.0, 0.0
    for x0 in start_points(planner, q0, qd0, duration, goal, count):
        plan, ms, cpu_ms = plan_segment(planner, q0, qd0, t_begin, duration, goal, forecast,
                                        x0=x0, settle_breaks=not split)
        plans.append(plan)
        wall, cpu = wall + ms, cpu + cpu_ms
    clock = _Clock()  # the ranking (a dense integral per plan) and polishing are plan time
    ranked = sorted(plans, key=lambda plan: rank(planner, plan))
    best = ranked[0]
    if split and best.success:
        settled, _, _ = plan_segment(planner, q0, qd0, t_begin, duration, goal, forecast,
                                     warm=best)
        best = settled if settled.success else best
    if planner.polisher is not None:
        best = _polished(planner, best, ranked, (q0, qd0, t_begin, duration, goal, forecast))
    ms, cpu_ms = clock.read()
    return best, wall + ms, cpu + cpu_ms, plans


DISTINCT = 1e-3  # rad: cold plans whose coefficients all agree this closely are one optimum


def _polished(planner: Planner, best: SegmentPlan, ranked: list[SegmentPlan],
              segment: tuple) -> SegmentPlan:
    """The plan that spends least of `best` and the config.polish best distinct converged
    plans of `ranked`, each solved again, warm from its motion, by planner.polisher (the
    split quadrature at config.polish_samples nodes, breaks settled). The many starts
    search on the planner's cheaper rule; the few that are polished spend what they plan."""
    picked: list[SegmentPlan] = []
    for plan in ranked:
        if len(picked) == planner.config.polish or not plan.success:
            break
        if all(np.max(np.abs(plan.trajectory.coefficients - other.trajectory.coefficients))
               > DISTINCT for other in picked):
            picked.append(plan)
    candidates = [best]
    for plan in picked:
        polished, _, _ = plan_segment(planner.polisher, *segment, warm=plan)
        if polished.success:
            candidates.append(polished)
    return min(candidates, key=lambda plan: rank(planner, plan))


def _screened(planner: Planner, q0, qd0, t_begin, duration, goal, forecast, plan,
              seen: set | None, alpha: float, rounds: int,
              late=lambda: False, settle_breaks: bool = True,
              rescue: bool = True, iterate: bool = False) -> tuple[SegmentPlan, float | None]:
    """Solve with the obstacle samples screened on a reference (`plan`, re-expressed on
    this horizon) and the limits at its turning points; re-screen on the result until
    the samples where it dips were seen by its solves (Screen.covered), it keeps the
    limits and (settle_breaks) the split quadrature's breaks are its own (planning.breaks).
    seen: the obstacle sample times `plan` was solved with, if it solves this very problem
    (same horizon and alpha: then it may be settled without a further solve); None if not.
    late(): True once no further solve may start (a deadline); rescue: whether a solve the
    fast solver cannot finish goes on with IPOPT (not under a deadline); iterate: the warm
    solve is a real-time iteration (Planner.solve), and an iterate that stops short of
    convergence ends the rounds (the next sample goes on from it). Returns the plan and
    its smallest clearance over the forecast when the last screen was of it (None: not
    known)."""
    config = planner.config
    reference, chosen = plan.trajectory.restrict(t_begin, duration), set(seen or ())
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
        attempt = planner.solve(q0, qd0, duration, goal, subset, t_begin, warm=plan,
                                reference=reference, alpha=alpha, rescue=rescue,
                                iterate=iterate)
        if attempt.status == ITERATE:
            return attempt, None
        if not attempt.success and not late():  # a warm start far from the optimum can stall
            attempt = planner.solve(q0, qd0, duration, goal, subset, t_begin,
                                    reference=reference, alpha=alpha, rescue=rescue)
        unchanged = attempt.success and plan.success and np.allclose(
            attempt.trajectory.coefficients, reference.coefficients, rtol=0.0, atol=UNCHANGED)
        plan, reference = attempt, attempt.trajectory
        if unchanged:
            break  # the same problem again: another round would return the same plan
    return plan, None


def check_start(planner: Planner, scenario: Scenario) -> None:
    """Raise PlanningError if the arm starts within the threshold of the obstacle."""
    if scenario.obstacle is None:
        return
    clearance = link_clearances(planner.config.geometry, np.asarray([scenario.start]),
                                scenario.obstacle.position(0.0)).min()
    if clearance < planner.config.threshold:
        raise PlanningError(f"start is inside the obstacle threshold: clearance "
                            f"{clearance:.4f} m < {planner.config.threshold} m")


def execute(planner: Planner, scenario: Scenario, replan: bool = True,
            avoid: bool = True, starts: int | None = None,
            first_start: np.ndarray | None = None) -> Execution:
    """Run Algorithm 2 on the scenario.

    replan=False follows the first plan throughout; avoid=False ignores the obstacle
    (the energy-optimal motion without obstacle, paper Fig. 9 red line); starts: of the
    first plan (default config.starts, planning.starts), or first_start: its one start point.
    """
    scenario.validate(planner.config)
    obstacle, goal, T = scenario.obstacle if avoid else None, scenario.goal, scenario.duration
    if avoid:
        check_start(planner, scenario)
    forecast = None if obstacle is None else forecast_at(obstacle, 0.0)
    if first_start is None:
        plan, ms, cpu, _ = plan_multistart(planner, scenario.start, scenario.start_velocity,
                                           0.0, T, goal, forecast, starts)
    else:
        plan, ms, cpu = plan_segment(planner, scenario.start, scenario.start_velocity, 0.0, T,
                                     goal, forecast, x0=first_start)
    segments, times, solve_ms, solve_cpu = [plan], [0.0], [ms], [cpu]
    failures, replan_failures = ([] if plan.success else [plan.status]), []
    if obstacle is None or not replan:
        return Execution(tuple(segments), tuple(times), tuple(solve_ms), tuple(failures),
                         (), tuple(solve_cpu))
    planned_with, latest = forecast, plan  # latest: the newest successful solve (converged
    # or a real-time iterate, planning.realtime_iteration.ITERATE), the next re-plan's warm start
    for t in obstacle.sample_times[:-1]:
        forecast = forecast_at(obstacle, t)
        iterating = plan.status == ITERATE  # the last re-plan stopped short: go on from it
        if not iterating and (not _stale(planner, plan, forecast)
                              or _same_prediction(planned_with, forecast)):
            continue  # safe, or nothing new to plan with: the last plan already saw this
        q, qd, _ = plan.trajectory.state(t)
        new, ms, cpu = plan_segment(planner, q[0], qd[0], t, T - t, goal, forecast,
                                    warm=latest, deadline_ms=planner.config.replan_deadline_ms,
                                    iterate=True)
        solve_ms.append(ms)
        solve_cpu.append(cpu)
        if not new.success:
            replan_failures.append(new.status)
            if new.status.startswith(DEADLINE):
                # tried again when the prediction changes (retried at every sample, re-plans
                # that could not meet the deadline made the bench's quick run take minutes)
                planned_with = forecast
            if new.status.endswith(LATE):  # too late to follow, yet the best start point
                latest = new
            # keep following the last good plan; a re-plan that failed otherwise is tried
            # again at the next sample: that plan never saw this forecast (measured: a
            # re-plan refused 0.45 mrad beyond a limit, not retried while the prediction
            # stayed the same, left the arm 2.6 cm from the obstacle)
            continue
        plan = latest = new
        planned_with = forecast
        segments.append(plan)
        times.append(float(t))
    return Execution(tuple(segments), tuple(times), tuple(solve_ms), tuple(failures),
                     tuple(replan_failures), tuple(solve_cpu))


def forecast_at(obstacle, t: float) -> ObstacleForecast:
    """Prediction at time t of the obstacle at the remaining samples, from what was seen."""
    seen = np.concatenate([[0.0], obstacle.sample_times])
    seen = seen[seen <= t + 1e-12][-2:]
    future = obstacle.sample_times[obstacle.sample_times > t + 1e-12]
    return ObstacleForecast(future, predict_linear(seen, obstacle.position(seen), future))


def _same_prediction(old: ObstacleForecast, new: ObstacleForecast) -> bool:
    """True if `new` predicts every remaining sample within PREDICTION_TOLERANCE of `old`."""
    index = np.searchsorted(old.times, new.times)
    if np.any(index >= len(old.times)) or not np.allclose(old.times[index], new.times):
        return False
    return bool(np.max(np.abs(old.centres[index] - new.centres), initial=0.0)
                <= PREDICTION_TOLERANCE)


def _stale(planner: Planner, plan: SegmentPlan, forecast: ObstacleForecast) -> bool:
    """True if the plan must be re-planned for this forecast: it comes within the threshold
    (Algorithm 2), or it was bent round the obstacle (a positive penalty) and now keeps more
    than the threshold everywhere: the obstacle has moved off its detour, whose energy a
    re-plan can save (measured: a first plan made against the obstacle standing still, never
    re-planned because it stayed clear, spent 5.06 J where a re-planned motion spent 0.23 J)."""
    clearance = _predicted_clearance(planner, plan, forecast)
    threshold = planner.config.threshold
    return clearance < threshold - TRIGGER_TOLERANCE or \
        (plan.penalty > 0.0 and clearance > threshold + TRIGGER_TOLERANCE)


def _predicted_clearance(planner: Planner, plan: SegmentPlan, forecast: ObstacleForecast):
    q = plan.trajectory.position(forecast.times)
    return link_clearances(planner.config.geometry, q, forecast.centres).min()
