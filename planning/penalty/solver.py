"""The planning NLP's solver (planning.penalty.backends: fatrop, sqpmethod or IPOPT): one
build, many solves (cold or warm-started); with real-time iterations also CasADi's feasible SQP, capped,
for the re-plans' warm solves."""

from __future__ import annotations

import dataclasses
import functools
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from identification.torque_model import TorqueModel
from planning.config import PlannerConfig
from planning.formulation.nlp import PlanningNLP
from planning.formulation.problem import ProblemNumbers, _breaks
from planning.formulation.quadrature import splits_evenly
from planning.formulation.trajectory import PolynomialTrajectory
from planning.penalty import backends, realtime_iteration
from planning.types import Segment, SegmentPlan

# a warm IPOPT rescue still unconverged after this many iterations is better restarted cold
# (docs/realtime.md, 'planning.penalty.solver')
RESCUE_WARM_ITERATIONS = 60
TORQUE_GRID = 65  # points of normalized time where a segment's torque is checked


@dataclass(frozen=True)
class _Solvers:
    """One NLP and its cold and warm solver instances, and the real-time iteration's."""

    nlp: PlanningNLP
    cold: ca.Function
    warm: ca.Function
    parts: ca.Function
    iterate: ca.Function | None = None  # feasiblesqp capped at config.penalty.replan_iterations


def _build(nlp: PlanningNLP, config: PlannerConfig, name: str) -> _Solvers:
    problem = {"x": nlp.x, "p": nlp.p, "f": nlp.f, "g": nlp.g}
    common = {"equality": nlp.lbg == nlp.ubg, "hessian": config.penalty.hessian,
              "compile_code": config.compile_code, "quick": config.quick_build}
    cold = backends.solver(f"{name}_cold", config.penalty.solver, problem, warm=False,
                           max_iter=config.penalty.max_iterations, **common)
    warm = backends.solver(f"{name}_warm", config.penalty.solver, problem, warm=True,
                           max_iter=config.penalty.warm_max_iterations, **common)
    parts = ca.Function("objective_parts", [nlp.x, nlp.p], [nlp.energy, nlp.penalty])
    iterate = None if config.penalty.replan_iterations is None else backends.solver(
        f"{name}_iterate", "feasiblesqp", problem, warm=True,
        max_iter=config.penalty.replan_iterations, **common)
    return _Solvers(nlp, cold, warm, parts, iterate)


