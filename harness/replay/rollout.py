"""Rollout fidelity: a model as MuJoCo holds it, started from a log's state at the start of
each window and driven by the log's torque, against the log's joint positions and velocities.

The model is a plain MuJoCo model (the robot's own file, or the MJCF `export --format mjcf`
writes, read back from that file). Its actuators are switched off (mjDSBL_ACTUATION) and the
torque enters as qfrc_applied, so a motor's gear or range does not matter; MuJoCo's own
mj_step integrates, at the model's timestep (refined, as `generate --mode measured` does, when
the log's step is not a whole number of timesteps). Within a log step the torque is linear
between the two samples (a log samples a torque that changed at the controller's rate, not
one held over the step). Windows tile the log without overlap, from its first sample; a window
diverges when a state is non-finite, MuJoCo reports an unstable acceleration (it would reset
the state) or a joint is more than pi from the log. The RMS errors are over every sample of the
windows that did not diverge.
"""

from __future__ import annotations

import copy
import tempfile
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from harness.errors import UserError
from harness.robots.arm import Arm
from harness.robots.export import export_model
from harness.robots.files import plain_mujoco
from harness.robots.inertials import model_standard_parameters

WINDOWS = (0.1, 0.5, 1.0)  # s, the window lengths `predict --rollout` takes by default
DIVERGED = np.pi  # rad from the log: a window this far off is no rollout any more
REGULAR = 1e-3  # relative spread of the log's time steps a rollout accepts


@dataclass(frozen=True)
class WindowFidelity:
    """One window length's figures (errors per joint; None when every window diverged)."""

    seconds: float
    samples: int  # log steps per window
    count: int
    diverged: int
    q_rms: np.ndarray | None  # rad
    qd_rms: np.ndarray | None  # rad/s

    def to_json(self) -> dict:
        return {"seconds": self.seconds, "samples": self.samples, "windows": self.count,
                "diverged": self.diverged, "diverged_fraction": self.diverged / self.count,
                "q_rms": None if self.q_rms is None else self.q_rms.tolist(),
                "qd_rms": None if self.qd_rms is None else self.qd_rms.tolist()}


def held_model(payload: dict | None, arm: Arm, report: list[str] | None = None
               ) -> tuple[mujoco.MjModel, str]:
    """The MuJoCo model a `--model` is as MuJoCo holds it, and its words: 'pinocchio' (payload
    None) the robot's own file; a MODEL.json with bodies the MJCF `export --format mjcf`
    writes, read back by plain MuJoCo (report: what the export approximated, its lines);
    UserError for a model without bodies."""
    if payload is None:
        return arm.mujoco, f"robot {arm.label}'s own model ({arm.entry.mjcf or arm.entry.urdf})"
    if model_standard_parameters(payload) is None:
        raise UserError("a rollout needs a model MuJoCo can hold: this MODEL.json has no bodies "
                        "(a sparse or feature model); identify with --prior nominal|flat, or "
                        "roll out --model pinocchio")
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "model.xml"
        export_model(payload, arm, "mjcf", path, report=report)
        return plain_mujoco(path), "its exported MJCF (export --format mjcf)"


def refined_model(payload: dict | None, model_path: str
                  ) -> tuple[mujoco.MjModel, np.ndarray, str] | None:
    """The refined MJCF a MODEL.json names (`identify --refine rollout`'s record 'refined':
    its path from MODEL.json's folder, else as written), read by plain MuJoCo, its motors'
    bias (N m per joint: the force on the joint is the torque the sensor reads + bias) and its
    words; None when the model names none; UserError when the file is not found."""
    from harness.robots.mjcf_export import motor_bias

    record = (payload or {}).get("refined") or {}
    if "mjcf" not in record:
        return None
    paths = [Path(model_path).parent / record["mjcf_from_model"]] \
        if "mjcf_from_model" in record else []
    path = next((p for p in [*paths, Path(record["mjcf"])] if p.is_file()), None)
    if path is None:
        raise UserError(f"{model_path}: its refined MJCF {record['mjcf']} is not found (identify "
                        "--refine rollout wrote it; keep it beside MODEL.json)")
    model = plain_mujoco(path)
    return model, motor_bias(model), f"its refined MJCF {path} (identify --refine rollout)"


def log_step(t: np.ndarray) -> float:
    """The log's sample step (s); UserError unless evenly sampled within REGULAR."""
    t = np.ravel(t)
    if len(t) < 2:
        raise UserError("a rollout needs a log of at least 2 samples")
    steps = np.diff(t)
    step = float(np.median(steps))
    if step <= 0 or np.max(np.abs(steps - step)) > REGULAR * step:
        raise UserError("a rollout needs evenly sampled time stamps (ingest resamples a log): "
                        f"steps from {steps.min():.4g} to {steps.max():.4g} s")
    return step


