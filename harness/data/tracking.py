"""Forward simulation of a plant tracking an excitation, seen through its sensors.

Controller: computed-torque feedforward from the plant's inverse dynamics at
the reference plus PD on the tracking error shaped by the current mass matrix,
M(q) (w^2 e + 2 zeta w e_dot), evaluated every physics step. Scaling by M keeps
the explicit PD stable where the arm's smallest effective inertia is tiny.
Only the sensor readings (encoder angles, actuator torques) leave this module
as the user's data; the simulator's own states are returned separately as truth.
"""

from __future__ import annotations

import copy
from dataclasses import replace

import mujoco
import numpy as np

from harness.data.pushes import apply_pushes
from harness.data.sensors import SensorConfig, encoder, estimate_derivatives
from harness.errors import UserError
from harness.robots.arm import Arm
from identification.excitation.fourier import FourierExcitation
from identification.metrics import error_measure, rel_error

OMEGA, ZETA = 30.0, 1.0  # rad/s, closed-loop bandwidth and damping of the tracking error


def _sensor_slices(model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray] | None:
    """sensordata indices of jointpos and actuatorfrc sensors, one per dof, if present."""
    pos = [model.sensor_adr[i] for i in range(model.nsensor)
           if model.sensor_type[i] == mujoco.mjtSensor.mjSENS_JOINTPOS]
    frc = [model.sensor_adr[i] for i in range(model.nsensor)
           if model.sensor_type[i] == mujoco.mjtSensor.mjSENS_ACTUATORFRC]
    if len(pos) == model.nv and len(frc) == model.nv:
        return np.array(pos), np.array(frc)
    return None


def _actuation(model: mujoco.MjModel) -> np.ndarray | None:
    """Map from joint torque to ctrl: inverse of the actuator moment (one motor per dof).

    None for a plant without actuators: torques then go in as ideal joint torques
    (qfrc_applied), e.g. robots compiled from a URDF.
    """
    if model.nu == 0:
        return None
    if model.nu != model.nv:
        raise UserError(f"measured mode needs one actuator per joint (nu={model.nu}, nv={model.nv})")
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    moment = np.zeros((model.nu, model.nv))
    mujoco.mju_sparse2dense(moment, data.actuator_moment, data.moment_rownnz,
                            data.moment_rowadr, data.moment_colind)
    return np.linalg.inv(moment.T)


def simulate_measured(arm: Arm, exc: FourierExcitation, t_out: np.ndarray, rate: float,
                      cfg: SensorConfig, rng: np.random.Generator, pushes=()):
    """Simulate arm, sense, estimate; returns q, qd, qdd, tau_clean at t_out (sampled at rate
    Hz), truth, stats. pushes: external forces on its links (harness.data.pushes.Push); their
    joint torque is in truth['tau_external'], and the joint stops' and contacts' (MuJoCo's
    qfrc_constraint: a push can drive a joint onto its stop) in truth['tau_constraint']."""
    model = copy.copy(arm.mujoco)  # its time step is refined below: the arm's is shared
    period = 1.0 / rate
    if abs(period / model.opt.timestep - round(period / model.opt.timestep)) > 1e-9:
        # e.g. MuJoCo's 2 ms default on URDF robots: refine so sensor samples land on the grid
        model.opt.timestep = period / np.ceil(period / model.opt.timestep)
    steps_per = max(1, int(round(1.0 / (cfg.sensing_rate * model.opt.timestep))))
    while round(period / model.opt.timestep) % steps_per:
        steps_per -= 1
    sim_dt = steps_per * model.opt.timestep
    cfg = replace(cfg, sensing_rate=1.0 / sim_dt)
    n_sense = int(round(t_out[-1] * cfg.sensing_rate)) + 1
    t_sense = np.arange(n_sense) * sim_dt
    to_ctrl = _actuation(model)
    sensors = _sensor_slices(model)

    data, ref_data = mujoco.MjData(model), mujoco.MjData(model)
    q_ref, qd_ref, qdd_ref = exc.evaluate(t_sense)
    data.qpos[:], data.qvel[:] = q_ref[0], qd_ref[0]
    q_read, tau_read = np.empty((n_sense, model.nv)), np.empty((n_sense, model.nv))
    q_true, qd_true, qdd_true = (np.empty((n_sense, model.nv)) for _ in range(3))
    external = np.zeros((n_sense, model.nv))
    stops = np.zeros((n_sense, model.nv))  # the joint stops' and contacts' torque (pushed runs)
    for k in range(n_sense):
        ref_data.qpos[:], ref_data.qvel[:], ref_data.qacc[:] = q_ref[k], qd_ref[k], qdd_ref[k]
        mujoco.mj_inverse(model, ref_data)
        mujoco.mj_forward(model, data)
        pd = OMEGA**2 * (q_ref[k] - data.qpos) + 2 * ZETA * OMEGA * (qd_ref[k] - data.qvel)
        tau = ref_data.qfrc_inverse + _mass_matrix(model, data) @ pd
        if to_ctrl is None:
            data.qfrc_applied[:] = tau
        else:
            data.ctrl[:] = to_ctrl @ tau
        mujoco.mj_forward(model, data)  # sensors and qacc at this instant
        if pushes:
            external[k] = apply_pushes(model, data, pushes, t_sense[k])
            mujoco.mj_forward(model, data)
            stops[k] = data.qfrc_constraint
        q_true[k], qd_true[k], qdd_true[k] = data.qpos, data.qvel, data.qacc
        if sensors is not None:
            q_read[k], tau_read[k] = data.sensordata[sensors[0]], data.sensordata[sensors[1]]
        else:
            q_read[k] = data.qpos
            tau_read[k] = data.qfrc_applied if to_ctrl is None else data.qfrc_actuator
        for _ in range(steps_per):
            mujoco.mj_step(model, data)
    if not np.all(np.isfinite(q_true)):
        raise UserError("simulation diverged (non-finite state)")
    q_est, qd_est, qdd_est = estimate_derivatives(encoder(q_read, cfg, rng), cfg)
    idx = np.round(t_out * cfg.sensing_rate).astype(int)
    truth = {"q": q_true[idx], "qd": qd_true[idx], "qdd": qdd_true[idx]}
    if pushes:
        truth["tau_external"] = external[idx]
        truth["tau_constraint"] = stops[idx]
    stats = state_errors(arm, (q_est[idx], qd_est[idx], qdd_est[idx]),
                         (truth["q"], truth["qd"], truth["qdd"]))
    stats["tracking_rms"] = float(np.sqrt(np.mean((q_true - q_ref) ** 2)))
    stats["sensors"] = dict(encoder_bits=cfg.encoder_bits, angle_noise=cfg.angle_noise,
                            sensing_rate=cfg.sensing_rate, window=cfg.window, polyorder=cfg.polyorder)
    return q_est[idx], qd_est[idx], qdd_est[idx], tau_read[idx], truth, stats


def _mass_matrix(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    m = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, m)
    return m


def state_errors(arm: Arm, est: tuple, true: tuple) -> dict:
    """Relative RMS errors of estimated qd, qdd and of the torque they imply."""
    out = {"error_measure": error_measure("states", "all samples"),
           "qd_rel_rmse": rel_error(est[1], true[1]).tolist(),
           "qdd_rel_rmse": rel_error(est[2], true[2]).tolist()}
    baseline = arm.nominal
    out["tau_from_states_rel_rmse"] = rel_error(baseline.torque(*est), baseline.torque(*true)).tolist()
    return out
