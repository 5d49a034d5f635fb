"""Joint polynomials in normalized time (paper eqs. 11, 12), quartic by default.

q_i(s) = sum_p c[i, p] s**p, s = (t - t_begin) / sigma in [0, 1], sigma the
duration (s). Start position and velocity fix c[:, 0] = q0 and
c[:, 1] = qd0 * sigma; the planner chooses c[:, 2:] (degree - 1 numbers per
joint: 9 for the paper's three quartics).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from math import comb

import numba
import numpy as np

DEGREE = 4  # the paper's quartic


def power_basis(s: np.ndarray, derivative: int = 0, degree: int = DEGREE) -> np.ndarray:
    """Rows d^k/ds^k [1, s, ..., s^degree] at normalized times s (n,) -> (n, degree + 1)."""
    s = np.atleast_1d(np.asarray(s, dtype=float))
    basis = np.zeros((len(s), degree + 1))
    for p in range(derivative, degree + 1):
        factor = np.prod(np.arange(p - derivative + 1, p + 1)) if derivative else 1.0
        basis[:, p] = factor * s ** (p - derivative)
    return basis


@dataclass(frozen=True)
class PolynomialTrajectory:
    """One planned segment: coefficients (dof, degree + 1), column p multiplies s**p."""

    t_begin: float  # s
    duration: float  # sigma, s
    coefficients: np.ndarray

    @classmethod
    def from_free(cls, t_begin: float, duration: float, q0, qd0, free: np.ndarray):
        """Segment from its start state and the free coefficients (dof, degree - 1) of
        s^2..s^degree."""
        free = np.asarray(free, float)
        coefficients = np.empty((free.shape[0], free.shape[1] + 2))
        coefficients[:, 0], coefficients[:, 1], coefficients[:, 2:] = q0, qd0, free
        coefficients[:, 1] *= duration
        return cls(t_begin, duration, coefficients)

    @property
    def degree(self) -> int:
        return self.coefficients.shape[1] - 1

    @property
    def t_end(self) -> float:
        return self.t_begin + self.duration

    def normalized(self, t: np.ndarray) -> np.ndarray:
        """Normalized time s of absolute times t (s), eq. (12)."""
        return (np.asarray(t, dtype=float) - self.t_begin) / self.duration

    def state(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q (rad), qd (rad/s), qdd (rad/s^2), each (n, dof), at absolute times t (s)."""
        s, c, d = self.normalized(np.atleast_1d(t)), self.coefficients.T, self.degree
        return (
            power_basis(s, 0, d) @ c,
            power_basis(s, 1, d) @ c / self.duration,
            power_basis(s, 2, d) @ c / self.duration**2,
        )

    def position(self, t) -> np.ndarray:
        """q (n, dof) in rad at absolute times t (s); cheaper than `state`."""
        return power_basis(self.normalized(np.atleast_1d(t)), 0, self.degree) @ self.coefficients.T

    def turning_points(self) -> np.ndarray:
        """Normalized times (dof, degree - 1) in (0, 1) where each joint's velocity vanishes;
        unused entries are NaN."""
        return stationary_points_rows(self.coefficients)

    def restrict(self, t_begin: float, duration: float) -> PolynomialTrajectory:
        """The same motion re-expressed on [t_begin, t_begin + duration] (exact: a
        polynomial in s is one of the same degree in any affinely shifted normalized time)."""
        shift, scale = (t_begin - self.t_begin) / self.duration, duration / self.duration
        binomial, lower, power, k = _binomial(self.degree + 1)
        # s = shift + scale u:  s^p = sum_k C(p, k) shift^(p-k) scale^k u^k
        change = np.where(lower, binomial * shift**power * scale**k, 0.0)
        return PolynomialTrajectory(t_begin, duration, self.coefficients @ change)


QuarticTrajectory = PolynomialTrajectory  # the paper's degree; the name older code uses


@cache
def _binomial(n: int) -> tuple[np.ndarray, ...]:
    """C(p, k) (n, n), where k <= p, max(p - k, 0) and k, for p, k < n (computed once)."""
    p, k = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    binomial = np.array([[comb(i, j) for j in range(n)] for i in range(n)], dtype=float)
    return binomial, k <= p, np.maximum(p - k, 0), k


def stationary_points_rows(coefficients: np.ndarray) -> np.ndarray:
    """stationary_points of each row of coefficients (n, degree + 1) -> (n, degree - 1),
    NaN-padded (compiled: the eigenvalues of each derivative's companion matrix)."""
    return _stationary_points_rows(np.asarray(coefficients, dtype=float))


@numba.njit("(f8[:, :],)", cache=True, nogil=True)
def _stationary_points_rows(c):
    """A row's derivative keeps its full degree unless its leading coefficient is below 1e-12
    of its largest (then exact zeros are trimmed, as stationary_points does); its real roots
    in (0, 1), sorted. Measured: as numpy (a batched eigvals) ~0.12 ms of a 2.2 ms re-plan."""
    m = c.shape[1] - 2  # degree of the derivative
    out = np.full((c.shape[0], max(m, 0)), np.nan)
    for j in range(c.shape[0]):
        slope = np.empty(m + 1)
        for p in range(m + 1):
            slope[p] = c[j, p + 1] * (p + 1)  # ascending coefficients of dq/ds
        top = m
        if abs(slope[m]) <= 1e-12 * (np.max(np.abs(slope)) + 1e-300):
            while top >= 0 and slope[top] == 0.0:
                top -= 1
        if top < 1:
            continue
        companion = np.zeros((top, top), np.complex128)
        for i in range(top):
            companion[0, i] = -slope[top - 1 - i] / slope[top]
        for i in range(1, top):
            companion[i, i - 1] = 1.0
        roots = np.linalg.eigvals(companion)
        inside = np.empty(top)
        count = 0
        for root in roots:
            if abs(root.imag) < 1e-9 and 1e-6 < root.real < 1 - 1e-6:
                inside[count] = root.real
                count += 1
        out[j, :count] = np.sort(inside[:count])
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


def hermite(start: np.ndarray, end: np.ndarray, degree: int) -> np.ndarray:
    """Coefficients (dof, degree + 1) of the polynomial in s in [0, 1] with the given
    derivatives d^k q/ds^k at s = 0 (start, (dof, a)) and s = 1 (end, (dof, b)),
    a + b = degree + 1 (e.g. the rest-to-rest quintic: a = b = 3, the minimum-jerk motion)."""
    start, end = np.atleast_2d(start), np.atleast_2d(end)
    rows = [power_basis([0.0], k, degree)[0] for k in range(start.shape[1])]
    rows += [power_basis([1.0], k, degree)[0] for k in range(end.shape[1])]
    return np.linalg.solve(np.array(rows), np.hstack([start, end]).T).T