def window_samples(seconds: float, step: float, n: int) -> int:
    """Log steps in a window of seconds; UserError when it is not within the log."""
    if not np.isfinite(seconds) or seconds <= 0:
        raise UserError(f"a rollout window must be a positive number of seconds, got {seconds:g}")
    samples = int(round(seconds / step))
    if samples > n - 1:
        raise UserError(f"rollout window {seconds:g} s is longer than the log "
                        f"({(n - 1) * step:.4g} s)")
    if samples < 1:
        raise UserError(f"rollout window {seconds:g} s is shorter than the log's step "
                        f"({step:.4g} s)")
    return samples


def rollout_model(model: mujoco.MjModel, step: float) -> mujoco.MjModel:
    """A copy of model driven by applied joint torques only (actuators off), its timestep a
    whole fraction of the log's step (refined the way generate refines it)."""
    model = copy.copy(model)
    model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_ACTUATION
    ratio = step / model.opt.timestep
    if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
        model.opt.timestep = step / np.ceil(ratio)
    return model


def roll(model: mujoco.MjModel, q0, qd0, tau: np.ndarray, step: float) -> tuple[np.ndarray, ...]:
    """q, qd (len(tau) - 1, nv) at the log's next samples, from q0, qd0 under tau (samples,
    nv) linear between samples; and whether MuJoCo found the acceleration unstable."""
    substeps = int(round(step / model.opt.timestep))
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = q0, qd0
    mujoco.mj_forward(model, data)
    q, qd = np.empty((len(tau) - 1, model.nv)), np.empty((len(tau) - 1, model.nv))
    for i in range(len(tau) - 1):
        for s in range(substeps):
            w = s / substeps
            data.qfrc_applied[:] = (1 - w) * tau[i] + w * tau[i + 1]
            mujoco.mj_step(model, data)
        q[i], qd[i] = data.qpos, data.qvel
    unstable = data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0
    return q, qd, unstable


def fidelity(model: mujoco.MjModel, t, q, qd, tau, seconds: float) -> WindowFidelity:
    """model (rollout_model's) rolled out over windows of seconds tiling the log (module
    docstring), against the log's q and qd."""
    step = log_step(t)
    samples = window_samples(seconds, step, len(q))
    count = (len(q) - 1) // samples
    if model.nv != q.shape[1]:
        raise UserError(f"the model has {model.nv} joints, the log {q.shape[1]}")
    q_err, qd_err, diverged = [], [], 0
    for k in range(count):
        window = slice(k * samples, (k + 1) * samples + 1)
        q_sim, qd_sim, unstable = roll(model, q[window][0], qd[window][0], tau[window], step)
        eq, eqd = q_sim - q[window][1:], qd_sim - qd[window][1:]
        if unstable or not (np.all(np.isfinite(eq)) and np.all(np.isfinite(eqd))) \
                or np.max(np.abs(eq)) > DIVERGED:
            diverged += 1
            continue
        q_err.append(eq)
        qd_err.append(eqd)
    return WindowFidelity(float(seconds), samples, count, diverged, window_rms(q_err),
                          window_rms(qd_err))


def window_rms(errors: list[np.ndarray]) -> np.ndarray | None:
    """Per joint RMS over every sample of the windows, None when there are none."""
    return np.sqrt(np.mean(np.concatenate(errors) ** 2, axis=0)) if errors else None


@dataclass(frozen=True)
class Rollout:
    """A model's figures per window length on a log (from sample `start` on)."""

    log_step: float  # s
    timestep: float  # s, MuJoCo's, as stepped
    start: int
    figures: list[WindowFidelity]


def roll_out(held: mujoco.MjModel, t, q, qd, tau, seconds, holdout: float | None = None
             ) -> Rollout:
    """held (held_model's) rolled out on the log over windows of each of seconds, on the last
    holdout fraction of its samples (the part `identify --holdout` scores; None: all);
    UserError before any rollout for a window the log (or its part) cannot hold."""
    step = log_step(t)
    start = 0 if holdout is None else int(round(len(q) * (1 - holdout)))
    if holdout is not None and not 0 < holdout <= 1:
        raise UserError(f"--rollout-holdout must be in (0, 1], got {holdout:g}")
    part = [np.asarray(x)[start:] for x in (np.ravel(t), q, qd, tau)]
    for s in seconds:
        window_samples(s, step, len(part[0]))
    plant = rollout_model(held, step)
    return Rollout(step, plant.opt.timestep, start, [fidelity(plant, *part, s) for s in seconds])


def table(figures: list[WindowFidelity]) -> str:
    """One short table: per window length, windows, diverged, RMS per joint."""
    def joints(x):
        return "-" if x is None else " ".join(f"{v:.3g}" for v in x)
    lines = ["window  windows  diverged  q RMS per joint (rad) | qd RMS per joint (rad/s)"]
    lines += [f"{f.seconds:<6g}s {f.count:>7d}  {100 * f.diverged / f.count:>6.1f} %  "
              f"{joints(f.q_rms)} | {joints(f.qd_rms)}" for f in figures]
    return "\n".join(lines)
