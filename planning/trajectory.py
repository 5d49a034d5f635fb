"""Quartic joint polynomials in normalized time (paper eqs. 11, 12).

q_i(s) = sum_p c[i, p] s**p, s = (t - t_begin) / sigma in [0, 1], sigma the
duration (s). Start position and velocity fix c[:, 0] = q0 and
c[:, 1] = qd0 * sigma; the planner chooses c[:, 2:] (9 numbers for 3 joints).
"""

from __future__ import annotations

from dataclasses import dataclass
from math import comb

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

    def position(self, t) -> np.ndarray:
        """q (n, dof) in rad at absolute times t (s); cheaper than `state`."""
        return power_basis(self.normalized(np.atleast_1d(t))) @ self.coefficients.T

    def turning_points(self) -> np.ndarray:
        """Normalized times (dof, 3) in (0, 1) where each joint's velocity vanishes;
        unused entries are NaN."""
        return stationary_points_rows(self.coefficients)

    def restrict(self, t_begin: float, duration: float) -> QuarticTrajectory:
        """The same motion re-expressed on [t_begin, t_begin + duration] (exact: a
        quartic in s is a quartic in any affinely shifted normalized time)."""
        shift, scale = (t_begin - self.t_begin) / self.duration, duration / self.duration
        p, k = np.meshgrid(np.arange(DEGREE + 1), np.arange(DEGREE + 1), indexing="ij")
        # s = shift + scale u:  s^p = sum_k C(p, k) shift^(p-k) scale^k u^k
        change = np.where(k <= p, _BINOMIAL * shift ** np.maximum(p - k, 0) * scale**k, 0.0)
        return QuarticTrajectory(t_begin, duration, self.coefficients @ change)


_BINOMIAL = np.array([[comb(p, k) for k in range(DEGREE + 1)] for p in range(DEGREE + 1)],
                     dtype=float)


def stationary_points_rows(coefficients: np.ndarray) -> np.ndarray:
    """stationary_points of each row of quartic coefficients (n, 5) -> (n, 3), NaN-padded;
    one batched eigenvalue call for the companion matrices of the cubic derivatives."""
    c = np.asarray(coefficients, dtype=float)
    slope = c[:, 1:] * np.arange(1, DEGREE + 1)  # ascending cubic coefficients
    lead = slope[:, -1]
    out = np.full((len(c), DEGREE - 1), np.nan)
    regular = np.abs(lead) > 1e-12 * (np.abs(slope).max(axis=1) + 1e-300)
    if regular.any():
        monic = slope[regular, :-1] / lead[regular, None]
        companion = np.zeros((int(regular.sum()), 3, 3))
        companion[:, 0, :] = -monic[:, ::-1]
        companion[:, 1, 0] = companion[:, 2, 1] = 1.0
        roots = np.linalg.eigvals(companion)
        ok = (np.abs(roots.imag) < 1e-9) & (roots.real > 1e-6) & (roots.real < 1 - 1e-6)
        values = np.sort(np.where(ok, roots.real, np.nan), axis=1)
        out[regular] = values
    for j in np.flatnonzero(~regular):
        roots = stationary_points(c[j])
        out[j, : len(roots)] = roots
    return out


def stationary_points(coefficients) -> np.ndarray:
    """Sorted real roots in (0, 1) of the derivative of ascending `coefficients`."""
    slope = np.arange(1, len(coefficients)) * np.asarray(coefficients[1:], dtype=float)
    slope = np.trim_zeros(slope, "b")
    if len(slope) < 2:
        return np.empty(0)
    roots = np.roots(slope[::-1])
    real = roots[np.abs(roots.imag) < 1e-9].real
    return np.sort(real[(real > 1e-6) & (real < 1 - 1e-6)])
