"""Quartic joint polynomials in normalized time (paper eqs. 11, 12).

q_i(s) = sum_p c[i, p] s**p, s = (t - t_begin) / sigma in [0, 1], sigma the
duration (s). Start position and velocity fix c[:, 0] = q0 and
c[:, 1] = qd0 * sigma; the planner chooses c[:, 2:] (9 numbers for 3 joints).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DEGREE = 4


def power_basis(s: np.ndarray, derivative: int = 0) -> np.ndarray:
    """Rows d^k/ds^k [1, s, s^2, s^3, s^4] at normalized times s (n,) -> (n, 5)."""
    s = np.atleast_1d(np.asarray(s, dtype=float))
    basis = np.zeros((len(s), DEGREE + 1))
    for p in range(derivative, DEGREE + 1):
        factor = np.prod(np.arange(p - derivative + 1, p + 1)) if derivative else 1.0
        basis[:, p] = factor * s ** (p - derivative)
    return basis


@dataclass(frozen=True)
class QuarticTrajectory:
    """One planned segment: coefficients (dof, 5), column p multiplies s**p."""

    t_begin: float  # s
    duration: float  # sigma, s
    coefficients: np.ndarray

    @classmethod
    def from_free(cls, t_begin: float, duration: float, q0, qd0, free: np.ndarray):
        """Segment from its start state and the free coefficients (dof, 3) of s^2..s^4."""
        fixed = np.stack([np.asarray(q0, float), np.asarray(qd0, float) * duration], axis=1)
        return cls(t_begin, duration, np.hstack([fixed, np.asarray(free, float)]))

    @property
    def t_end(self) -> float:
        return self.t_begin + self.duration

    def normalized(self, t: np.ndarray) -> np.ndarray:
        """Normalized time s of absolute times t (s), eq. (12)."""
        return (np.asarray(t, dtype=float) - self.t_begin) / self.duration

    def state(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q (rad), qd (rad/s), qdd (rad/s^2), each (n, dof), at absolute times t (s)."""
        s = self.normalized(np.atleast_1d(t))
        c = self.coefficients.T
        return (
            power_basis(s) @ c,
            power_basis(s, 1) @ c / self.duration,
            power_basis(s, 2) @ c / self.duration**2,
        )

    def turning_points(self) -> np.ndarray:
        """Normalized times (dof, 3) in (0, 1) where each joint's velocity vanishes;
        unused entries are NaN."""
        out = np.full((len(self.coefficients), DEGREE - 1), np.nan)
        for j, c in enumerate(self.coefficients):
            roots = np.polynomial.Polynomial(c).deriv().roots()
            real = roots[np.abs(roots.imag) < 1e-9].real
            real = np.sort(real[(real > 1e-6) & (real < 1 - 1e-6)])
            out[j, : len(real)] = real
        return out

    def restrict(self, t_begin: float, duration: float) -> QuarticTrajectory:
        """The same motion re-expressed on [t_begin, t_begin + duration] (exact: a
        quartic in s is a quartic in any affinely shifted normalized time)."""
        inner = np.polynomial.Polynomial([(t_begin - self.t_begin) / self.duration,
                                          duration / self.duration])
        rows = [np.polynomial.Polynomial(c)(inner).coef for c in self.coefficients]
        coefficients = np.zeros_like(self.coefficients)
        for i, row in enumerate(rows):
            coefficients[i, : len(row)] = row[: DEGREE + 1]
        return QuarticTrajectory(t_begin, duration, coefficients)
