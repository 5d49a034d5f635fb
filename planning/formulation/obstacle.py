"""A moving spherical obstacle, sampled K times over the motion (paper III.G)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LinearObstacle:
    """Centre moving at constant velocity from `start` (t = 0) to `end` (t = duration); m, s."""

    start: tuple[float, float, float]
    end: tuple[float, float, float]
    duration: float
    samples: int = 200

    def position(self, t) -> np.ndarray:
        """Centre (n, 3) in metres at times t (s), held at the end points outside [0, T]."""
        frac = np.clip(np.atleast_1d(np.asarray(t, float)) / self.duration, 0.0, 1.0)
        start, end = np.asarray(self.start), np.asarray(self.end)
        return start + frac[:, None] * (end - start)

    @property
    def sample_times(self) -> np.ndarray:
        """Times t_k = k T / K, k = 1..K (s), at which the obstacle is observed."""
        return self.duration * np.arange(1, self.samples + 1) / self.samples


@dataclass(frozen=True)
class SwayingObstacle(LinearObstacle):
    """The linear path plus a sinusoidal sway: centre(t) = linear(t) + sway sin(2 pi periods
    t / duration); m, s. Constant-velocity prediction is never exact for it, so the arm
    re-plans at every sample where the prediction threatens (Algorithm 2 exercised)."""

    sway: tuple[float, float, float] = (0.0, 0.0, 0.0)  # amplitude vector, m
    periods: float = 1.0  # sway periods over the motion

    def position(self, t) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, float))
        phase = 2 * np.pi * self.periods * np.clip(t, 0.0, self.duration) / self.duration
        return super().position(t) + np.sin(phase)[:, None] * np.asarray(self.sway)


def predict_linear(times: np.ndarray, observed: np.ndarray, future: np.ndarray) -> np.ndarray:
    """Constant-velocity prediction (n, 3) at `future` times from the last two observations.

    With a single observation the obstacle is predicted to stand still.
    """
    observed = np.atleast_2d(observed)
    if len(observed) < 2:
        return np.broadcast_to(observed[-1], (len(future), 3)).copy()
    velocity = (observed[-1] - observed[-2]) / (times[-1] - times[-2])
    return observed[-1] + (np.asarray(future) - times[-1])[:, None] * velocity
