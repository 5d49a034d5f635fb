"""Excitation trajectories for identification: finite Fourier series in the joint limits.

q_i(t) = c_i + sum_l  a_il sin(l w t) + b_il cos(l w t),  w = 2 pi f0.

Random coefficients with a 1/l spectrum are scaled so every joint sweeps a wide
band of its range (wide amplitude is what makes the libraries full rank; small
amplitude left the paper's library at rank 58/75 while scoping). Among several
seeded candidates the one with the best-conditioned column-normalized
regressor is kept.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FourierExcitation:
    """A multi-sine joint trajectory; angles in rad, time in s, f0 in Hz."""

    centre: np.ndarray  # (dof,)
    sin_coef: np.ndarray  # (dof, L)
    cos_coef: np.ndarray  # (dof, L)
    f0: float

    @property
    def period(self) -> float:
        return 1.0 / self.f0

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q, qd, qdd of shape (len(t), dof) at times t."""
        t = np.asarray(t, dtype=float)[:, None]
        harmonics = np.arange(1, self.sin_coef.shape[1] + 1)
        w = 2 * np.pi * self.f0 * harmonics  # (L,)
        s, c = np.sin(t * w), np.cos(t * w)  # (n, L)
        q = self.centre + s @ self.sin_coef.T + c @ self.cos_coef.T
        qd = (c * w) @ self.sin_coef.T - (s * w) @ self.cos_coef.T
        qdd = -(s * w**2) @ self.sin_coef.T - (c * w**2) @ self.cos_coef.T
        return q, qd, qdd


def random_excitation(
    lower: np.ndarray,
    upper: np.ndarray,
    rng: np.random.Generator,
    harmonics: int = 20,
    f0: float = 0.05,
    fill: float = 0.9,
) -> FourierExcitation:
    """One random excitation that sweeps `fill` of each joint's range over a period."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    dof = len(lower)
    decay = 1.0 / np.arange(1, harmonics + 1)
    sin_coef = rng.normal(size=(dof, harmonics)) * decay
    cos_coef = rng.normal(size=(dof, harmonics)) * decay
    shape = FourierExcitation(np.zeros(dof), sin_coef, cos_coef, f0)
    q, _, _ = shape.evaluate(np.linspace(0.0, shape.period, 4001))
    lo, hi = q.min(axis=0), q.max(axis=0)
    scale = fill * (upper - lower) / (hi - lo)
    centre = 0.5 * (lower + upper) - scale * 0.5 * (lo + hi)
    return FourierExcitation(centre, sin_coef * scale[:, None], cos_coef * scale[:, None], f0)


def within_velocity(exc: FourierExcitation, velocity: np.ndarray | None,
                    grid: int = 4001) -> FourierExcitation:
    """exc with the swing of every joint whose speed exceeds velocity (rad/s, inf: none)
    shrunk about the middle of its sweep until it does not; exc itself if none exceeds."""
    if velocity is None:
        return exc
    q, qd, _ = exc.evaluate(np.linspace(0.0, exc.period, grid))
    # 0.1 % under the limit: the grid may miss the true peak between its points
    factor = np.minimum(1.0, 0.999 * np.asarray(velocity, float) / np.abs(qd).max(axis=0))
    if np.all(factor >= 1.0):
        return exc
    middle = 0.5 * (q.min(axis=0) + q.max(axis=0))
    return FourierExcitation(middle + factor * (exc.centre - middle), exc.sin_coef * factor[:, None],
                             exc.cos_coef * factor[:, None], exc.f0)


def normalized_condition(features: np.ndarray) -> float:
    """Condition number of a feature matrix with columns scaled to unit norm."""
    norms = np.linalg.norm(features, axis=0)
    if np.any(norms == 0):
        return float("inf")
    s = np.linalg.svd(features / norms, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


def design_excitation(
    lower: np.ndarray,
    upper: np.ndarray,
    seed: int,
    condition: Callable[[FourierExcitation], float],
    candidates: int = 16,
    velocity: np.ndarray | None = None,
    **kwargs,
) -> tuple[FourierExcitation, float]:
    """The best-conditioned of `candidates` seeded random excitations, with its condition;
    each held within the joint speeds `velocity` (rad/s) when given (within_velocity)."""
    rng = np.random.default_rng(seed)
    best, best_cond = None, np.inf
    for _ in range(candidates):
        exc = within_velocity(random_excitation(lower, upper, rng, **kwargs), velocity)
        cond = condition(exc)
        if best is None or cond < best_cond:
            best, best_cond = exc, cond
    return best, best_cond
