"""The numbers of one planning problem: the parameter vector p of the NLP (planning.formulation.nlp), its
bounds for a goal, start points, and the motion a point x of the NLP stands for. A mixin of
planning.penalty.solver.Planner (which needs `config`, `model` and `nlp`), shared by the penalty
loop and the anytime SQP (planning.anytime)."""

from __future__ import annotations

import numpy as np

from planning.formulation.breaks import even_breaks, power_breaks
from planning.formulation.limits import END_MARGIN, goal_limit_signs, quotient_turning_points
from planning.formulation.nlp import PlanningNLP, turning_slots
from planning.formulation.quadrature import split_nodes
from planning.formulation.trajectory import PolynomialTrajectory
from planning.types import ObstacleForecast


class ProblemNumbers:
    """Parameters, bounds, start points and motions of the planning NLP."""

    def parameters(self, q0, qd0, duration: float, goal, forecast: ObstacleForecast | None,
                   t_begin: float = 0.0, reference: PolynomialTrajectory | None = None,
                   alpha: float | None = None) -> np.ndarray:
        """Pack the parameter vector p; obstacle samples outside (t_begin, t_end] weigh 0;
        the joint limits are constrained at the turning points of `reference` (a motion
        on the same horizon, e.g. the previous solution), the split quadrature's breaks
        put at its power's sign changes (evenly without a reference)."""
        k = self.config.obstacle_slots
        centres, s_obs, weight = np.zeros((k, 3)), np.zeros(k), np.zeros(k)
        if forecast is not None:
            s = (np.asarray(forecast.times) - t_begin) / duration
            keep = np.flatnonzero((s > 1e-12) & (s <= 1 + 1e-12))
            m = len(keep)
            if m > k:  # pass a screened forecast (planning.formulation.screening) instead
                raise ValueError(f"{m} obstacle samples on the horizon, the NLP has {k} slots")
            centres[:m], s_obs[:m], weight[:m] = forecast.centres[keep], s[keep], 1.0
        turning, v_turning, signs = self.turning_points(goal, reference)
        alpha = self.config.penalty_weight if alpha is None else alpha
        return np.concatenate([q0, qd0, [duration], goal, centres.ravel(), s_obs, weight,
                               *_slots(turning), signs + (signs == 0), *_slots(v_turning),
                               [alpha], self.breaks(reference)])

    def breaks(self, reference: PolynomialTrajectory | None) -> np.ndarray:
        """The split quadrature's breaks for a reference motion (none for other rules)."""
        count = self.config.power_breaks if self.config.energy_quadrature == "split" else 0
        if not count or reference is None:
            return even_breaks(count)
        return power_breaks(self.model, reference, count)

    def turning_points(self, goal, reference: PolynomialTrajectory | None):
        """Where the limits are enforced beyond the fixed samples: q's turning points (dof, degree - 1)
        and those of the goal-limit quotient (planning.formulation.limits), NaN for none; and the
        per-joint goal-limit signs."""
        dof, (extrema, order, slots) = self.model.dof, turning_slots(self.config)
        signs = self.goal_signs(goal)
        if reference is None:
            return (np.full((dof, extrema), np.nan), np.full((dof, slots), np.nan), signs)
        turning = reference.turning_points()
        turning[(signs != 0)[:, None] & (turning > 1 - END_MARGIN)] = np.nan
        v_turning = quotient_turning_points(reference, np.asarray(goal, float), signs,
                                            order, slots)
        return turning, v_turning, signs

    def bounds(self, goal, nlp: PlanningNLP | None = None) -> tuple[np.ndarray, np.ndarray]:
        """lbg, ubg for this goal: the quotient rows hold (>= 0) where it is on a limit."""
        nlp = nlp or self.nlp
        lbg, ubg = nlp.lbg.copy(), nlp.ubg.copy()
        signs = self.goal_signs(goal)
        for j in np.flatnonzero(signs):
            lbg[nlp.quotient_rows[int(j)]] = 0.0
        return lbg, ubg

    def goal_signs(self, goal) -> np.ndarray:
        """planning.formulation.limits.goal_limit_signs of a goal, kept per goal (read-only): a re-plan
        asks for them several times."""
        return self._goal_entry(goal)[0]

    def _goal_limits(self, goal) -> tuple[int, ...]:
        """The joints whose goal is on a limit (kept with the goal's signs)."""
        return self._goal_entry(goal)[1]

    def _goal_entry(self, goal) -> tuple[np.ndarray, tuple[int, ...]]:
        cache = self.__dict__.setdefault("_goal_signs", {})
        key = tuple(np.asarray(goal, float).tolist())
        if key not in cache:
            if len(cache) > 64:
                cache.clear()
            signs = goal_limit_signs(goal, self.config.lower, self.config.upper)
            signs.flags.writeable = False
            cache[key] = signs, tuple(int(j) for j in np.flatnonzero(signs))
        return cache[key]

    def initial_guess(self, q0, qd0, duration: float, goal, bumps=None) -> np.ndarray:
        """A cubic that reaches the goal at rest, plus bumps (dof, degree - 2) in rad times
        the shapes s^(k+2) (1 - s) (k = 0..degree - 3, zero at both ends) for a multi-start;
        zero power slacks."""
        v = np.asarray(qd0, float) * duration
        d = np.asarray(goal, float) - np.asarray(q0, float) - v
        free = np.zeros((len(d), self.config.degree - 1))
        free[:, 0], free[:, 1] = 3 * d + v, -v - 2 * d
        if bumps is not None:  # s^(k+2) - s^(k+3): column k up, column k + 1 down
            free[:, :-1] += bumps
            free[:, 1:] -= bumps
        return np.concatenate([free.ravel(), np.zeros(self._slacks)])

    def trajectory(self, x: np.ndarray, q0, qd0, t_begin: float,
                   duration: float) -> PolynomialTrajectory:
        """The segment a point x of the NLP (a solution or a start point) stands for."""
        width = self.config.degree - 1
        free = np.asarray(x)[: width * self.model.dof].reshape(self.model.dof, width)
        return PolynomialTrajectory.from_free(t_begin, duration, q0, qd0, free)

    @property
    def _slacks(self) -> int:
        """Number of power slack variables (0 with a smoothed |P|)."""
        return 0 if self.config.power_smoothing > 0 else self.config.energy_samples

    def energy_nodes(self, nlp: PlanningNLP, p: np.ndarray) -> np.ndarray:
        """The energy quadrature's normalized times for parameters p (the split rule's move
        with its breaks, the tail of p)."""
        if not nlp.breaks.numel():
            return np.asarray(nlp.nodes, float)
        return np.asarray(split_nodes(_breaks(nlp, p), self.config.energy_samples)[0], float)


def _breaks(nlp: PlanningNLP, p: np.ndarray) -> np.ndarray:
    """The split quadrature's breaks in parameters p (their tail; empty for other rules)."""
    return p[len(p) - nlp.breaks.numel():]


def _slots(times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Turning-point parameters: times (NaN -> 0.5) and 0/1 flags, column-major like ca.vec."""
    real = np.isfinite(times)
    return (np.where(real, times, 0.5).ravel(order="F"),
            real.astype(float).ravel(order="F"))
