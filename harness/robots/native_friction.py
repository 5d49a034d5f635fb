"""A model's joint friction and sensor offset in MuJoCo's own terms, for `export --format mjcf`.

MuJoCo's dry friction is a joint's `frictionloss` f: a soft constraint whose force, at the
simulator's states, is f sat((qd + lead qdd) / eps), lead = 1 / b and eps = R f / b set by the
joint's solreffriction/solimpfriction (harness.closeloop.plants.friction_shape, the relation the
project derived and checked against MuJoCo). A model's friction beyond viscous (its Coulomb
atom, qd / sqrt(qd^2 + w^2), and a sigmoid's phi1 [s(phi2 (qd + phi3)) - s(phi2 phi3)]) is
approximated by the nearest f sat(qd / eps) + d qd + k: d added to the joint's damping, eps
set through solimpfriction's dmin, and for each eps of a grid (f >= 0, viscous + d >= 0, k
free) by least squares over joint speeds spread evenly on [-V, V] (V the joint's velocity
limit, else FIT_SPEED). The constant k, which MuJoCo has no joint term for, goes with the
sensor offset into the bias of a motor per joint: its control is the torque the sensor reads,
its force that less the offset and k. MuJoCo's lead (its friction force follows qd + lead qdd)
cannot be zero: the time constant is set to its bound, twice the timestep, so lead = dmax
timestep (0.0019 s at the Panda's 2 ms, against 0.0095 s at the default 0.02 s time constant).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import mujoco
import numpy as np
from scipy.optimize import lsq_linear

from identification.friction import FrictionLaw
from identification.library.kinematic import COULOMB_WIDTH
from identification.model import joint_entries

FIT_SPEED = 2.0  # rad/s, the fit's speed range where the robot states no velocity limit
FIT_POINTS = 4001  # speeds in the fit's range
WIDTHS = np.geomspace(COULOMB_WIDTH, 1.0, 61)  # rad/s, the eps grid the fit chooses among
DMIN_RANGE = (1e-4, 0.9999)  # MuJoCo's bounds on solimp's impedance (mjMINIMP, mjMAXIMP)


@dataclass(frozen=True)
class NativeFriction:
    """One joint's friction as MuJoCo holds it, and what the approximation leaves."""

    frictionloss: float  # N m
    damping: float  # N m s/rad (the model's viscous plus the fit's)
    constant: float  # N m, k: held in the motor's bias
    width: float  # rad/s, eps: MuJoCo's linear zone of the frictionloss
    speed: float  # rad/s, V: the fit's range [-V, V]
    gap: float  # N m, RMS of the model's friction less MuJoCo's over the range
    own: float  # N m, the coefficient of the law's own column (a sigmoid's phi1; 0 without)


def model_friction(qd: np.ndarray, viscous: float, coulomb: float, law: FrictionLaw,
                   phi1: float) -> np.ndarray:
    """The model's joint friction torque at speeds qd (the kinematic library's atoms)."""
    out = viscous * qd + coulomb * qd / np.sqrt(qd**2 + COULOMB_WIDTH**2)
    return out + (phi1 * law.column(qd) if law.has_column else 0.0)


def fit_joint(viscous: float, coulomb: float, law: FrictionLaw, phi1: float, speed: float
              ) -> NativeFriction:
    """The nearest f sat(qd / eps) + (viscous + d) qd + k (module docstring) on [-speed, speed]."""
    qd = np.linspace(-speed, speed, FIT_POINTS)
    target = model_friction(qd, viscous, coulomb, law, phi1)
    best = None
    for eps in WIDTHS:
        design = np.column_stack([np.clip(qd / eps, -1, 1), qd, np.ones_like(qd)])
        fit = lsq_linear(design, target, bounds=([0, 0, -np.inf], [np.inf, np.inf, np.inf]))
        gap = float(np.sqrt(np.mean((design @ fit.x - target) ** 2)))
        if best is None or gap < best[0]:
            best = (gap, eps, fit.x)
    gap, eps, (f, d, k) = best
    return NativeFriction(float(f), float(d), float(k), float(eps), speed, gap, phi1)