class Planner(ProblemNumbers):
    """Energy-optimal, obstacle-penalized polynomial segments (quartic by default) for one torque model.

    Torque limits (config.torque_limit) are an active-set pair of NLPs: every solve first
    runs the NLP without torque rows; only when that optimum's torque exceeds the limit
    on a dense grid is the NLP with torque rows (built on first need) solved. A relaxed
    optimum that respects the limits is the constrained optimum, so the common case pays
    nothing (the torque rows are costly: (docs/realtime.md, 'planning.penalty.solver')).
    """

    def __init__(self, model: TorqueModel, config: PlannerConfig):
        self.config = config
        if self.config.penalty.solver not in backends.SOLVERS:  # feasiblesqp cannot solve cold
            raise ValueError(f"solver must be one of {backends.SOLVERS}, got "
                             f"'{self.config.penalty.solver}'")
        if self.config.penalty.replan_iterations is not None and self.config.penalty.replan_iterations < 1:
            raise ValueError(f"replan_iterations must be >= 1 or None, got "
                             f"{self.config.penalty.replan_iterations}")
        self.model = model
        self._relaxed: dict[tuple[int, ...], _Solvers] = {}
        self._limited: dict[tuple[int, ...], _Solvers] = {}
        self._rescue: dict[int, _Solvers] = {}
        self.solver_ms = 0.0  # wall time (ms) of all its solver calls so far: timing breakdowns

    @functools.cached_property
    def polisher(self) -> Planner | None:
        """The planner that re-solves the best cold plans with the split quadrature at
        config.penalty.polish_samples nodes (None without config.penalty.polish)."""
        config = self.config
        if not config.penalty.polish:
            return None
        if not splits_evenly(config.penalty.polish_samples, config.power_breaks):
            raise ValueError(f"polish_samples ({config.penalty.polish_samples}) must be a "
                             f"multiple of power_breaks + 1 ({config.power_breaks + 1})")
        # polishing is part of a cold plan: no re-plan deadline keeps its IPOPT rescue away
        return Planner(self.model, dataclasses.replace(
            config.with_penalty(polish=0, replan_iterations=None), energy_quadrature="split",
            energy_samples=config.penalty.polish_samples, starts=1, replan_deadline_ms=None,
            replanner="penalty"))

    @property
    def layout(self) -> tuple:
        """What fixes the NLP's rows and variables beyond the goal's limits and the torque
        rows: the energy rule and its sample count (a warm start from a plan of another
        layout takes its motion, not its multipliers)."""
        config = self.config
        return (config.energy_quadrature, config.energy_samples, config.power_smoothing > 0)

    @functools.cached_property
    def nlp(self) -> PlanningNLP:
        """The NLP with every goal-limit row and no torque rows, for callers that evaluate its
        functions with `parameters` and `bounds` (the paper reproduction's trust-constr
        baseline); the solves use the NLP for their goal (_relaxed_for)."""
        return PlanningNLP(self.model, dataclasses.replace(self.config, torque_limit=None))

    def prepare(self, goal) -> None:
        """Build the solvers for this goal ahead of the solves (planning.replanning does so
        before its clock starts): generating an NLP's code and its IPOPT rescuer's takes
        seconds (docs/realtime.md, 'planning.penalty.solver'), which
        must not land inside a plan's or a re-plan's time."""
        self._relaxed_for(goal)

    def _relaxed_for(self, goal) -> _Solvers:
        """The NLP without torque rows, with goal-limit rows for the joints whose goal is on
        a limit (PlanningNLP's goal_limits), built on first need with its IPOPT rescuer."""
        key = self._goal_limits(goal)
        if key not in self._relaxed:
            relaxed = dataclasses.replace(self.config, torque_limit=None)
            self._relaxed[key] = _build(PlanningNLP(self.model, relaxed, key), self.config,
                                        "plan")
            if self.config.compile_code and self.config.penalty.solver != "ipopt":
                self._rescuer(self._relaxed[key])
        return self._relaxed[key]

    def _torque_limited(self, goal) -> _Solvers:
        key = self._goal_limits(goal)
        if key not in self._limited:
            self._limited[key] = _build(PlanningNLP(self.model, self.config, key), self.config,
                                        "plan_torque")
        return self._limited[key]

    def torque_excess(self, trajectory: PolynomialTrajectory) -> float:
        """Largest |tau_i| - torque_limit_i (N m) on a dense grid of the segment (< 0: inside;
        -inf without limits)."""
        if self.config.torque_limit is None:
            return -np.inf
        t = trajectory.t_begin + trajectory.duration * np.linspace(0.0, 1.0, TORQUE_GRID)
        tau = self.model.torque(*trajectory.state(t))
        return float(np.max(np.abs(tau) - np.asarray(self.config.torque_limit)))

    def solve(self, segment: Segment, warm: SegmentPlan | None = None,
              reference: PolynomialTrajectory | None = None, alpha: float | None = None,
              rescue: bool = True, iterate: bool = False) -> SegmentPlan:
        """Plan the segment: from (q0, qd0) at t_begin to goal at t_begin + duration, past the
        obstacle samples of its forecast; a cold solve starts from segment.x0 (default:
        initial_guess).

        reference: a motion on the same horizon whose turning points get limit constraints
        in addition to the fixed samples (see PlanningNLP, planning.formulation.limits).
        alpha: penalty weight (J/m^2 per sample), default config.penalty_weight.
        rescue: a solve the fast solver cannot finish goes on with IPOPT (see _solve); False
        for a re-plan under a deadline, whose answer would come too late.
        iterate: a warm solve first takes config.penalty.replan_iterations feasible-SQP iterations
        and returns their iterate, status ITERATE, if it has not converged (see _solve).
        """
        q0, qd0, t_begin, duration, goal = (segment.q0, segment.qd0, segment.t_begin,
                                            segment.duration, segment.goal)
        alpha = self.config.penalty_weight if alpha is None else float(alpha)
        p = self.parameters(q0, qd0, duration, goal, segment.forecast, t_begin, reference, alpha)
        x0 = self.initial_guess(q0, qd0, duration, goal) if segment.x0 is None else segment.x0
        inputs = (q0, qd0, duration, t_begin, p, alpha, x0)
        plan = self._solve(self._relaxed_for(goal), goal, warm, inputs, rescue, iterate)
        if not plan.success or self.torque_excess(plan.trajectory) <= 0:
            return plan
        # the relaxed optimum overdrives a motor: solve again with the torque rows
        limited = self._solve(self._torque_limited(goal), goal, warm, inputs, rescue, iterate)
        return dataclasses.replace(limited, solve_ms=plan.solve_ms + limited.solve_ms,
                                   solve_cpu_ms=plan.solve_cpu_ms + limited.solve_cpu_ms)

    def _solve(self, solvers: _Solvers, goal, warm: SegmentPlan | None,
               segment: tuple, rescue: bool = True, iterate: bool = False) -> SegmentPlan:
        q0, qd0, duration, t_begin, p, alpha, x0 = segment
        lbg, ubg = self.bounds(goal, solvers.nlp)
        args = {"p": p, "lbg": lbg, "ubg": ubg}
        if warm is None:
            solver, args["x0"] = solvers.cold, x0
        else:
            solver = solvers.warm
            args.update(self._warm_start(warm, t_begin, duration, solvers.nlp, p))
        start, cpu = time.perf_counter(), time.thread_time()
        result, stats = None, None
        if iterate and warm is not None and solvers.iterate is not None:
            result, stats = realtime_iteration.step(solvers.iterate, args)
        if stats is None:  # not iterating, or the iterate is not one to follow: solve it out
            result = solver(**args)
            stats = backends.stats(solver, args, result)
        if not stats.success and self.config.penalty.solver != "ipopt" and rescue:
            # a solve the fast solver could not finish: IPOPT from the same start point (not
            # for a re-plan under a deadline: it would come too late, seconds
            # (docs/realtime.md, 'planning.penalty.solver'))
            rescue = self._rescuer(solvers)
            solver = rescue.cold if warm is None else rescue.warm
            result = solver(**args)
            stats = backends.stats(solver, args, result)
        elapsed = (1e3 * (time.perf_counter() - start), 1e3 * (time.thread_time() - cpu))
        self.solver_ms += elapsed[0]
        return self._segment(solvers, result, stats, elapsed, segment)

    def _rescuer(self, solvers: _Solvers) -> _Solvers:
        """IPOPT (built on first need, compiled like the fast solver) on the same NLP: fatrop
        at a raised penalty weight can stop short of convergence
        (docs/realtime.md, 'planning.penalty.solver')."""
        key = id(solvers)
        if key not in self._rescue:
            rescue = self.config.with_penalty(solver="ipopt", replan_iterations=None,
                                              warm_max_iterations=max(
                self.config.penalty.warm_max_iterations, RESCUE_WARM_ITERATIONS))
            self._rescue[key] = _build(solvers.nlp, rescue, "plan_rescue")
        return self._rescue[key]

    def _warm_start(self, warm: SegmentPlan, t_begin: float, duration: float,
                    nlp: PlanningNLP, p: np.ndarray) -> dict:
        """Primal-dual start: the previous plan's remaining motion re-expressed on the new
        horizon, the power slacks it implies, and the previous multipliers (torque rows,
        the last ones, zero-padded or dropped when the previous solve had none / this has
        none)."""
        rest = warm.trajectory.restrict(t_begin, duration)
        x = rest.coefficients[:, 2:].ravel()
        if self._slacks:
            q, qd, qdd = rest.state(t_begin + duration * self.energy_nodes(nlp, p))
            x = np.concatenate([x, np.abs(np.sum(self.model.torque(q, qd, qdd) * qd, axis=1))])
        rows = len(nlp.lbg)
        lam_g = np.zeros(rows)
        kept = min(rows, len(warm.multipliers[0]))
        lam_g[:kept] = warm.multipliers[0][:kept]
        if not self.config.penalty.dual_warm_start or warm.layout != self.layout:
            return {"x0": x}
        return {"x0": x, "lam_g0": lam_g, "lam_x0": warm.multipliers[1]}

    def _segment(self, solvers: _Solvers, result, stats, elapsed, segment) -> SegmentPlan:
        q0, qd0, duration, t_begin, p, alpha, _ = segment
        x = np.asarray(result["x"]).ravel()
        trajectory = self.trajectory(x, q0, qd0, t_begin, duration)
        energy, penalty = (float(v) for v in solvers.parts(x, p))
        return SegmentPlan(
            trajectory=trajectory, energy=energy, penalty=penalty,
            success=stats.success, status=stats.status,
            iterations=stats.iterations, solve_ms=elapsed[0],
            solve_cpu_ms=elapsed[1], penalty_weight=alpha, x=x,
            multipliers=(np.asarray(result["lam_g"]).ravel(), np.asarray(result["lam_x"]).ravel()),
            breaks=_breaks(solvers.nlp, p), layout=self.layout,
        )
