"""The energy + clearance-penalty NLP (paper eqs. 15-19), built once, solved by IPOPT.

Decision variables x = [free quartic coefficients (dof x 3, row-major), e (N)]:
e_i >= |P(i/N)| is the epigraph of the absolute power, so the objective
sigma/N sum e_i + alpha sum_k w_k (max(0, lambda - D1_k)^2 + max(0, lambda - D2_k)^2)
is smooth enough for exact derivatives. Parameters p = [q0, qd0, sigma, q_end,
obstacle centres (3 K), their normalized times s_k (K), weights w_k (K), the
normalized times of each joint's turning points (dof x 3) and 0/1 flags (dof x 3)
saying which of them are real], so a
re-plan changes only numbers: the solver is built once and warm-started.

Joint limits hold at fixed interior samples and, exactly, at the turning points
of a reference motion (where a polynomial peaks); the solver re-solves until the
turning points of its own solution are the ones constrained.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from identification import TorqueModel
from planning.clearance import symbolic_link_clearances
from planning.config import PlannerConfig
from planning.trajectory import DEGREE, power_basis

EXTREMA = DEGREE - 1  # a quartic turns at most 3 times


class PlanningNLP:
    """Symbolic objective f(x, p) and constraints lbg <= g(x, p) <= ubg."""

    def __init__(self, model: TorqueModel, config: PlannerConfig):
        self.config = config
        dof, n, k = model.dof, config.energy_samples, config.obstacle_slots
        self.dof = dof
        free = ca.SX.sym("free", dof, 3)
        slack = ca.SX.sym("e", 0 if config.power_smoothing > 0 else n)
        self.x = ca.vertcat(ca.vec(free.T), slack)
        q0, qd0, sigma, goal = (ca.SX.sym(s, d) for s, d in
                                (("q0", dof), ("qd0", dof), ("sigma", 1), ("goal", dof)))
        obstacle, s_obs, weight = ca.SX.sym("obs", 3, k), ca.SX.sym("s_obs", k), ca.SX.sym("w", k)
        extremum, newton = ca.SX.sym("s_lim", dof, EXTREMA), ca.SX.sym("newton", dof, EXTREMA)
        self.p = ca.vertcat(q0, qd0, sigma, goal, ca.vec(obstacle), s_obs, weight,
                            ca.vec(extremum), ca.vec(newton))
        coefficients = ca.horzcat(q0, qd0 * sigma, free)  # (dof, 5), column p -> s**p

        def state(s):
            return (_poly(coefficients, s, 0), _poly(coefficients, s, 1) / sigma,
                    _poly(coefficients, s, 2) / sigma**2)

        power = []
        for i in range(1, n + 1):
            q, qd, qdd = state(i / n)
            power.append(ca.dot(model.symbolic_torque(q, qd, qdd), qd))
        power = ca.vertcat(*power)
        penalty = 0
        for j in range(k):
            d2, d3 = symbolic_link_clearances(config.geometry, state(s_obs[j])[0], obstacle[:, j])
            gap = ca.fmax(0, config.threshold - d2) ** 2 + ca.fmax(0, config.threshold - d3) ** 2
            penalty += weight[j] * gap
        if config.power_smoothing > 0:  # smooth |P| instead of the epigraph
            eps = config.power_smoothing
            self.energy = sigma / n * ca.sum1(ca.sqrt(power**2 + eps**2) - eps)
            g, lbg, ubg = [], [], []
        else:
            self.energy = sigma / n * ca.sum1(slack)
            g, lbg, ubg = [power - slack, -power - slack], [-np.inf] * 2 * n, [0.0] * 2 * n
        self.penalty = config.penalty_weight * penalty
        self.f = self.energy + self.penalty
        g.append(state(1.0)[0] - goal)  # eq. (19)
        lbg += [0.0] * dof
        ubg += [0.0] * dof
        # End velocity: free, but pointing inward when the goal lies on a joint limit
        # (bounds set per solve; see Planner.bounds). Replaces a turning-point constraint
        # at s -> 1, which would be degenerate next to the goal equality.
        self.end_velocity_rows = slice(sum(x.numel() for x in g), sum(x.numel() for x in g) + dof)
        g.append(state(1.0)[1])
        lbg += [-np.inf] * dof
        ubg += [np.inf] * dof
        if config.rest_at_goal:
            g.append(state(1.0)[1])
            lbg += [0.0] * dof
            ubg += [0.0] * dof
        for s in np.arange(1, config.limit_samples + 1) / (config.limit_samples + 1):
            g.append(_poly(coefficients, float(s), 0))
            lbg += list(config.lower)
            ubg += list(config.upper)
        for j in range(dof):  # limits at the motion's own turning points (parameters)
            for m in range(EXTREMA):
                g.append(_poly(coefficients[j, :], _newton(coefficients[j, :], extremum[j, m],
                                                            newton[j, m]), 0))
                lbg.append(config.lower[j])
                ubg.append(config.upper[j])
        self.g = ca.vertcat(*g)
        self.lbg, self.ubg = np.array(lbg), np.array(ubg)

    def functions(self) -> tuple[ca.Function, ca.Function, ca.Function]:
        """Numeric f(x, p), grad f(x, p), g(x, p), jacobian g(x, p) for checks and baselines."""
        f = ca.Function("objective", [self.x, self.p], [self.f, ca.gradient(self.f, self.x)])
        g = ca.Function("constraints", [self.x, self.p], [self.g, ca.jacobian(self.g, self.x)])
        parts = ca.Function("objective_parts", [self.x, self.p], [self.energy, self.penalty])
        return f, g, parts


def _newton(coefficients, s, use):
    """One Newton step from s towards the turning point q'(s) = 0 of this motion (when
    use = 1), at most 0.1 long and clamped to [0, 1]: a reference turning point that is
    slightly off still constrains the current peak to second order."""
    slope, curvature = _poly(coefficients, s, 1), _poly(coefficients, s, 2)
    safe = ca.fabs(curvature) > 1e-3
    step = ca.if_else(safe, slope / ca.if_else(safe, curvature, 1.0), 0.0)
    step = ca.fmin(ca.fmax(use * step, -0.1), 0.1)
    return ca.fmin(ca.fmax(s - step, 0.0), 1.0)


def _poly(coefficients, s, derivative: int):
    """d^k q / ds^k at one normalized time s (number or CasADi scalar)."""
    if isinstance(s, float):
        return coefficients @ ca.DM(power_basis(np.array([s]), derivative).T)
    terms = [ca.DM.ones(1), s, s**2, s**3, s**4]
    factors = {0: [1, 1, 1, 1, 1], 1: [0, 1, 2, 3, 4], 2: [0, 0, 2, 6, 12]}[derivative]
    column = ca.vertcat(*[f * terms[max(p - derivative, 0)] if f else 0 for p, f in
                          enumerate(factors)])
    return coefficients @ column
