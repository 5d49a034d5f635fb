"""What the energy-optimal planner is compared with.

- A minimum-jerk motion with the same boundary conditions (rest to rest).
- scipy `minimize(method="trust-constr")` on the very same NLP with
  finite-difference gradients: closest to the authors' MATLAB fmincon set-up.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.optimize import BFGS, NonlinearConstraint, minimize

from planning.penalty.solver import Planner


@dataclass(frozen=True)
class MinimumJerk:
    """Rest-to-rest quintic q(s) = q0 + (goal - q0)(10 s^3 - 15 s^4 + 6 s^5); rad, s."""

    start: np.ndarray
    goal: np.ndarray
    duration: float

    def state(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q (rad), qd (rad/s), qdd (rad/s^2), each (n, dof), at times t (s)."""
        s = np.atleast_1d(np.asarray(t, float))[:, None] / self.duration
        delta = np.asarray(self.goal) - np.asarray(self.start)
        shape = 10 * s**3 - 15 * s**4 + 6 * s**5
        rate = (30 * s**2 - 60 * s**3 + 30 * s**4) / self.duration
        accel = (60 * s - 180 * s**2 + 120 * s**3) / self.duration**2
        return np.asarray(self.start) + delta * shape, delta * rate, delta * accel


@dataclass(frozen=True)
class ScipyResult:
    """One trust-constr solve: objective (J), wall time (ms), iterations, converged?"""

    objective: float
    solve_ms: float
    iterations: int
    success: bool
    message: str
    x: np.ndarray


def solve_trust_constr(planner: Planner, x0: np.ndarray, p: np.ndarray,
                       max_iterations: int = 1000) -> ScipyResult:
    """scipy trust-constr on the planner's NLP at parameters p, gradients by finite
    differences (objective and constraints evaluated numerically, no derivatives)."""
    objective, constraints, _ = planner.nlp.functions()

    def f(x):
        return float(objective(x, p)[0])

    def g(x):
        return np.asarray(constraints(x, p)[0]).ravel()

    limits = NonlinearConstraint(g, planner.nlp.lbg, planner.nlp.ubg, jac="2-point", hess=BFGS())
    start = time.perf_counter()
    with warnings.catch_warnings():  # BFGS updates on linear constraints warn; harmless
        warnings.simplefilter("ignore", UserWarning)
        result = minimize(f, x0, method="trust-constr", jac="2-point", hess=BFGS(),
                          constraints=[limits],
                          options={"maxiter": max_iterations, "gtol": 1e-8, "xtol": 1e-10})
    elapsed = 1e3 * (time.perf_counter() - start)
    return ScipyResult(float(result.fun), elapsed, int(result.nit), bool(result.success),
                       str(result.message), np.asarray(result.x))
