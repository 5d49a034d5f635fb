"""The energy + clearance-penalty NLP (paper eqs. 15-19), built once, solved by IPOPT.

Decision variables x = [free polynomial coefficients (dof x (degree - 1), row-major),
e (N)]: e_i >= |P(s_i)| is the epigraph of the absolute power, so the objective
sigma sum_i w_i e_i (planning.formulation.quadrature; the paper's w_i = 1/N, s_i = i/N)
+ alpha sum_k w_k sum_links max(0, lambda - D_link,k)^2
is smooth enough for exact derivatives. Parameters p = [q0, qd0, sigma, q_end,
obstacle centres (3 K), their normalized times s_k (K), weights w_k (K), the
normalized times of each joint's turning points (dof x (degree - 1)) and 0/1 flags
saying which of them are real, the goal-limit signs and quotient turning points
(planning.formulation.limits), alpha, and the split quadrature's breaks (planning.formulation.breaks)], so
a re-plan changes only numbers: the solver is built once and warm-started.

Joint limits hold at fixed interior samples and, exactly, at the turning points
of a reference motion (where a polynomial peaks); the solver re-solves until the
turning points of its own solution are the ones constrained.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from identification.torque_model import TorqueModel
from planning.config import RATE_MARGIN, PlannerConfig
from planning.formulation.clearance import clearance_site, symbolic_link_clearances
from planning.formulation.limits import quotient
from planning.formulation.quadrature import energy_nodes
from planning.formulation.trajectory import power_basis


def turning_slots(config: PlannerConfig) -> tuple[int, int, int]:
    """How often a joint polynomial can turn (degree - 1), the order of the goal's zero of
    q - goal at s = 1 (2 when arriving at rest) and the turning-point slots of the goal-limit
    quotient (planning.formulation.limits)."""
    extrema, order = config.degree - 1, 2 if config.rest_at_goal else 1
    return extrema, order, extrema - order


@dataclass(frozen=True)
class Site:
    """One use of a per-sample function in the rows (the torque model at a state, the link
    distances at a pose): the function (`inputs` -> `expression`, SX), its arguments in the
    NLP (expressions of x and p) and the symbol its value is in PlanningNLP.lifted_g
    (planning.anytime.local_model differentiates each site in its own arguments)."""

    kind: str
    inputs: tuple
    expression: ca.SX
    args: tuple
    output: ca.SX


class PlanningNLP:
    """Symbolic objective f(x, p) and constraints lbg <= g(x, p) <= ubg; the same rows as
    lifted_g, expressions of x, p and the outputs of its sites (each use of the torque model
    or the link distances, PlanningNLP.sites) standing for them."""

    def __init__(self, model: TorqueModel, config: PlannerConfig,
                 goal_limits: tuple[int, ...] | None = None, elastic: bool = False):
        """goal_limits: the joints whose goal-limit quotient rows are built (default: all);
        a planner builds them only for joints whose goal is on a limit (elsewhere they are
        free rows, which still cost the solver (docs/realtime.md, 'planning.formulation.nlp')).
        elastic: clearance as rows D_link,k + v_link,k >= lambda with slacks v >= 0 (lbx)
        weighing alpha w_k v_link,k in the objective (an exact L1 penalty: a fixed weight
        above the rows' multipliers gives the constrained optimum, and where no motion
        clears the forecast the least violation), instead of the quadratic penalty."""
        self.config, self.dof = config, model.dof
        dof, n, k = model.dof, config.energy_samples, config.obstacle_slots
        if config.degree < 3:
            raise ValueError(f"polynomial degree must be >= 3, got {config.degree}")
        # the split rule's breaks (planning.formulation.breaks) are parameters, its nodes expressions
        self.breaks = ca.SX.sym("breaks", config.power_breaks
                                if config.energy_quadrature == "split" else 0)
        self.nodes, self.weights = energy_nodes(config.energy_quadrature, n, self.breaks)
        free = ca.SX.sym("free", dof, config.degree - 1)
        self.slack = ca.SX.sym("e", 0 if config.power_smoothing > 0 else n)
        self.links = len(config.geometry.links)
        self.elastic = ca.SX.sym("v", k * self.links if elastic else 0)  # slot-major
        self.x = ca.vertcat(ca.vec(free.T), self.slack, self.elastic)
        q0, qd0, self.sigma, goal = (ca.SX.sym(s, d) for s, d in
                                     (("q0", dof), ("qd0", dof), ("sigma", 1), ("goal", dof)))
        obstacle, s_obs, weight = ca.SX.sym("obs", 3, k), ca.SX.sym("s_obs", k), ca.SX.sym("w", k)
        self.extrema, self.order, self.quotient_slots = turning_slots(config)
        extremum = ca.SX.sym("s_lim", dof, self.extrema)
        newton = ca.SX.sym("newton", dof, self.extrema)
        sign = ca.SX.sym("limit_sign", dof)
        v_turn = ca.SX.sym("v_turn", dof, self.quotient_slots)
        v_newton = ca.SX.sym("v_newton", dof, self.quotient_slots)
        alpha = ca.SX.sym("alpha")  # penalty weight: a parameter, raised by the solver loop
        # a guided bank's elastic rows' normals, 3 per link and slot (slot-major; 0: unguided)
        self.guide = ca.SX.sym("guide", 3 * k * self.links if elastic and config.bank.guided else 0)
        self.p = ca.vertcat(q0, qd0, self.sigma, goal, ca.vec(obstacle), s_obs, weight,
                            ca.vec(extremum), ca.vec(newton), sign, ca.vec(v_turn),
                            ca.vec(v_newton), alpha, self.breaks, self.guide)
        self.coefficients = ca.horzcat(q0, qd0 * self.sigma, free)  # column p -> s**p
        self.sites: list[Site] = []
        self._calls: list = []  # each site's value in g: a call node or its expression
        self._model, self.inline = _torque_function(model)
        self._g, self._lbg, self._ubg = [], [], []
        power = self._power(model)
        self.clearance_rows = None
        if elastic:
            slot_weights = ca.vec(ca.repmat(weight.T, self.links, 1))  # slot-major, as v
            self.penalty = alpha * ca.dot(slot_weights, self.elastic)
            self.clearance_rows = self._clearance_rows(obstacle, s_obs)
        else:
            self.penalty = alpha * self._penalty(obstacle, s_obs, weight)
        self.energy = self._energy(power)
        self.f = self.energy + self.penalty
        self._add(self.state(1.0)[0] - goal, 0.0, 0.0)  # eq. (19)
        if config.rest_at_goal:
            self._add(self.state(1.0)[1], 0.0, 0.0)
        self._joint_limits(extremum, newton)
        joints = range(dof) if goal_limits is None else goal_limits
        self.quotient_rows = {j: self._goal_limit(j, goal[j], sign[j], v_turn[j, :],
                                                  v_newton[j, :]) for j in joints}
        self.torque_rows = self._torque_limits(model, s_obs)
        self.lifted_g = ca.vertcat(*self._g)
        if self.sites:  # each site's value (its call, or its expression copied) in place
            outputs = ca.vertcat(*(site.output for site in self.sites))
            self.g, self.energy = ca.substitute([self.lifted_g, self.energy], [outputs],
                                                [ca.vertcat(*self._calls)])
            self.f = self.energy + self.penalty
        else:
            self.g = self.lifted_g
        self.lbg, self.ubg = np.array(self._lbg), np.array(self._ubg)
        self.lbx = np.concatenate([np.full(self.x.numel() - self.elastic.numel(), -np.inf),
                                   np.zeros(self.elastic.numel())])

    def state(self, s):
        """q, qd (1/s), qdd (1/s^2) of the segment at normalized time s."""
        c, sigma = self.coefficients, self.sigma
        return _poly(c, s, 0), _poly(c, s, 1) / sigma, _poly(c, s, 2) / sigma**2

    def _add(self, rows, lower, upper) -> slice:
        """Append constraint rows with bounds (scalars or per-row lists); their slice in g."""
        start = sum(r.numel() for r in self._g)
        self._g.append(rows)
        count = rows.numel()
        self._lbg += list(np.broadcast_to(lower, count))
        self._ubg += list(np.broadcast_to(upper, count))
        return slice(start, start + count)

    def _site(self, kind: str, function: ca.Function, inputs, expression, *args):
        """The symbol standing for function(*args) in the lifted rows (a new site)."""
        output = ca.SX.sym(f"{kind}_{len(self.sites)}", expression.numel())
        self.sites.append(Site(kind, tuple(inputs), expression, tuple(args), output))
        self._calls.append(function(*args))
        return output

    def _torque(self, q, qd, qdd):
        """The torque model at a state (a site)."""
        return self._site("torque", *self._model, q, qd, qdd)

    def _power(self, model: TorqueModel):
        """P(s_i) = sum_j tau_j qd_j at the N energy samples (eq. 15); keeps the torques
        for the torque limits."""
        power, self._node_torques = [], []
        for s in self.nodes:
            q, qd, qdd = self.state(s if isinstance(s, ca.SX) else float(s))
            tau = self._torque(q, qd, qdd)
            self._node_torques.append(tau)
            power.append(ca.dot(tau, qd))
        return ca.vertcat(*power)

    def _torque_limits(self, model: TorqueModel, s_obs) -> slice | None:
        """-tau_max <= tau(s) <= tau_max at s = 0, the energy samples and the obstacle
        samples (unused obstacle slots sit at s = 0: a duplicate, harmless row)."""
        limit = self.config.torque_limit
        if limit is None:
            return None
        if len(limit) != self.dof:
            raise ValueError(f"torque_limit needs {self.dof} values, got {len(limit)}")
        torques = [self._torque(*self.state(0.0)), *self._node_torques]
        torques += [self._torque(*self.state(s_obs[j]))
                    for j in range(self.config.obstacle_slots)]
        bound = np.tile(np.asarray(limit, float), len(torques))
        return self._add(ca.vertcat(*torques), -bound, bound)

    def _energy(self, power):
        """sigma sum w_i |P(s_i)| (eq. 18 with the paper's rule): epigraph slacks, or a
        smoothed |P| if configured."""
        eps, w = self.config.power_smoothing, ca.vertcat(*self.weights)
        self.epigraph = (slice(0, 0), slice(0, 0))  # rows P - e <= 0 and -P - e <= 0
        if eps > 0:
            return self.sigma * ca.dot(w, ca.sqrt(power**2 + eps**2) - eps)
        self.epigraph = (self._add(power - self.slack, -np.inf, 0.0),
                         self._add(-power - self.slack, -np.inf, 0.0))
        return self.sigma * ca.dot(w, self.slack)

    def _penalty(self, obstacle, s_obs, weight):
        """sum_k w_k sum_links max(0, lambda - D_link)^2 (eq. 17 over every moving link); the
        per-sample term is called, not copied, where the torque model is."""
        config, total = self.config, 0
        q, centre = ca.SX.sym("q", self.dof), ca.SX.sym("centre", 3)
        distances = symbolic_link_clearances(config.geometry, q, centre)
        violation = ca.Function("violation", [q, centre], [sum(
            ca.fmax(0, config.threshold - d) ** 2 for d in distances)],
            {"never_inline": not self.inline})
        for j in range(config.obstacle_slots):
            total += weight[j] * violation(self.state(s_obs[j])[0], obstacle[:, j])
        return total

    def _clearance_rows(self, obstacle, s_obs) -> slice:
        """D_link(q(s_k), c_k) + v_link,k >= lambda for every slot k and link (slot-major),
        guided: D along the link's guidance normal where it has one (clearance_site);
        a slot without a sample gets lbg = -inf per solve (Planner.bounds)."""
        inputs, distances = clearance_site(self.config.geometry, self.dof, self.guide.numel() > 0)
        function = ca.Function("distances", list(inputs), [distances],
                               {"never_inline": not self.inline})
        width = 3 * self.links  # slot j's normals, where the site takes them

        def normals(j: int) -> tuple:
            return (self.guide[width * j: width * (j + 1)],) if len(inputs) > 2 else ()

        rows = [self._site("distances", function, inputs, distances, self.state(s_obs[j])[0],
                           obstacle[:, j], *normals(j)) for j in range(self.config.obstacle_slots)]
        return self._add(ca.vertcat(*rows) + self.elastic, self.config.threshold, np.inf)

    def _joint_limits(self, extremum, newton) -> None:
        """Limits at fixed interior samples and at the (Newton-corrected) turning points."""
        config, c = self.config, self.coefficients
        for s in np.arange(1, config.limit_samples + 1) / (config.limit_samples + 1):
            self._add(_poly(c, float(s), 0), config.lower, config.upper)
        for j in range(self.dof):
            for m in range(self.extrema):
                at = _newton(c[j, :], extremum[j, m], newton[j, m])
                self._add(_poly(c[j, :], at, 0), config.lower[j], config.upper[j])
        # the velocity at s = 0 is given (a row of parameters only), the acceleration is not
        inner = np.arange(1, config.rate_samples + 1) / (config.rate_samples + 1)
        for derivative, limit in ((1, config.velocity_limit), (2, config.acceleration_limit)):
            if limit is None:
                continue
            if len(limit) != self.dof:
                raise ValueError(f"rate limits need {self.dof} values, got {len(limit)}")
            bound = RATE_MARGIN * np.asarray(limit, float)
            for s in (inner if derivative == 1 else np.concatenate([[0.0], inner, [1.0]])):
                self._add(_poly(c, float(s), derivative) / self.sigma**derivative, -bound, bound)

    def _goal_limit(self, j: int, goal, sign, turning, use) -> slice:
        """Rows v >= 0 of planning.formulation.limits' quotient for joint j (at the fixed samples, at
        s = 1 and at its Newton-corrected turning points); bounds are set per solve
        (Planner.bounds): [0, inf] when the goal is on a limit, free otherwise."""
        v = ca.horzcat(*quotient([self.coefficients[j, p] for p in range(self.config.degree + 1)],
                                 goal, sign, self.order))
        samples = np.arange(1, self.config.limit_samples + 2) / (self.config.limit_samples + 1)
        rows = [_poly(v, float(s), 0) for s in samples]
        rows += [_poly(v, _newton(v, turning[m], use[m]), 0) for m in range(self.quotient_slots)]
        return self._add(ca.vertcat(*rows), -np.inf, np.inf)

    def functions(self) -> tuple[ca.Function, ca.Function, ca.Function]:
        """Numeric (f, grad f)(x, p), (g, jacobian g)(x, p) and (energy, penalty)(x, p)."""
        f = ca.Function("objective", [self.x, self.p], [self.f, ca.gradient(self.f, self.x)])
        g = ca.Function("constraints", [self.x, self.p], [self.g, ca.jacobian(self.g, self.x)])
        parts = ca.Function("objective_parts", [self.x, self.p], [self.energy, self.penalty])
        return f, g, parts


def _torque_function(model: TorqueModel) -> tuple[tuple, bool]:
    """The model's torque tau(q, qd, qdd): (its SX function, inputs, expression), and whether
    the NLP copies its expression into every sample (inline) or calls it there (a call node:
    one copy of the function and of its derivatives in the generated C, the NLP's code no
    longer grows with the model times the samples)."""
    q, qd, qdd = (ca.SX.sym(name, model.dof) for name in ("q", "qd", "qdd"))
    tau = model.symbolic_torque(q, qd, qdd)
    inline = ca.Function("torque", [q, qd, qdd], [tau]).n_instructions() <= INLINE_INSTRUCTIONS
    function = ca.Function("torque", [q, qd, qdd], [tau], {"never_inline": not inline})
    return (function, (q, qd, qdd), tau), inline


# a small torque model is inlined (faster solves), a large one called at each sample (its C
# would be too large to compile) (docs/realtime.md, 'planning.formulation.nlp')
INLINE_INSTRUCTIONS = 400


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
    """d^k q / ds^k at one normalized time s (number or CasADi scalar) of ascending
    coefficients (rows x degree+1)."""
    degree = coefficients.shape[1] - 1
    if isinstance(s, float):
        return coefficients @ ca.DM(power_basis(np.array([s]), derivative, degree).T)
    column = []
    for p in range(degree + 1):
        factor = float(np.prod(np.arange(p - derivative + 1, p + 1))) if derivative else 1.0
        column.append(factor * s ** (p - derivative) if p >= derivative else 0)
    return coefficients @ ca.vertcat(*column)
