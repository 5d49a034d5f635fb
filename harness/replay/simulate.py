"""Replay a planned trajectory on a MuJoCo plant and measure what it costs.

The plant is driven only through its actuators by a tracking controller at the
simulation timestep: model feedforward (the closed-form Pinocchio torque at the
reference) plus joint PD with gain matrices scaled by the plant's joint-space inertia
matrix at the reference configuration of each step (gain scheduling), so every mode keeps
the same closed-loop natural frequency along the whole motion. With gains fixed at the
start pose, joint 1's inertia falling 48x when the arm folds (swaying scenario:
0.023 -> 0.0005 kg m^2) pushed the explicit PD past its stability limit at the
0.5 ms step: +-10 N m chatter, 12.9 J instead of 1.18 J. With diagonal gains (each joint
its own inertia) the Panda chattered at its motors' limits (87 N m, 300 J instead of
0.07 J): near q2 = 0 joints 1 and 3 turn about almost the same axis, and the mode q1 - q3
has a tiny inertia that diagonal gains drive far past their frequency. The obstacle moves as
a mocap body along the plan's path. Measured: energy integral |sum tau_i qd_i| dt
from the torques the actuators applied, clearance (centre-to-segment and
surface) and tracking error.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from harness.errors import UserError
from harness.replay.clearance import ClearanceProbe
from harness.replay.friction import PlantFriction
from harness.replay.reference import PlanReference, check_joint_limits
from identification.torque_model import TorqueModel
from planning.formulation.kinematics import ArmGeometry


@dataclass(frozen=True)
class TrackingGains:
    """PD gains as a closed-loop natural frequency (rad/s) and damping ratio."""

    natural_frequency: float = 200.0  # 0.1 rad per 0.5 ms step: stable, stiff to friction
    damping_ratio: float = 1.0


@dataclass(frozen=True)
class ReplayTrace:
    """Time series of one replay, one row per simulation step (timestep dt, s)."""

    t: np.ndarray  # (n,) s
    q: np.ndarray  # (n, dof) rad, measured
    q_ref: np.ndarray  # (n, dof) rad
    tau: np.ndarray  # (n, dof) N m, applied by the actuators
    power: np.ndarray  # (n,) W, sum_i tau_i qd_i
    power_reference: np.ndarray  # (n,) W, feedforward torque times reference velocity
    obstacle: np.ndarray  # (n, 3) m
    end_effector: np.ndarray  # (n, 3) m
    clearance: np.ndarray  # (n, links) m, centre-to-segment per link
    surface: np.ndarray | None  # (n, links) m, mj_geomDistance per link capsule


def plant_joint_map(model: mujoco.MjModel, dof: int) -> tuple[np.ndarray, np.ndarray]:
    """(joint index driven by each actuator, gear) for a plant of dof motor-driven joints."""
    if model.nq != dof or model.nv != dof or model.nu != dof:
        raise UserError(
            f"plant has nq={model.nq}, nv={model.nv}, nu={model.nu}; the plan has {dof} joints"
        )
    if np.any(model.actuator_trntype != mujoco.mjtTrn.mjTRN_JOINT):
        raise UserError("plant actuators must act on joints directly")
    joints = model.actuator_trnid[:, 0].copy()
    if sorted(joints) != list(range(dof)):
        raise UserError("plant needs exactly one actuator per joint")
    return joints, model.actuator_gear[:, 0].copy()


def joint_inertia(model: mujoco.MjModel, q: np.ndarray) -> np.ndarray:
    """Joint-space inertia matrices (n, nv, nv) in kg m^2 (incl. armature) at each row of q."""
    data = mujoco.MjData(model)
    out = np.zeros((len(q), model.nv, model.nv))
    for k, qk in enumerate(q):
        data.qpos[:] = qk
        mujoco.mj_fwdPosition(model, data)
        mujoco.mj_fullM(model, data, out[k])
    return out


def _pd_gains(model: mujoco.MjModel, q: np.ndarray, gains: TrackingGains):
    """(kp, kd), each (n, nv, nv): the inertia matrix at the reference configurations q
    (n, nv) times w^2 and 2 zeta w, so every mode of the arm, coupled joints included,
    closes at the same natural frequency."""
    inertia = joint_inertia(model, q)
    w, z = gains.natural_frequency, gains.damping_ratio
    return inertia * w**2, 2 * z * inertia * w


def simulate(model: mujoco.MjModel, reference: PlanReference, feedforward: TorqueModel,
             gains: TrackingGains = TrackingGains(),
             geometry: ArmGeometry | None = None,
             friction: PlantFriction | None = None) -> ReplayTrace:
    """Track reference on model (the plant), its joints also feeling `friction` (an identified
    model's friction MuJoCo's joints cannot have, harness.replay.friction), and record every
    simulation step; clearance is measured to the links of geometry (default: the
    Lynxmotion's)."""
    joints, gear = plant_joint_map(model, reference.dof)
    if feedforward.dof != reference.dof:
        raise UserError(f"feedforward model has {feedforward.dof} joints, the plan {reference.dof}")
    check_joint_limits(reference, model.jnt_range, model.jnt_limited.astype(bool))
    probe = ClearanceProbe.of(model, geometry)
    dt = model.opt.timestep
    n = int(round(reference.duration / dt))
    t = reference.t[0] + dt * np.arange(n + 1)
    q_ref, qd_ref, qdd_ref = reference.joints_at(t)
    tau_ff = feedforward.torque(q_ref, qd_ref, qdd_ref)
    obstacle = reference.obstacle_at(t)
    kp, kd = _pd_gains(model, q_ref, gains)

    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = q_ref[0], qd_ref[0]
    rows = {k: np.empty((n + 1, reference.dof)) for k in ("q", "qd", "tau")}
    ee, clearance = np.empty((n + 1, 3)), np.empty((n + 1, len(probe.segments)))
    surface = np.empty((n + 1, len(probe.link_geoms))) if probe.has_surface else None
    for k in range(n + 1):
        probe.move_obstacle(data, obstacle[k])
        tau = tau_ff[k] + kp[k] @ (q_ref[k] - data.qpos) + kd[k] @ (qd_ref[k] - data.qvel)
        data.ctrl[:] = tau[joints] / gear
        if friction is not None:
            friction.apply(data)
        rows["q"][k], rows["qd"][k] = data.qpos, data.qvel
        # mj_step evaluates forces and kinematics at the pre-step state, recorded here.
        (mujoco.mj_step if k < n else mujoco.mj_forward)(model, data)
        rows["tau"][k] = data.qfrc_actuator
        ee[k] = data.site_xpos[probe.flange_site]
        clearance[k] = probe.centre_distances(data, obstacle[k])
        if surface is not None:
            surface[k] = probe.surface_distances(model, data)
    return ReplayTrace(
        t=t, q=rows["q"], q_ref=q_ref, tau=rows["tau"],
        power=np.einsum("ij,ij->i", rows["tau"], rows["qd"]),
        power_reference=np.einsum("ij,ij->i", tau_ff, qd_ref),
        obstacle=obstacle, end_effector=ee, clearance=clearance, surface=surface,
    )


@dataclass(frozen=True)
class ReplayResult:
    """What a replay measured (SI units: J, m, rad). Written as REPLAY.json."""

    energy: float  # J, integral |sum tau qd| dt of the applied torques
    energy_planned: float  # J, the plan's own figure (or the reference's when absent)
    energy_reference: float  # J, same integral of feedforward torque along the reference
    min_clearance: float  # m, centre-to-segment, all links
    surface_clearance: float | None  # m, mj_geomDistance, None without an obstacle geom
    planned_min_clearance: float | None  # m, the plan's own figure
    threshold: float  # m, lambda
    tracking_rms: float  # rad, sqrt(mean over time of |q - q_ref|^2)
    tracking_rms_per_joint: tuple[float, ...]  # rad
    max_tracking_error: float  # rad, largest single-joint deviation
    max_torque: tuple[float, ...]  # N m per joint
    duration: float  # s
    timestep: float  # s

    @property
    def energy_error(self) -> float:
        """Relative deviation of replayed from planned energy (NaN if the plan spends none)."""
        if self.energy_planned == 0:
            return float("nan")
        return (self.energy - self.energy_planned) / self.energy_planned


def energy_of(power: np.ndarray, dt: float) -> float:
    """integral |P| dt (J) of a power series (W) sampled every dt (s), last sample excluded."""
    return float(np.sum(np.abs(power[:-1])) * dt)


def summarize(trace: ReplayTrace, reference: PlanReference, dt: float) -> ReplayResult:
    """Reduce a trace to the measured numbers."""
    error = trace.q - trace.q_ref
    energy_reference = energy_of(trace.power_reference, dt)
    return ReplayResult(
        energy=energy_of(trace.power, dt),
        energy_planned=reference.energy if reference.energy is not None else energy_reference,
        energy_reference=energy_reference,
        min_clearance=float(trace.clearance.min()),
        surface_clearance=None if trace.surface is None else float(trace.surface.min()),
        planned_min_clearance=reference.min_clearance,
        threshold=reference.threshold,
        tracking_rms=float(np.sqrt(np.mean(np.sum(error**2, axis=1)))),
        tracking_rms_per_joint=tuple(np.sqrt(np.mean(error**2, axis=0)).tolist()),
        max_tracking_error=float(np.abs(error).max()),
        max_torque=tuple(np.abs(trace.tau).max(axis=0).tolist()),
        duration=reference.duration,
        timestep=dt,
    )


def replay(model: mujoco.MjModel, reference: PlanReference, feedforward: TorqueModel,
           gains: TrackingGains = TrackingGains(),
           geometry: ArmGeometry | None = None,
           friction: PlantFriction | None = None) -> tuple[ReplayResult, ReplayTrace]:
    """Simulate and summarize: the measured result and its time series."""
    trace = simulate(model, reference, feedforward, gains, geometry, friction)
    return summarize(trace, reference, model.opt.timestep), trace
