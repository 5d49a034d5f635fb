"""The one interface where identification, planning and the harness meet.

A torque model maps joint states to joint torques. Identified sparse models,
the Pinocchio closed-form baseline and "declared model + added effects" all
implement it, so the planner and the replay never know which one they hold.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np


@dataclass(frozen=True)
class Motion:
    """Joint trajectory samples, the states a torque model is evaluated on: t (n,) in s;
    q, qd, qdd (n, dof) in rad, rad/s, rad/s^2. Datasets and plans extend it."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray


@runtime_checkable
class TorqueModel(Protocol):
    """Inverse dynamics tau = f(q, qd, qdd) of a dof-joint robot.

    Units: q in rad, qd in rad/s, qdd in rad/s^2, tau in N m.
    """

    dof: int

    def torque(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """Vectorized torques: arrays of shape (n, dof) in, (n, dof) out."""
        ...

    def symbolic_torque(self, q, qd, qdd):
        """The same map on CasADi column vectors (SX or MX, dof x 1) for the planner.

        Returns a CasADi expression of shape (dof, 1) with exact derivatives.
        """
        ...


def as_states(q, qd, qdd, dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validate and broadcast a state triple to float arrays of shape (n, dof)."""
    arrays = [np.atleast_2d(np.asarray(x, dtype=float)) for x in (q, qd, qdd)]
    for name, x in zip(("q", "qd", "qdd"), arrays, strict=True):
        if x.ndim != 2 or x.shape[1] != dof:
            raise ValueError(f"{name} must have shape (n, {dof}), got {x.shape}")
        if not np.all(np.isfinite(x)):
            raise ValueError(f"{name} contains NaN or inf")
    if not arrays[0].shape == arrays[1].shape == arrays[2].shape:
        raise ValueError(
            f"q, qd, qdd shapes differ: {arrays[0].shape}, {arrays[1].shape}, {arrays[2].shape}"
        )
    return arrays[0], arrays[1], arrays[2]