def own_coefficients(payload: dict, dof: int) -> tuple[list[FrictionLaw], np.ndarray]:
    """Each joint's friction law and its own column's coefficient (a sigmoid's phi1, a
    Stribeck's F_s; 0 for a law without a column, and for a payload of bodies alone)."""
    phi1 = np.zeros(dof)
    if payload.get("joints") is None:
        return [FrictionLaw() for _ in range(dof)], phi1
    joints = joint_entries(payload, dof)
    laws = [FrictionLaw.from_dict(x) for x in payload.get("friction") or []] \
        or [FrictionLaw() for _ in joints]
    for j, (joint, law) in enumerate(zip(joints, laws, strict=True)):
        if law.has_column:
            phi1[j] = dict(zip(joint["terms"], joint["coefficients"], strict=True)).get(
                law.term(j + 1), 0.0)
    return laws, phi1


def native_friction(payload: dict, params: np.ndarray, speeds) -> list[NativeFriction]:
    """Each joint's NativeFriction from MODEL.json's payload and its 13 dof standard
    parameters, fitted over [-V, V] with V from speeds (None or non-finite: FIT_SPEED)."""
    dof = params.size // 13
    laws, phi1 = own_coefficients(payload, dof)
    out = []
    for j in range(dof):
        v = FIT_SPEED if speeds is None or not np.isfinite(speeds[j]) else float(speeds[j])
        out.append(fit_joint(params[11 * dof + j], params[12 * dof + j], laws[j], phi1[j], v))
    return out


def set_native_friction(model: mujoco.MjModel, frictions: list[NativeFriction]) -> None:
    """model's hinge dofs (in joint order) given each joint's frictionloss, damping, the
    shortest lead (solreffriction's time constant at MuJoCo's bound, twice the timestep) and,
    by solimpfriction's dmin, its linear zone eps (MuJoCo's relation: friction_shape)."""
    from harness.closeloop.plants import friction_shape

    for j, friction in enumerate(frictions):
        dof = model.jnt_dofadr[j]
        model.dof_frictionloss[dof] = friction.frictionloss
        model.dof_damping[dof] = friction.damping
        if friction.frictionloss <= 0:
            continue
        model.dof_solref[dof, 0] = 2 * model.opt.timestep  # the shortest lead MuJoCo allows
        probe = copy.copy(model)
        probe.dof_solimp[dof, 0] = 0.5  # eps is proportional to (1 - dmin) / dmin
        _, eps = friction_shape(probe, int(dof), friction.frictionloss)
        ratio = friction.width / eps  # the wanted (1 - dmin) / dmin
        model.dof_solimp[dof, 0] = float(np.clip(1 / (1 + ratio), *DMIN_RANGE))


def inverse_torque(model: mujoco.MjModel, bias: np.ndarray, q, qd, qdd) -> np.ndarray:
    """(n, dof) N m: the control model needs to follow (q, qd, qdd): mj_inverse, its friction
    constraints included, less its motors' bias (the torque its sensor would read)."""
    data = mujoco.MjData(model)
    out = np.empty((len(q), model.nv))
    for i in range(len(q)):
        data.qpos[:], data.qvel[:], data.qacc[:] = q[i], qd[i], qdd[i]
        mujoco.mj_inverse(model, data)
        out[i] = data.qfrc_inverse - bias
    return out


def inverse_gap(model: mujoco.MjModel, bias: np.ndarray, q, qd, qdd, sensor: np.ndarray
                ) -> np.ndarray:
    """Per joint RMS (N m) of inverse_torque against the torque the model says the sensor
    reads (sensor, (n, dof))."""
    return np.sqrt(np.mean((inverse_torque(model, bias, q, qd, qdd) - sensor) ** 2, axis=0))
