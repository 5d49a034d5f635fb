"""Where a motion's power changes sign: the breakpoints of the "split" energy quadrature.

|P| has a kink wherever P crosses zero, and a quadrature rule with nodes across a kink
converges slowly (docs/realtime.md, 'planning.formulation.breaks'). Between consecutive sign
changes |P| is as smooth as the motion, so Gauss-Legendre on each such interval is
accurate with few nodes. The breakpoints are found on a reference motion (a start point
or the previous solution) and the solve is repeated until they are those of its own
solution (planning.replanning), as for the turning points of the joint limits.
"""

from __future__ import annotations

import numpy as np

from identification.torque_model import TorqueModel
from planning.formulation.energy import power
from planning.formulation.trajectory import PolynomialTrajectory

GRID = 129  # points of normalized time where the power's sign is read
SETTLED = 0.005  # normalized time: a sign change this close to a break needs no re-solve


def even_breaks(count: int) -> np.ndarray:
    """count breaks splitting [0, 1] evenly (no reference motion known)."""
    return np.arange(1, count + 1) / (count + 1)


def sign_changes(model: TorqueModel, reference: PolynomialTrajectory) -> tuple[np.ndarray, np.ndarray]:
    """Normalized times where the reference's power changes sign (linear interpolation
    between grid points) and the power's jump across each (W, its steepness)."""
    s = np.linspace(0.0, 1.0, GRID)
    p = power(model, *reference.state(reference.t_begin + reference.duration * s))
    i = np.flatnonzero(p[:-1] * p[1:] < 0)
    return s[i] + (s[i + 1] - s[i]) * p[i] / (p[i] - p[i + 1]), np.abs(p[i + 1] - p[i])


def _steepest(model: TorqueModel, reference: PolynomialTrajectory, count: int) -> np.ndarray:
    """The reference's `count` steepest power sign changes (all when there are fewer)."""
    changes, jump = sign_changes(model, reference)
    return changes[np.argsort(-jump, kind="stable")][:count]


def power_breaks(model: TorqueModel, reference: PolynomialTrajectory, count: int) -> np.ndarray:
    """count ascending normalized times: the reference's power sign changes (the count
    steepest when there are more), the longest intervals halved for the breaks left over."""
    breaks = list(_steepest(model, reference, count))
    while len(breaks) < count:
        edges = np.concatenate([[0.0], np.sort(breaks), [1.0]])
        k = int(np.argmax(np.diff(edges)))
        breaks.append(0.5 * (edges[k] + edges[k + 1]))
    return np.sort(np.asarray(breaks, float))


def settled(model: TorqueModel, trajectory: PolynomialTrajectory, used: np.ndarray) -> bool:
    """True if each of the solution's sign changes (the len(used) steepest) is within
    SETTLED of a break the solve used: its |P| has no kink inside an interval."""
    if not len(used):
        return True
    changes = _steepest(model, trajectory, len(used))
    return bool(np.all(np.min(np.abs(changes[:, None] - used[None, :]), axis=1,
                              initial=np.inf) <= SETTLED))
