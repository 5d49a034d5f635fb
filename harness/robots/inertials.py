"""A MuJoCo model with other inertial parameters: the dynamics an identified model believes.

The standard parameters are identification.library.kinematic.atom_names' (what a physically
consistent fit identifies and PinocchioModel.atom_parameters gives of a URDF): per body, in
its joint's frame, m, m c (kg m) and the rotational inertia about the frame's origin
(kg m^2: Ixx, Ixy, Iyy, Ixz, Iyz, Izz, Pinocchio's toDynamicParameters order); then per
joint armature (kg m^2), viscous damping (N m s/rad) and Coulomb friction (N m). A MuJoCo
body of a URDF arm has its joint's frame (the URDF link frame), so they map one to one; the
bodies welded to it (a hand, held fingers) are in its parameters and left massless.
"""

from __future__ import annotations

import mujoco
import numpy as np

from harness.errors import UserError

# a MODEL.json's own standard parameters, 13 per joint, when it carries them at top level
PARAMETERS_KEY = "body_parameters"
JOINT_PARAMETERS = ("armature", "viscous", "coulomb")  # metrics.physical.joint_parameters, in order
MIN_MASS = 1e-9  # kg: MuJoCo needs a positive mass on a moving body


def centroidal_inertia(parameters: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass (kg), centre of mass (3,) m and the (3, 3) rotational inertia about it (kg m^2)
    of one body's 10 standard parameters."""
    m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = (float(v) for v in parameters)
    mass = max(m, MIN_MASS)
    c = np.array([hx, hy, hz]) / mass
    origin = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    return mass, c, origin - mass * (c @ c * np.eye(3) - np.outer(c, c))  # parallel axis


def body_inertials(parameters: np.ndarray) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """Mass (kg), centre of mass (3,) m, principal moments (3,) kg m^2 and the quaternion
    (w, x, y, z) of the principal axes, of one body's 10 standard parameters."""
    mass, c, centre = centroidal_inertia(parameters)
    moments, axes = np.linalg.eigh(centre)
    if np.linalg.det(axes) < 0:
        axes[:, 0] = -axes[:, 0]  # a rotation, not a reflection
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, axes.ravel())
    return mass, c, np.maximum(moments, 0.0), quat


def model_standard_parameters(payload: dict) -> np.ndarray | None:
    """The 13 dof standard parameters (module docstring) of a MODEL.json's payload: its
    'body_parameters', else a consistent fit's metrics.physical; None for a model without
    bodies (a fit in the robot's base atoms, a feature model)."""
    if payload.get(PARAMETERS_KEY) is not None:
        return np.asarray(payload[PARAMETERS_KEY], float)
    physical = (payload.get("metrics") or {}).get("physical") or {}
    if "standard_parameters" not in physical or "joint_parameters" not in physical:
        return None
    joints = physical["joint_parameters"]
    try:
        return np.array([*physical["standard_parameters"],
                         *(v for k in JOINT_PARAMETERS for v in joints[k])], float)
    except (KeyError, TypeError, ValueError) as exc:
        raise UserError(f"the model's metrics.physical parameters are malformed: {exc}") from None


def set_standard_parameters(model: mujoco.MjModel, parameters) -> mujoco.MjModel:
    """model (changed in place, and returned) with the bodies of its dof hinge joints, in
    joint order, given these 13 dof standard parameters (module docstring)."""
    dof = model.njnt
    parameters = np.asarray(parameters, float)
    if parameters.shape != (13 * dof,) or not np.all(np.isfinite(parameters)):
        raise UserError(f"the plant needs {13 * dof} finite standard parameters (13 per joint), "
                        f"got {parameters.size}")
    for j in range(dof):
        body = model.jnt_bodyid[j]
        mass, c, moments, quat = body_inertials(parameters[10 * j:10 * j + 10])
        model.body_mass[body], model.body_ipos[body] = mass, c
        model.body_inertia[body], model.body_iquat[body] = moments, quat
        for child in fixed_children(model, body):  # their inertia is in the joint's body
            model.body_mass[child], model.body_inertia[child] = MIN_MASS, MIN_MASS
        dof_address = model.jnt_dofadr[j]
        armature, viscous, coulomb = parameters[10 * dof + j::dof][:3]
        model.dof_armature[dof_address] = armature
        model.dof_damping[dof_address] = viscous
        model.dof_frictionloss[dof_address] = coulomb
    mujoco.mj_setConst(model, mujoco.MjData(model))
    return model


def fixed_children(model: mujoco.MjModel, body: int) -> list[int]:
    """The bodies welded to body (no joint between them: a URDF's fixed links)."""
    out = []
    for child in range(model.nbody):
        if model.body_parentid[child] == body and child != body and model.body_jntnum[child] == 0:
            out += [child, *fixed_children(model, child)]
    return out
