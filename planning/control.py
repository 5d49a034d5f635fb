"""The executed trajectory at a controller's rate: what a robot is sent (`plan --trajectory`).

One row every 1/rate s from t = 0 to the end of the motion (the last row at the duration,
where the motion is at rest at the goal when the plan arrives at rest): time (s), joint
positions (rad), velocities (rad/s), accelerations (rad/s^2) and the planning model's
torque at that state (N m), the feed-forward a torque-controlled arm adds to its feedback.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.torque_model import TorqueModel
from planning.replanning import Execution
from planning.result import sample_execution


@dataclass(frozen=True)
class ControlTrajectory:
    """Samples (n,) s and (n, dof) of the executed motion and its feed-forward torque."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray

    def header(self) -> list[str]:
        """Column names: t, q1..qn, qd1..qdn, qdd1..qddn, tau1..taun."""
        dof = self.q.shape[1]
        return ["t"] + [f"{name}{j + 1}" for name in ("q", "qd", "qdd", "tau")
                        for j in range(dof)]

    def table(self) -> np.ndarray:
        """The rows (n, 1 + 4 dof), in header's order."""
        return np.column_stack([self.t, self.q, self.qd, self.qdd, self.tau])


def control_trajectory(execution: Execution, model: TorqueModel, duration: float,
                       rate: float) -> ControlTrajectory:
    """The execution sampled every 1/rate s (Hz) on [0, duration] (s), the last sample at the
    duration, with the planning model's torque."""
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"rate must be a finite number > 0 Hz, got {rate}")
    steps = int(np.ceil(duration * rate - 1e-9))
    t = np.minimum(np.arange(steps + 1) / rate, duration)
    q, qd, qdd = sample_execution(execution, t)
    return ControlTrajectory(t, q, qd, qdd, np.asarray(model.torque(q, qd, qdd), float))
