"""Energy of a joint trajectory under a torque model (paper eqs. 15, 18), in joules."""

from __future__ import annotations

import numpy as np

from identification.torque_model import TorqueModel
from planning.formulation.trajectory import PolynomialTrajectory

# points of a segment where dense_energy reads the power: ample to rank plans 0.5 % apart
# (docs/realtime.md, 'planning.formulation.energy')
DENSE_POINTS = 513


def power(model: TorqueModel, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """Mechanical power sum_i tau_i qd_i (W) at each of n states (n, dof)."""
    return np.sum(model.torque(q, qd, qdd) * qd, axis=1)


def absolute_energy(model: TorqueModel, t: np.ndarray, q, qd, qdd) -> float:
    """Integral of |P| dt (J) by the trapezoid rule on the time grid t (s)."""
    p = np.abs(power(model, q, qd, qdd))
    return float(np.sum(0.5 * (p[1:] + p[:-1]) * np.diff(t)))


def dense_energy(model: TorqueModel, trajectory: PolynomialTrajectory,
                 points: int = DENSE_POINTS) -> float:
    """Integral of |P| dt (J) over a segment, read at `points` even points: what a plan
    spends, whatever quadrature it was planned with (a planning quadrature with few nodes
    under-counts it: the optimizer can place power between its nodes)."""
    t = trajectory.t_begin + trajectory.duration * np.linspace(0.0, 1.0, points)
    return absolute_energy(model, t, *trajectory.state(t))


def net_work(model: TorqueModel, t: np.ndarray, q, qd, qdd) -> float:
    """Integral of P dt (J), trapezoid rule on t (s). For a conservative (rigid-body) model
    it is the change of kinetic plus potential energy, whatever the path: a lower bound
    |net work| <= integral of |P| dt that no parametrization can beat."""
    p = power(model, q, qd, qdd)
    return float(np.sum(0.5 * (p[1:] + p[:-1]) * np.diff(t)))
