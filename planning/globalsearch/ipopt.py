"""IPOPT on the elastic planning NLP (planning.formulation.nlp, elastic=True), to
convergence: the global search's other solver (GlobalSearchOptions.solver "ipopt") and the
realtime study's independent reference. The NLP sees the obstacle samples screened from
the reference motion's clearances (planning.formulation.screening); a round re-screens from
its solution while that dips at a sample the solve did not see or leaves a joint limit
between its constrained points. Its plans' clock_ms follows the anytime SQP's clock
(planning.anytime.budget.Clock): on the nominal clock iteration_ms per IPOPT iteration and
Clock.ROUND_ITERATIONS per round, under CPU clocks the planning thread's CPU."""

from __future__ import annotations

import casadi as ca
import numpy as np

from identification.torque_model import TorqueModel
from planning.anytime.budget import Clock
from planning.anytime.safety import SafetyCheck
from planning.config import PlannerConfig
from planning.formulation.limits import LIMIT_TOLERANCE
from planning.formulation.nlp import PlanningNLP
from planning.formulation.problem import ProblemNumbers
from planning.formulation.screening import MARGIN, near_samples, on_horizon, uncovered
from planning.penalty import backends
from planning.timing import Stopwatch
from planning.types import ObstacleForecast, Segment, SegmentPlan

ROUNDS = 6  # screening rounds at most
MAX_ITERATIONS = 1000
TORQUE_TOLERANCE = 1e-6  # N m


class IpoptElastic(ProblemNumbers):
    """IPOPT's solves of the elastic NLP (torque rows included when the configuration has
    torque limits) for one torque model and configuration."""

    def __init__(self, model: TorqueModel, config: PlannerConfig):
        self.model, self.config = model, config
        self.check = SafetyCheck(model, config, config.compile_code)
        self._solvers: dict[tuple, tuple] = {}

    def prepare(self, goal) -> None:
        self._solver(goal)

    def _solver(self, goal) -> tuple:
        key = self._goal_limits(goal)
        if key not in self._solvers:
            nlp = PlanningNLP(self.model, self.config, key, elastic=True)
            problem = {"x": nlp.x, "p": nlp.p, "f": nlp.f, "g": nlp.g}
            solver = backends.solver("elastic_ipopt", "ipopt", problem, nlp.lbg == nlp.ubg,
                                     warm=False, max_iter=MAX_ITERATIONS, hessian="exact",
                                     compile_code=self.config.compile_code)
            parts = ca.Function("elastic_parts", [nlp.x, nlp.p], [nlp.energy, nlp.penalty])
            self._solvers[key] = (nlp, solver, parts)
        return self._solvers[key]

    def solve(self, segment: Segment) -> SegmentPlan:
        """One plan of the segment from segment.x0 (its coefficients; default the initial
        guess), to convergence."""
        q0, qd0, t_begin, duration, goal, forecast = (
            segment.q0, segment.qd0, segment.t_begin, segment.duration, segment.goal,
            segment.forecast)
        clock, config = Stopwatch(), self.config
        nlp, solver, parts = self._solver(goal)
        # the budgets' clock, as the SQP's (its first solve's NLP build left out, as there)
        budget = Clock(config.anytime.iteration_ms)
        times, centres = on_horizon(forecast, t_begin, duration)
        check = self.check.against(times, centres, t_begin, duration)
        x0 = self.initial_guess(q0, qd0, duration, goal) if segment.x0 is None else segment.x0
        nc = self.model.dof * (config.degree - 1)
        x = np.zeros(nlp.x.numel())
        x[:nc] = np.asarray(x0)[:nc]
        reference = self.trajectory(x, q0, qd0, t_begin, duration)
        iterations = 0
        for _ in range(ROUNDS):
            links = check.links(reference.coefficients)
            slots = near_samples(links.min(axis=1), config.threshold, config.obstacle_slots)
            p = np.concatenate([self.parameters(
                q0, qd0, duration, goal, ObstacleForecast(times[slots], centres[slots]),
                t_begin, reference, config.anytime.elastic_weight), np.zeros(nlp.guide.numel())])
            lbg, ubg = self.bounds(goal, nlp)
            used = np.zeros((config.obstacle_slots, nlp.links), bool)
            used[: len(slots)] = True
            lbg[nlp.clearance_rows][~used.ravel()] = -np.inf  # a view: empty slots free
            solution = solver(x0=x, p=p, lbg=lbg, ubg=ubg, lbx=nlp.lbx)
            stats = solver.stats()
            iterations += int(stats.get("iter_count", 0))
            budget.tick(int(stats.get("iter_count", 0)) + Clock.ROUND_ITERATIONS)
            x = np.asarray(solution["x"], float).ravel()
            reference = self.trajectory(x, q0, qd0, t_begin, duration)
            safety = check(reference.coefficients)
            dips = safety.links < config.threshold - config.penalty_tolerance
            near = links[slots] < config.threshold + MARGIN
            if safety.limit_excess <= LIMIT_TOLERANCE and \
                    not uncovered(dips, slots, near, config.obstacle_slots):
                break
        energy, penalty = (float(v) for v in parts(x, p))
        success = bool(stats["success"]) and safety.limit_excess <= LIMIT_TOLERANCE and \
            safety.torque_excess <= TORQUE_TOLERANCE
        wall, cpu = clock.read()
        return SegmentPlan(
            trajectory=reference, energy=energy, penalty=penalty, success=success,
            status="converged" if stats["success"] else str(stats["return_status"]),
            iterations=iterations, solve_ms=wall, solve_cpu_ms=cpu,
            penalty_weight=config.anytime.elastic_weight, x=x,
            multipliers=(np.asarray(solution["lam_g"], float).ravel(),
                         np.asarray(solution["lam_x"], float).ravel()),
            layout=("ipopt",) + self._goal_limits(goal), slot_times=times[slots],
            clock_ms=budget.ms())
