"""Plans and re-plans of Algorithm 2 by the anytime elastic SQP (PlannerConfig.replanner
"sqp"): clearance as rows D >= lambda with an L1 slack of fixed weight (planning.formulation.nlp,
elastic=True), solved by planning.anytime.sqp under a CPU budget, every accepted iterate checked on
the whole forecast, the joint limits and the torque limits (planning.anytime.safety).

A plan returns the best safe iterate (least energy among those keeping the threshold within
the penalty tolerance, the limits and the torques), else the one that misses the threshold
least (a minimum-violation plan: its status says by how many mm); one stopped by its budget
(planning.anytime.budget) unconverged has status ITERATE, and Algorithm 2 re-plans from it at the
next sample. The NLP sees the obstacle samples screened from the check's own clearances
(planning.formulation.screening's rule); a round re-screens where the chosen iterate dips unseen or
leaves a limit between its constrained points; the torque rows join (a second NLP, as
planning.penalty.solver's pair) when an iterate overdrives a motor.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from identification.torque_model import TorqueModel
from planning.anytime import local_model, sqp
from planning.anytime.budget import Clock, RoundCosts
from planning.anytime.candidates import TORQUE_TOLERANCE, Candidate, choose
from planning.anytime.safety import SafetyCheck
from planning.config import PlannerConfig
from planning.formulation import compiled, guidance
from planning.formulation.limits import LIMIT_TOLERANCE
from planning.formulation.nlp import PlanningNLP
from planning.formulation.problem import ProblemNumbers
from planning.formulation.screening import MARGIN, near_samples, on_horizon, uncovered
from planning.starts import start_points
from planning.types import ITERATE, ObstacleForecast, Segment, SegmentPlan

CONVERGED = "converged"
MIN_VIOLATION = "minimum violation"
ROUNDS = 4


@dataclass
class _Problem:
    """One elastic NLP (goal limits, torque rows or not) with its SQP and objective parts."""

    nlp: PlanningNLP
    sqp: sqp.AnytimeSQP
    parts: compiled.Buffered
    layout: tuple


class Anytime(ProblemNumbers):
    """The anytime SQP's plans of one torque model and configuration."""

    def __init__(self, model: TorqueModel, config: PlannerConfig, converge: bool = False):
        """converge: every solve runs to convergence (no settling, more screening rounds:
        the global search's, planning.globalsearch), given an unlimited budget."""
        self.model, self.config = model, config
        self.settled_share, self.round_cap = (0.0, 2 * ROUNDS) if converge else \
            (sqp.SETTLED_SHARE, ROUNDS)
        self.max_iterations = 200  # a round's SQP iterations at most
        self.check = SafetyCheck(model, config, config.compile_code)
        self._problems: dict[tuple, _Problem] = {}
        self._prepared: set[tuple] = set()
        self.rounds = RoundCosts()
        self._building = np.zeros(2)  # wall and CPU s spent building problems so far
        # when a list: (inputs, plan, CPU ms in the solver's evaluations and QPs, CPU ms in
        # its solves) of every warm plan (the realtime study's references and overhead)
        self.record: list | None = None

    def prepare(self, goal) -> None:
        """Build (and compile) this goal's NLPs ahead of the plans, and call each once:
        seconds, not plan time."""
        key = self._goal_limits(goal)
        if key in self._prepared:
            return
        self._prepared.add(key)
        self.problem(goal, False)
        # the torque-limited NLP (the largest C) ahead only where re-plans are timed; a quick
        # build makes it when a plan first needs it, its build not counted as plan time
        if self.config.torque_limit is not None and not self.config.quick_build:
            self.problem(goal, True)
        # a first plan pays for loading the code and the solvers' first calls
        # (docs/realtime.md, 'planning.anytime.solver'): one throw-away plan, from the goal to itself
        lower, upper = np.asarray(self.config.lower), np.asarray(self.config.upper)
        start = np.clip(np.asarray(goal, float) + 0.1, lower, upper)
        far = ObstacleForecast(np.array([0.5, 1.0]), np.full((2, 3), 10.0))
        self.solve(Segment(start, np.zeros(len(start)), 0.0, 1.0, goal, far, budget_ms=5.0))
        for problem in self._problems.values():  # the first calls' costs predict nothing
            problem.sqp.forget()
        self.rounds.clear()

    def problem(self, goal, torque: bool) -> _Problem:
        key = (self._goal_limits(goal), torque)
        if key not in self._problems:
            began = time.perf_counter(), time.thread_time()
            config = self.config if torque else dataclasses.replace(self.config,
                                                                    torque_limit=None)
            nlp = PlanningNLP(self.model, config, key[0], elastic=True)
            what = f"the anytime SQP's {'torque-limited ' if torque else ''}model"
            quick = self.config.quick_build
            build = (lambda f: compiled.function(f, quick, what)) if self.config.compile_code \
                else (lambda f: f)
            local = build(local_model.local_function(nlp, "elastic_local"))
            parts = compiled.Buffered(build(ca.Function("elastic_parts", [nlp.x, nlp.p],
                                                        [ca.vertcat(nlp.energy, nlp.penalty)])))
            self._problems[key] = _Problem(nlp, sqp.AnytimeSQP(
                local, local_model.layout_of(nlp), nlp.lbx, nlp.g.numel(), self.settled_share), parts,
                ("elastic",) + key)
            self._building += (time.perf_counter() - began[0], time.thread_time() - began[1])
        return self._problems[key]

    def solve(self, segment: Segment, warm: SegmentPlan | None = None
              ) -> tuple[SegmentPlan, float, float]:
        """One plan of the segment (cold from segment.x0, default the initial guess) or
        re-plan (warm), within segment.budget_ms on the budget's clock (default the config's
        re-plan budget); the plan and its wall and CPU time (ms, end to end)."""
        q0, qd0, t_begin, duration, goal, forecast = (
            segment.q0, segment.qd0, segment.t_begin, segment.duration, segment.goal,
            segment.forecast)
        wall, cpu = time.perf_counter(), time.thread_time()
        building = self._building.copy()  # a problem built during this plan: not its time
        config = self.config
        clock = Clock(config.anytime.iteration_ms)  # what the budget counts
        budget = config.anytime.replan_budget_ms if segment.budget_ms is None \
            else segment.budget_ms
        times, centres = on_horizon(forecast, t_begin, duration)
        if warm is None:
            x0 = self.initial_guess(q0, qd0, duration, goal) if segment.x0 is None \
                else segment.x0
            reference = self.trajectory(x0, q0, qd0, t_begin, duration)
        else:
            reference = warm.trajectory.restrict(t_begin, duration)
        torque = warm is not None and warm.layout[-1:] == (True,)
        check = self.check.against(times, centres, t_begin, duration)
        radius = sqp.COLD_RADIUS if warm is None else config.anytime.warm_radius
        best, plan, iterations, last = None, None, 0, warm
        spent = self._solver_ms()
        for _ in range(self.round_cap):
            clock.tick(Clock.ROUND_ITERATIONS)
            round_began = clock.ms()
            problem = self.problem(goal, torque)
            links = check.links(reference.coefficients)  # what the screening needs
            slots = near_samples(links.min(axis=1), config.threshold,
                                 config.obstacle_slots)
            p = np.concatenate([self.parameters(
                q0, qd0, duration, goal, ObstacleForecast(times[slots], centres[slots]),
                t_begin, reference, config.anytime.elastic_weight), self._guide(
                problem, warm if segment.guided else None, times[slots], centres[slots])])
            lbg, ubg = self._bounds(problem, goal, links[slots])
            start, lam_g, lam_x = self._start(problem, reference, times[slots], last)
            points: list[sqp.Point] = []
            reserve = self.rounds.reserve(clock)  # for packing after the solve
            solution, count = problem.sqp.solve(start, p, lbg, ubg, lam_g, budget - reserve,
                                                points.append, self.max_iterations,
                                                lam_x0=lam_x, clock=clock,
                                                per_point_ms=self.rounds.check_ms(clock),
                                                radius=radius)
            solved = clock.ms()
            iterations += count
            chosen, checked = choose(points, lambda x: self.trajectory(
                x, q0, qd0, t_begin, duration), check, config, problem.sqp.layout.v)
            chose = clock.ms()
            converged = solution.status == sqp.CONVERGED and chosen.x is solution.x
            round_plan = self._segment(problem, chosen, solution, p, times[slots],
                                    self._status(chosen, converged))
            if best is None or chosen.rank < best.rank:
                best, plan = chosen, round_plan
            last = round_plan
            more = self._needs_round(chosen, slots, links[slots])
            if more == "torque":
                torque = True
            self.rounds.record(clock, clock.ms() - chose,
                               clock.ms() - round_began - problem.sqp.loop_ms,
                               (chose - solved) / max(checked, 1))
            if not more or budget - clock.ms() < self.round_ms(clock, problem):
                break
            reference = round_plan.trajectory
        built = self._building - building
        elapsed = (1e3 * (time.perf_counter() - wall - built[0]),
                   1e3 * (time.thread_time() - cpu - built[1]))
        plan = dataclasses.replace(plan, iterations=iterations, solve_ms=elapsed[0],
                                   solve_cpu_ms=elapsed[1], clock_ms=clock.ms())
        if self.record is not None and warm is not None:
            solver, solves = self._solver_ms() - spent
            self.record.append(((segment, warm), plan, solver, solves))
        return plan, *elapsed

    def _solver_ms(self) -> np.ndarray:
        """CPU ms so far in the solvers' compiled evaluations and QPs, and in their solves."""
        problems = self._problems.values()
        return np.array([sum(problem.sqp.spent_ms for problem in problems),
                         sum(problem.sqp.solve_ms for problem in problems)])

    def round_ms(self, clock: Clock | None = None, problem: _Problem | None = None) -> float:
        """What a round of a plan with two iterations (of the problem's, else of any
        problem's) is expected to cost (planning.anytime.budget.RoundCosts)."""
        iteration = max((other.sqp.iteration_ms for other in self._problems.values()),
                        default=0.0) if problem is None else problem.sqp.iteration_ms
        return self.rounds.round_ms(clock or Clock(self.config.anytime.iteration_ms), iteration)

    def rank(self, plan: SegmentPlan) -> tuple[bool, float]:
        """Sort key of candidate plans (as planning.starts.rank, compiled): usable first,
        then the energy actually spent (dense integral) plus the clearance penalty (J)."""
        return (not plan.success, self.check.energy(plan.trajectory) + plan.penalty)

    def best_of(self, segment: Segment, warm: SegmentPlan | None, starts: int) -> SegmentPlan:
        """The best (planning.starts.rank) of the plan from `warm` and of cold plans from
        `starts` start points (planning.starts), each with segment.budget_ms of CPU: a
        multi-start re-plan (AnytimeOptions.replan_starts)."""
        plans = [] if warm is None else [self.solve(segment, warm)[0]]
        for x0 in start_points(self, segment.q0, segment.qd0, segment.duration, segment.goal,
                               starts):
            plans.append(self.solve(dataclasses.replace(segment, x0=x0))[0])
        return min(plans, key=self.rank)

    def _guide(self, problem: _Problem, warm: SegmentPlan | None, times, centres):
        """The NLP's guidance normals, from warm's motion (planning.formulation.guidance)."""
        if warm is None or not problem.nlp.guide.numel():  # unguided, or a bank without it
            return np.zeros(problem.nlp.guide.numel())
        return guidance.normals(self.config.geometry, warm.trajectory, times, centres,
                                self.config.obstacle_slots, self.config.threshold + MARGIN)

    def _bounds(self, problem: _Problem, goal, near: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The planner's bounds; the clearance rows of empty slots and of links the reference
        keeps more than MARGIN above the threshold free (their slacks leave the QP: a step
        that brings such a link near is caught by the check and re-screened)."""
        lbg, ubg = self.bounds(goal, problem.nlp)
        rows, links = problem.nlp.clearance_rows, problem.nlp.links
        used = np.zeros((self.config.obstacle_slots, links), bool)
        used[: len(near)] = near < self.config.threshold + MARGIN
        lbg[rows][~used.ravel()] = -np.inf  # a slice of lbg: a view
        return lbg, ubg

    def _needs_round(self, best: Candidate, slots, near) -> str | None:
        """Why another round: "torque" (a motor overdriven), "limits" (beyond a limit between
        the turning points constrained), "screen" (a link dips at a sample where the solve
        had no row for it)."""
        if best.safety.torque_excess > TORQUE_TOLERANCE:
            return "torque"
        if best.safety.limit_excess > LIMIT_TOLERANCE:
            return "limits"
        config = self.config
        dips = best.safety.links < config.threshold - config.penalty_tolerance
        return "screen" if uncovered(dips, slots, near < config.threshold + MARGIN,
                                     config.obstacle_slots) else None

    def _start(self, problem: _Problem, reference, slot_times, last: SegmentPlan | None):
        """The start point (the reference's free coefficients, slacks reset by the SQP) and
        the multipliers of `last` where they belong to this NLP, those of its clearance
        rows moved with their sample times."""
        nlp, layout, (n, count) = problem.nlp, problem.sqp.layout, problem.sqp.sizes
        x = np.zeros(n)
        x[:layout.nc] = reference.coefficients[:, 2:].ravel()
        lam_g, lam_x = np.zeros(count), np.zeros(n)
        if last is None or last.layout != problem.layout or not len(last.multipliers[0]):
            return x, lam_g, lam_x
        lam_g[:], lam_x[:] = last.multipliers
        rows, links, v = nlp.clearance_rows, nlp.links, layout.v
        old_g = last.multipliers[0][rows].reshape(-1, links)
        old_x = last.multipliers[1][v].reshape(-1, links)
        new_g, new_x = np.zeros_like(old_g), np.zeros_like(old_x)
        if len(last.slot_times) and len(slot_times):
            index = np.minimum(np.searchsorted(last.slot_times, slot_times),
                               len(last.slot_times) - 1)
            same = np.flatnonzero(np.abs(last.slot_times[index] - slot_times) < 1e-9)
            new_g[same], new_x[same] = old_g[index[same]], old_x[index[same]]
        lam_g[rows], lam_x[v] = new_g.ravel(), new_x.ravel()
        return x, lam_g, lam_x

    def _segment(self, problem: _Problem, chosen: Candidate, solution, p, slot_times,
                 status: str) -> SegmentPlan:
        (parts,) = problem.parts(chosen.x, p)
        last = chosen.x is solution.x
        n, count = problem.sqp.sizes
        lam_g = solution.lam_g if last else np.zeros(count)
        lam_x = solution.lam_x if last else np.zeros(n)
        detour = bool(np.any(np.abs(solution.lam_g[problem.nlp.clearance_rows]) > 1e-9))
        return SegmentPlan(
            trajectory=chosen.trajectory, energy=float(parts[0]), penalty=float(parts[1]),
            success=chosen.hard == 0, status=status,
            iterations=0, solve_ms=0.0, solve_cpu_ms=0.0,
            penalty_weight=self.config.anytime.elastic_weight, x=chosen.x,
            multipliers=(lam_g, lam_x), layout=problem.layout, slot_times=slot_times,
            detour=detour)

    def _status(self, best: Candidate, converged: bool) -> str:
        unsafe, hard = best.unsafe, best.hard
        deficit = self.config.threshold - best.safety.lowest
        if hard > 0:
            return f"limits left by {hard:.2e} (joint limits in rad, torques in N m)"
        status = CONVERGED if converged else ITERATE
        if unsafe:
            status += f", {MIN_VIOLATION}: {1e3 * deficit:.1f} mm below the threshold"
        return status
