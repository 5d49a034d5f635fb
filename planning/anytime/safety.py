"""Whether a motion is safe to follow, in two compiled CasADi functions called through
buffers (no Python per sample): its clearance at every forecast sample, and how far it
leaves the joint limits (whole motion) and the torque limits (a dense grid).

- clearance: each link's distance (m) at each of CHUNK forecast samples (more are checked
  a chunk at a time; padding samples sit far away).
- motion: the worst excursion beyond the joint limits (rad; < 0: inside) over a grid of
  LIMIT_GRID points, each refined by one Newton step towards the nearest turning point (a
  polynomial's peak between grid points is then found to ~1e-8 rad, far inside
  planning.formulation.limits.LIMIT_TOLERANCE), and the worst
  |tau_i| - torque_limit_i (N m) over TORQUE_GRID points (-inf without torque limits).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np

from identification.torque_model import TorqueModel
from planning.config import PlannerConfig
from planning.formulation import compiled
from planning.formulation.clearance import symbolic_link_clearances
from planning.formulation.trajectory import PolynomialTrajectory, power_basis

CHUNK = 32  # forecast samples per call of the clearance function
LIMIT_GRID = 65
TORQUE_GRID = 65  # as planning.penalty.solver's torque check
FAR = 1e3  # m: where padding samples sit
ENERGY_POINTS = 257  # trapezoid points of the compiled dense energy


@dataclass(frozen=True)
class Safety:
    """One motion's check: clearance (m) at each forecast sample, limit excess (rad) and
    torque excess (N m); negative excesses are margins."""

    clearance: np.ndarray
    limit_excess: float
    torque_excess: float
    links: np.ndarray  # (k, links) m: each link's distance at each sample

    @cached_property
    def lowest(self) -> float:
        return float(self.clearance.min()) if len(self.clearance) else np.inf


class SafetyCheck:
    """The compiled checks of one arm, torque model and configuration."""

    def __init__(self, model: TorqueModel, config: PlannerConfig, compile_code: bool = True):
        self.config, self.dof, self.degree = config, model.dof, config.degree
        checks = [self._clearance_function(), self._motion_function(model),
                  self._energy_function(model)]
        if compile_code:  # built together
            checks = compiled.functions(checks, config.quick_build, "the safety checks")
        self._clearance, self._motion, self._energy = map(compiled.Buffered, checks)

    def energy(self, trajectory: PolynomialTrajectory) -> float:
        """The integral of |P| dt (J) by the trapezoid rule at ENERGY_POINTS even points
        (planning.formulation.energy.dense_energy's rule, compiled: what ranks the starts of a cold
        plan without numpy torques per start: (docs/realtime.md, 'planning.anytime.safety'))."""
        (out,) = self._energy(trajectory.coefficients.ravel(order="F"), [trajectory.duration])
        return float(out[0])

    def _energy_function(self, model: TorqueModel) -> ca.Function:
        c, sigma = self._coefficients(), ca.SX.sym("sigma")
        grid = np.linspace(0.0, 1.0, ENERGY_POINTS)
        states = [ca.DM(power_basis(grid, k, self.degree)) @ c.T / sigma**k for k in range(3)]
        tau = _torque(model)
        power = ca.vertcat(*[ca.dot(tau(*(m[i, :].T for m in states)), states[1][i, :].T)
                             for i in range(ENERGY_POINTS)])
        magnitude = ca.fabs(power)
        integral = sigma * ca.sum1(magnitude[1:] + magnitude[:-1]) / (2 * (ENERGY_POINTS - 1))
        return ca.Function("dense_energy", [c, sigma], [integral])

    def __call__(self, trajectory: PolynomialTrajectory, times: np.ndarray,
                 centres: np.ndarray) -> Safety:
        """Check `trajectory` against obstacle centres (k, 3) at absolute times (k,)."""
        bound = self.against(times, centres, trajectory.t_begin, trajectory.duration)
        return bound(trajectory.coefficients)

    def clearance(self, trajectory: PolynomialTrajectory, times: np.ndarray,
                  centres: np.ndarray) -> float:
        """The smallest clearance (m) of `trajectory`'s links to obstacle centres (k, 3) at
        absolute times (k,): planning.formulation.clearance.predicted_clearance, compiled."""
        bound = self.against(times, centres, trajectory.t_begin, trajectory.duration)
        return float(bound.links(trajectory.coefficients).min())

    def against(self, times: np.ndarray, centres: np.ndarray, t_begin: float,
                duration: float):
        """The check of motions on [t_begin, t_begin + duration] against one forecast, its
        samples packed once: a function of the coefficients (dof, degree + 1) -> Safety,
        whose `links` gives the clearances alone."""
        k, count = len(times), len(self.config.geometry.links)
        padded = -(-k // CHUNK) * CHUNK
        s, c = np.zeros(padded), np.full((padded, 3), FAR)
        s[:k], c[:k] = (np.asarray(times, float) - t_begin) / duration, centres
        chunks = [(start, s[start:start + CHUNK], c[start:start + CHUNK].ravel())
                  for start in range(0, k, CHUNK)]
        return _Bound(self, chunks, k, count, np.array([duration]))

    def _coefficients(self):
        return ca.SX.sym("c", self.dof, self.degree + 1)

    def _clearance_function(self) -> ca.Function:
        c, s, centres = self._coefficients(), ca.SX.sym("s", CHUNK), ca.SX.sym("o", 3, CHUNK)
        q, centre = ca.SX.sym("q", self.dof), ca.SX.sym("centre", 3)
        distances = symbolic_link_clearances(self.config.geometry, q, centre)
        links = ca.Function("links", [q, centre], [ca.vertcat(*distances)])
        basis = ca.horzcat(*[s**p for p in range(self.degree + 1)])  # CHUNK x (degree + 1)
        positions = basis @ c.T
        rows = [links(positions[j, :].T, centres[:, j]) for j in range(CHUNK)]
        return ca.Function("clearance_check", [c, s, centres], [ca.vertcat(*rows)])

    def _motion_function(self, model: TorqueModel) -> ca.Function:
        config, c, sigma = self.config, self._coefficients(), ca.SX.sym("sigma")
        grid = np.linspace(0.0, 1.0, LIMIT_GRID)
        q, slope, curvature = (ca.DM(power_basis(grid, k, self.degree)) @ c.T for k in range(3))
        half = 0.5 / (LIMIT_GRID - 1)
        safe = ca.fabs(curvature) > 1e-9
        step = ca.if_else(safe, slope / ca.if_else(safe, curvature, 1.0), 0.0)
        s_peak = ca.fmin(ca.fmax(ca.repmat(ca.DM(grid), 1, self.dof) - step,
                                 ca.repmat(ca.DM(grid - half), 1, self.dof)),
                         ca.repmat(ca.DM(grid + half), 1, self.dof))
        s_peak = ca.fmin(ca.fmax(s_peak, 0.0), 1.0)
        peaks = ca.horzcat(*[_poly(c[j, :], s_peak[:, j]) for j in range(self.dof)])
        lower, upper = (ca.repmat(ca.DM(b).T, LIMIT_GRID, 1) for b in (config.lower, config.upper))
        excess = ca.mmax(ca.vertcat(ca.vec(lower - q), ca.vec(q - upper), ca.vec(lower - peaks),
                                    ca.vec(peaks - upper)))
        torque = -np.inf
        if config.torque_limit is not None:
            tgrid = np.linspace(0.0, 1.0, TORQUE_GRID)
            states = [ca.DM(power_basis(tgrid, k, self.degree)) @ c.T / sigma**k for k in range(3)]
            tau = _torque(model)
            limit = ca.DM(config.torque_limit)
            torque = ca.mmax(ca.vertcat(*[ca.fabs(tau(*(m[i, :].T for m in states))) - limit
                                          for i in range(TORQUE_GRID)]))
        return ca.Function("motion_check", [c, sigma], [ca.vertcat(excess, torque)])


class _Bound:
    """SafetyCheck.against's check: one forecast's samples packed in chunks."""

    def __init__(self, check: SafetyCheck, chunks, k: int, count: int, sigma: np.ndarray):
        self.check, self.chunks, self.shape, self.sigma = check, chunks, (k, count), sigma

    def links(self, coefficients: np.ndarray) -> np.ndarray:
        """Each link's distance (k, links) in m at each sample."""
        c = coefficients.ravel(order="F")
        out = np.empty((len(self.chunks) * CHUNK, self.shape[1]))
        for start, chunk_s, chunk_c in self.chunks:
            (values,) = self.check._clearance(c, chunk_s, chunk_c)
            out[start:start + CHUNK] = values.reshape(CHUNK, self.shape[1])
        return out[: self.shape[0]]

    def __call__(self, coefficients: np.ndarray, links: np.ndarray | None = None) -> Safety:
        """The whole check; links: this motion's clearances if already computed."""
        links = self.links(coefficients) if links is None else links
        (motion,) = self.check._motion(coefficients.ravel(order="F"), self.sigma)
        return Safety(links.min(axis=1), float(motion[0]), float(motion[1]), links)


def _poly(row, s):
    """A polynomial (ascending coefficients, a 1 x (degree + 1) row) at the points s."""
    return sum(row[p] * s**p for p in range(row.numel()))


def _torque(model: TorqueModel) -> ca.Function:
    """The model's torque as a called (not copied) SX function of q, qd, qdd."""
    q, qd, qdd = (ca.SX.sym(name, model.dof) for name in ("q", "qd", "qdd"))
    return ca.Function("tau", [q, qd, qdd], [model.symbolic_torque(q, qd, qdd)],
                       {"never_inline": True})
