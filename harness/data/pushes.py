"""The world pushing a simulated plant: external forces on its links at known times.

A push is a force (N, world frame) on a body's centre of mass (MuJoCo `xfrc_applied`) over
[start, start + duration] s, raised and lowered by a half-cosine of RAMP s at each end (a
hand's push builds up over tens of milliseconds). The joint torque it makes, J^T F, is kept
as the data's truth (`tau_external_true`), never shown to the loop.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

RAMP = 0.02  # s, the push's rise and fall


@dataclass(frozen=True)
class Push:
    """A force on one body over an interval: body (a MuJoCo body name), start and duration in
    s, force (3,) N in the world frame."""

    body: str
    start: float
    duration: float
    force: tuple[float, float, float]

    def envelope(self, t: float) -> float:
        """0..1: the push's share at time t."""
        u = t - self.start
        if u <= 0.0 or u >= self.duration:
            return 0.0
        edge = min(u, self.duration - u, RAMP) / RAMP
        return float(0.5 - 0.5 * np.cos(np.pi * edge))

    def to_json(self) -> dict:
        return {"body": self.body, "start": self.start, "duration": self.duration,
                "force": list(self.force)}


def apply_pushes(model: mujoco.MjModel, data: mujoco.MjData, pushes, t: float) -> np.ndarray:
    """Set data.xfrc_applied for the pushes at time t; returns their joint torque (nv,) N m
    (J^T F at the bodies' centres of mass: MuJoCo's mj_applyFT)."""
    data.xfrc_applied[:] = 0.0
    tau = np.zeros(model.nv)
    for push in pushes:
        share = push.envelope(t)
        if share == 0.0:
            continue
        body = model.body(push.body).id
        force = share * np.asarray(push.force, float)
        data.xfrc_applied[body, :3] += force
        mujoco.mj_applyFT(model, data, force, np.zeros(3), data.xipos[body], body, tau)
    return tau
