"""The figures the study puts side by side for each model, on the log's held-out part: the
torque error per joint (relative RMS against the logged torque, as `predict` scores a measured
log: the model's torque plus the sensor offset it holds), rollout fidelity per window length
(harness.replay.rollout, as `predict --rollout --rollout-holdout` measures it), each body's
smallest pseudo-inertia eigenvalue (>= 0: physically consistent) and mass, and the fit's time.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from harness.replay.rollout import (
    WindowFidelity,
    log_step,
    roll_out,
    window_rms,
    window_samples,
)
from harness.robots.native_friction import inverse_torque
from identification.metrics import rel_error
from identification.physical import min_pseudo_eigenvalues

WINDOWS = (0.1, 0.5)  # s, the rollout windows judged (the bench's real-data section's)


@dataclass(frozen=True)
class Scored:
    """One model's figures on the held-out part."""

    name: str
    torque_error: np.ndarray  # per joint, relative
    rollout: list[dict]  # per window length, WindowFidelity.to_json's
    min_eigenvalues: np.ndarray | None  # per body, kg m^2 (None: no bodies to judge)
    masses: np.ndarray | None  # per joint's body, kg
    seconds: float | None  # the fit's wall time (None: nothing fitted)
    command: str = ""

    def to_json(self) -> dict:
        def listed(x):
            return None if x is None else np.asarray(x).tolist()
        return {"name": self.name, "torque_error": listed(self.torque_error),
                "rollout": self.rollout,
                "min_pseudo_eigenvalues": listed(self.min_eigenvalues),
                "masses": listed(self.masses), "command": self.command,
                "timing": {"fit_seconds": self.seconds}}


def held_slice(n: int, holdout: float) -> slice:
    """The last holdout fraction of n samples (identify --holdout's split)."""
    return slice(int(round(n * (1 - holdout))), None)


def score_mujoco(name: str, model: mujoco.MjModel, bias: np.ndarray, arrays: dict,
                 holdout: float, parameters: np.ndarray | None, seconds: float | None,
                 command: str = "") -> Scored:
    """A MuJoCo model whose motors' bias holds the sensor offset (the control is the torque the
    sensor reads, the joint's force that + bias): its torque is mj_inverse less the bias, its
    rollouts driven by the logged torque + bias; parameters (13 dof standard) judge its
    bodies."""
    held = held_slice(len(arrays["q"]), holdout)
    torque = inverse_torque(model, bias, arrays["q"][held], arrays["qd"][held],
                            arrays["qdd"][held])
    done = roll_out(model, arrays["t"], arrays["q"], arrays["qd"], arrays["tau"] + bias,
                    WINDOWS, holdout)
    return Scored(name, rel_error(torque, arrays["tau"][held]),
                  [f.to_json() for f in done.figures],
                  *_bodies(parameters, model.njnt), seconds, command)


def constant_velocity(arrays: dict, holdout: float) -> list[dict]:
    """No model: each window of the held-out part (harness.replay.rollout's windows) continued
    from its first sample at that sample's velocity, q0 + qd0 t; its q and qd RMS per joint
    (WindowFidelity.to_json's), per window length in WINDOWS. What a rollout has to beat to
    predict anything of the torque."""
    start = held_slice(len(arrays["q"]), holdout).start
    t, q, qd = np.ravel(arrays["t"])[start:], arrays["q"][start:], arrays["qd"][start:]
    step, out = log_step(t), []
    for seconds in WINDOWS:
        samples = window_samples(seconds, step, len(q))
        count = (len(q) - 1) // samples
        q_err, qd_err = [], []
        for k in range(count):
            w = slice(k * samples, (k + 1) * samples + 1)
            q_err.append(q[w][0] + np.outer(t[w][1:] - t[w][0], qd[w][0]) - q[w][1:])
            qd_err.append(qd[w][0] - qd[w][1:])
        out.append(WindowFidelity(float(seconds), samples, count, 0, window_rms(q_err),
                                  window_rms(qd_err)).to_json())
    return out


def _bodies(parameters, dof: int) -> tuple:
    if parameters is None:
        return None, None
    inertial = np.asarray(parameters[:10 * dof])
    return min_pseudo_eigenvalues(inertial), inertial[::10]


def window(s: Scored, seconds: float) -> dict:
    return next(w for w in s.rollout if abs(w["seconds"] - seconds) < 1e-9)


def joints_worse(ours: Scored, peer: Scored, seconds: float) -> int:
    """Joints where ours rolls out worse than the peer over windows of seconds (every joint
    when either has no window that did not diverge)."""
    q_ours, q_peer = window(ours, seconds)["q_rms"], window(peer, seconds)["q_rms"]
    if q_ours is None or q_peer is None:
        return len(ours.torque_error)
    return int(np.sum(np.asarray(q_ours) > np.asarray(q_peer)))
