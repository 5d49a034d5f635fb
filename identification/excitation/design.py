"""An excitation designed for identification: a rest-to-rest finite Fourier series per joint
(Swevers et al. 1997; as in FloBaRoID and FIGAROH), the best found for a criterion
(D-optimal or the condition number).

q_j(t) = c_j + sum_l a_jl sin(l w t) + b_jl cos(l w t), w = 2 pi / duration: periodic over
the duration. At rest at t = 0, hence at t = duration: sum_l l a_jl = 0 and sum_l l^2 b_jl = 0.
Position (inside a margin), velocity and acceleration limits are linear in the coefficients
on a dense time grid. The objective is a criterion of the regressor (passed in: any columns,
e.g. identification's atoms and offsets; identification.excitation.criteria) on a coarse
grid, its gradient from the regressor's vector-Jacobian product; SLSQP from the best of seeded
random candidates that meet the limits. A clearance passed in (the robot's distance to itself
and the floor) is a constraint on the coarse grid, its gradient by finite differences; an
optimum that still touches on a dense grid between those points is walked back towards its
start (every point of the segment meets the linear limits) until it does not.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from identification.excitation.criteria import CRITERIA, Regressor, log_condition
from identification.excitation.descent import descend
from identification.excitation.fourier import FourierExcitation

CLEARANCE = 0.005  # m kept on the design grid: the closest approach may fall between its points
TIGHTEN = 0.985  # of each bound on the limit grid: 20 points a cycle miss a peak by <= 1.2 %
SHRINK, SHRINKS = 0.8, 10  # a colliding candidate's swing shrinks about its centre pose


@dataclass(frozen=True)
class ExcitationLimits:
    """Joint limits (dof,): positions (rad), speeds (rad/s) and accelerations (rad/s^2), inf
    where none; `margin`: the fraction of each joint's range kept free at either end."""

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    margin: float = 0.05

    @property
    def inner(self) -> tuple[np.ndarray, np.ndarray]:
        """The positions allowed: the range less the margin at either end (rad)."""
        pad = self.margin * (np.asarray(self.upper) - np.asarray(self.lower))
        return np.asarray(self.lower) + pad, np.asarray(self.upper) - pad

    def violation(self, q, qd, qdd) -> float:
        """Largest excess over any limit (rad, rad/s or rad/s^2; <= 0: none) of the states."""
        lo, hi = self.inner
        return float(max(np.max(q - hi), np.max(lo - q), np.max(np.abs(qd) - self.velocity),
                         np.max(np.abs(qdd) - self.acceleration)))


@dataclass(frozen=True)
class ExcitationDesign:
    """The designed excitation, the condition of its regressor on the design grid, that of
    the candidate it started from, the optimizer's iterations, SLSQP's exit status and
    message of its last run (None, "" if it never ran), and whether the design is its random
    start (no safe iterate improved on it: SLSQP failed or could not move)."""

    excitation: FourierExcitation
    condition: float
    start_condition: float
    iterations: int
    status: int | None = None
    message: str = ""
    stuck: bool = False

    @property
    def converged(self) -> bool:
        """SLSQP's last run ended at an optimum (exit status 0), not at its iteration limit
        (9) or a failed step: only then is the design an optimum rather than its best safe
        iterate so far."""
        return self.status == 0

    def convergence(self) -> str:
        """One clause saying whether the design converged."""
        if self.converged:
            return f"converged (SLSQP: {self.message}, {self.iterations} iterations)"
        return (f"not converged: SLSQP stopped with exit status {self.status} ({self.message}) "
                f"after {self.iterations} iterations; the design is its best safe iterate, not "
                "an optimum")


