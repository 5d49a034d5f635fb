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


@numba.njit(cache=True, nogil=True)
def _horner(c, degree, s):
    """The polynomial of ascending coefficients c[: degree + 1] at s."""
    value = c[degree]
    for p in range(degree - 1, -1, -1):
        value = value * s + c[p]
    return value


@numba.njit(cache=True, nogil=True)
def _bisect(c, degree, a, b, fa):
    """The root in (a, b) of a polynomial with a sign change on it, to the last bit."""
    while True:
        middle = 0.5 * (a + b)
        if middle <= a or middle >= b:
            return middle
        value = _horner(c, degree, middle)
        if value == 0.0:
            return middle
        if (value < 0.0) == (fa < 0.0):
            a, fa = middle, value
        else:
            b = middle


@numba.njit("(f8[:, :],)", cache=True, nogil=True)
def _stationary_points_rows(c):
    """A row's derivative keeps its full degree unless its leading coefficient is below 1e-12
    of its largest (then exact zeros are trimmed, as stationary_points does); its real roots
    in (0, 1), sorted. Each derivative of the derivative, from the linear one up, is
    monotone between the roots of the next one: its roots are the sign changes there, each
    bisected to the last bit (an exact zero at a root of the next one, a multiple root,
    counts once); faster than companion-matrix eigenvalues
    (docs/realtime.md, 'planning.formulation.trajectory')."""
    m = c.shape[1] - 2  # degree of the derivative
    out = np.full((c.shape[0], max(m, 0)), np.nan)
    chain = np.zeros((max(m, 0) + 1, max(m, 0) + 1))
    roots, found = np.empty(max(m, 0) + 2), np.empty(max(m, 0) + 2)
    for j in range(c.shape[0]):
        for p in range(m + 1):
            chain[0, p] = c[j, p + 1] * (p + 1)  # ascending coefficients of dq/ds
        top = m
        if abs(chain[0, m]) <= 1e-12 * (np.max(np.abs(chain[0, :m + 1])) + 1e-300):
            while top >= 0 and chain[0, top] == 0.0:
                top -= 1
        if top < 1:
            continue
        for d in range(1, top):  # chain[d]: the d-th derivative of dq/ds, degree top - d
            for p in range(top - d + 1):
                chain[d, p] = chain[d - 1, p + 1] * (p + 1)
        count = 0  # roots in (0, 1) of the level below, sorted
        for d in range(top - 1, -1, -1):
            new, a, fa = 0, 0.0, _horner(chain[d], top - d, 0.0)
            for i in range(count + 1):
                b = roots[i] if i < count else 1.0
                fb = _horner(chain[d], top - d, b)
                if fa * fb < 0.0:
                    found[new] = _bisect(chain[d], top - d, a, b, fa)
                    new += 1
                elif fb == 0.0 and i < count:
                    found[new] = b
                    new += 1
                a, fa = b, fb
            roots[:new] = found[:new]
            count = new
        k = 0
        for i in range(count):
            if 1e-6 < roots[i] < 1 - 1e-6:
                out[j, k] = roots[i]
                k += 1
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