def _basis(t: np.ndarray, w: float, harmonics: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(len(t), 1 + 2 L) maps of one joint's [c, a_1..a_L, b_1..b_L] to q, qd, qdd."""
    lw = w * np.arange(1, harmonics + 1)
    s, c = np.sin(np.outer(t, lw)), np.cos(np.outer(t, lw))
    one, zero = np.ones((len(t), 1)), np.zeros((len(t), 1))
    return (np.hstack([one, s, c]), np.hstack([zero, c * lw, -s * lw]),
            np.hstack([zero, -s * lw**2, -c * lw**2]))


def _to_excitation(x: np.ndarray, dof: int, harmonics: int, f0: float) -> FourierExcitation:
    X = x.reshape(dof, 1 + 2 * harmonics)
    return FourierExcitation(X[:, 0].copy(), X[:, 1:1 + harmonics].copy(),
                             X[:, 1 + harmonics:].copy(), f0)


def _rest_projection(harmonics: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows of the rest equalities for one joint's coefficients: qd(0) = 0, qdd(0) = 0."""
    ls = np.arange(1, harmonics + 1, dtype=float)
    velocity = np.concatenate([[0.0], ls, np.zeros(harmonics)])
    acceleration = np.concatenate([[0.0], np.zeros(harmonics), ls**2])
    return velocity, acceleration


def _candidate(rng: np.random.Generator, limits: ExcitationLimits, bases, harmonics: int,
               centre: np.ndarray) -> np.ndarray:
    """Random 1/l-spectrum coefficients at rest at t = 0, scaled per joint to the largest swing
    about the centre pose (rad) the limits allow on the grid."""
    dof, (lo, hi), (Bq, Bqd, Bqdd) = len(limits.lower), limits.inner, bases
    rows = _rest_projection(harmonics)
    decay = np.concatenate([[0.0], 1 / np.arange(1, harmonics + 1), 1 / np.arange(1, harmonics + 1)])
    X = rng.normal(size=(dof, 1 + 2 * harmonics)) * decay
    for r in rows:  # project onto the rest equalities (the rows are orthogonal)
        X -= np.outer(X @ r / (r @ r), r)
    q, qd, qdd = X @ Bq.T, X @ Bqd.T, X @ Bqdd.T  # (dof, m)
    half = 0.5 * (q.max(axis=1) - q.min(axis=1))
    room = np.minimum(hi - centre, centre - lo)
    factor = TIGHTEN * np.minimum.reduce([room / half, limits.velocity / np.abs(qd).max(axis=1),
                                          limits.acceleration / np.abs(qdd).max(axis=1)])
    X *= factor[:, None]
    X[:, 0] = centre - factor * 0.5 * (q.max(axis=1) + q.min(axis=1))
    return X.ravel()


def _centre(rng: np.random.Generator, limits: ExcitationLimits, clearance, poses: int = 64):
    """A candidate's centre pose: the middle of the allowed range, or with a clearance the
    clearest of random poses in the middle half of it (far from the floor and itself)."""
    lo, hi = limits.inner
    middle, quarter = 0.5 * (lo + hi), 0.25 * (hi - lo)
    if clearance is None:
        return middle
    q = rng.uniform(middle - quarter, middle + quarter, (poses, len(lo)))
    return q[np.argmax(clearance(q))]


def _linear_constraints(limits: ExcitationLimits, bases, harmonics: int) -> list[dict]:
    """SLSQP's constraints: the limits on the grid (G x + h >= 0) and the rest equalities."""
    dof, k = len(limits.lower), 1 + 2 * harmonics
    lo, hi = limits.inner
    slack = 0.5 * (1 - TIGHTEN) * (hi - lo)
    blocks, offsets = [], []
    for B, bound_lo, bound_hi in ((bases[0], lo + slack, hi - slack),
                                  (bases[1], -TIGHTEN * limits.velocity, TIGHTEN * limits.velocity),
                                  (bases[2], -TIGHTEN * limits.acceleration,
                                   TIGHTEN * limits.acceleration)):
        for j in range(dof):
            for sign, bound in ((-1.0, bound_hi[j]), (1.0, bound_lo[j])):
                if np.isfinite(bound):  # sign * B x_j - sign * bound >= 0
                    block = np.zeros((len(B), dof * k))
                    block[:, j * k:(j + 1) * k] = sign * B
                    blocks.append(block)
                    offsets.append(np.full(len(B), -sign * bound))
    G, h = np.vstack(blocks), np.concatenate(offsets)
    E = np.zeros((2 * dof, dof * k))
    for j in range(dof):
        E[2 * j:2 * j + 2, j * k:(j + 1) * k] = np.vstack(_rest_projection(harmonics))
    return [{"type": "ineq", "fun": lambda x: G @ x + h, "jac": lambda x: G},
            {"type": "eq", "fun": lambda x: E @ x, "jac": lambda x: E}]


def _clearance_constraint(clearance, Dq: np.ndarray, dof: int, step: float = 1e-6) -> dict:
    """SLSQP's clearance(q(t)) - CLEARANCE >= 0 on the grid of Dq; the Jacobian through
    finite differences per joint (dof + 1 calls) and the linear basis."""
    def fun(x):
        return clearance(Dq @ x.reshape(dof, -1).T) - CLEARANCE

    def jac(x):
        q = Dq @ x.reshape(dof, -1).T
        base = clearance(q)
        dq = np.stack([(clearance(q + step * np.eye(dof)[j]) - base) / step for j in range(dof)], 1)
        return (dq[:, :, None] * Dq[:, None, :]).reshape(len(q), -1)

    return {"type": "ineq", "fun": fun, "jac": jac}


def optimize_excitation(
    limits: ExcitationLimits,
    duration: float,
    regressor: Regressor,
    clearance: Callable[[np.ndarray], np.ndarray] | None = None,
    seed: int = 0,
    harmonics: int = 5,
    candidates: int = 8,
    iterations: int = 60,
    design_points: int = 100,
    limit_points: int | None = None,
    check_points: int = 1000,
    criterion: str = "condition",
    progress: Callable[[int, int], None] | None = None,
) -> ExcitationDesign:
    """The designed excitation (see the module docstring), `duration` s long; clearance(q)
    -> (n,) is the robot's smallest distance (m) to itself or the floor at joint states
    (n, dof), <= 0 where they touch: a constraint on the design grid (gradient by finite
    differences), checked on a dense grid. criterion: what is minimized, "condition" (the
    log condition number of the normalized regressor) or "information" (log_information);
    progress(iteration, iterations), if given, is called after each optimizer iteration.
    A candidate that collides has its swing shrunk about its centre pose; ValueError if
    none is collision-free even so."""
    measure = CRITERIA[criterion]
    dof, f0 = len(limits.lower), 1.0 / duration
    w = 2 * np.pi * f0
    design_t = np.linspace(0.0, duration, design_points, endpoint=False)
    Dq, Dqd, Dqdd = _basis(design_t, w, harmonics)
    limit_points = 20 * harmonics if limit_points is None else limit_points
    bases = _basis(np.linspace(0.0, duration, limit_points, endpoint=False), w, harmonics)
    check = _basis(np.linspace(0.0, duration, check_points + 1), w, harmonics)
    k = 1 + 2 * harmonics

    def states(x, B):
        X = x.reshape(dof, k)
        return X @ B[0].T, X @ B[1].T, X @ B[2].T

    def objective(x):
        X = x.reshape(dof, k)
        value, (gq, gqd, gqdd) = measure(regressor, Dq @ X.T, Dqd @ X.T, Dqdd @ X.T, True)
        return value, (gq.T @ Dq + gqd.T @ Dqd + gqdd.T @ Dqdd).ravel()

    def safe(x) -> bool:
        q, qd, qdd = states(x, check)
        ok = limits.violation(q.T, qd.T, qdd.T) <= 1e-9
        return ok and (clearance is None or bool(np.all(clearance(q.T) > 0)))

    def shrunk(x):  # the swing shrunk about the centre pose until safe (or given up)
        for _ in range(SHRINKS):
            if safe(x):
                break
            x = x.reshape(dof, k) * np.concatenate([[1.0], np.full(k - 1, SHRINK)])
            x = x.ravel()
        return x

    rng = np.random.default_rng(seed)
    starts = [shrunk(_candidate(rng, limits, bases, harmonics, _centre(rng, limits, clearance)))
              for _ in range(candidates)]
    scored = sorted((objective(x)[0], i) for i, x in enumerate(starts) if safe(x))
    if not scored:
        raise ValueError(f"none of {candidates} random excitations is collision-free")
    start = starts[scored[0][1]]
    constraints = _linear_constraints(limits, bases, harmonics)
    if clearance is not None:
        constraints.append(_clearance_constraint(clearance, Dq, dof))
    # one BLAS thread: SLSQP's path turns on rounding, and the design must be the same
    # whatever threads the caller's BLAS runs
    with threadpool_limits(limits=1, user_api="blas"):
        best, used, last = descend(objective, start, constraints, iterations, safe, progress)

    def condition(x) -> float:
        X = x.reshape(dof, k)
        return float(np.exp(log_condition(regressor, Dq @ X.T, Dqd @ X.T, Dqdd @ X.T)))

    return ExcitationDesign(_to_excitation(best, dof, harmonics, f0), condition(best),
                            condition(start), used, None if last is None else int(last.status),
                            "" if last is None else str(last.message), best is start)
