"""The model mujoco.sysid (MuJoCo's system-identification toolbox, the `sysid` extra) fits,
and its parameters, as the toolbox's own examples set them: every moving body's inertia in the
toolbox's pseudo-inertia (log-Cholesky) parameters with its default bounds, and per joint
armature, damping, frictionloss and a motor's bias (the sensor offset).

The toolbox's pseudo-inertia writer (apply_body_theta_inertia) zeroes the body's diagonal
inertia and sets a NaN `iquat` for the compiler to take `fullinertia`, which MuJoCo 4.0.1
refuses ("mass and inertia of moving bodies must be larger than mjMINVAL"); it also compiles
the spec once per body per evaluation (_infer_inertial). write_pseudo_inertia writes the same
inertia as principal moments and axes (harness.robots.inertials.body_inertials), no compile
(docs/identification.md, "mujoco.sysid as a peer").
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from harness.robots.arm import Arm
from harness.robots.inertials import MIN_MASS, body_inertials, fixed_children

BOUNDS = {"armature": (0.0, 1.0), "damping": (0.0, 10.0), "frictionloss": (0.0, 10.0),
          "bias": (-10.0, 10.0)}  # kg m^2, N m s/rad, N m, N m: wide, as a user starts
OFF_BOUND = 0.01  # a start at a bound moved this fraction of the range in (the toolbox's
# move_off_bounds: armature 0.01 kg m^2, damping and frictionloss 0.1)
JOINT_FIELDS = ("armature", "damping", "frictionloss")  # the standard parameters' joint order


def toolbox():
    """mujoco.sysid; ImportError naming the extra when its dependencies are missing (the
    package then imports empty)."""
    from mujoco import sysid
    if not hasattr(sysid, "optimize"):
        raise ImportError("mujoco.sysid needs the sysid extra: pip install 'torquebench[sysid]' "
                          "(make install installs it)")
    return sysid


def joint_names(model: mujoco.MjModel) -> list[str]:
    return [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(model.njnt)]


def peer_spec(arm: Arm, parameters: np.ndarray) -> mujoco.MjSpec:
    """The arm's MuJoCo spec with its joints' bodies and joints given 13 dof standard
    parameters (harness.robots.inertials; the welded bodies' inertia in their joint's body),
    driven and sensed for the toolbox (drive_and_sense): the model the peer fits."""
    spec, model = arm.spec.copy(), arm.mujoco
    names = joint_names(model)
    for j, name in enumerate(names):
        body = model.jnt_bodyid[j]
        write_inertia(spec.body(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body)),
                      parameters[10 * j:10 * j + 10])
        for child in fixed_children(model, body):
            welded = spec.body(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, child))
            welded.explicitinertial, welded.fullinertia = True, np.full(6, np.nan)
            welded.mass, welded.inertia = MIN_MASS, [MIN_MASS] * 3
        values = parameters[10 * len(names) + j::len(names)]
        for field_name, value in zip(JOINT_FIELDS, values, strict=True):
            set_joint(spec.joint(name), field_name, value)
    return drive_and_sense(spec, names, np.zeros(len(names)))


def drive_and_sense(spec: mujoco.MjSpec, names: list[str], bias: np.ndarray) -> mujoco.MjSpec:
    """spec (changed, and returned) with its own actuators and sensors replaced by a motor per
    joint 'torque_<joint>' (gear 1, its affine bias the given one, N m) and sensors
    'q_<joint>', 'qd_<joint>' (the toolbox checks a log's columns against the model's sensors;
    it compares the rollout's state)."""
    for element in [*spec.actuators, *spec.sensors]:  # the file's own: the log's torque
        spec.delete(element)  # drives the joints, the rollout's q and qd are compared
    for name, b in zip(names, bias, strict=True):
        motor = spec.add_actuator(name=f"torque_{name}", target=name,
                                  trntype=mujoco.mjtTrn.mjTRN_JOINT)
        motor.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        motor.biasprm[0] = b
    for kind, prefix in ((mujoco.mjtSensor.mjSENS_JOINTPOS, "q"),
                         (mujoco.mjtSensor.mjSENS_JOINTVEL, "qd")):
        for name in names:
            spec.add_sensor(name=f"{prefix}_{name}", type=kind, objname=name,
                            objtype=mujoco.mjtObj.mjOBJ_JOINT)
    return spec


def file_spec(path) -> tuple[mujoco.MjSpec, np.ndarray]:
    """The MJCF at path (`export --format mjcf`'s: its motors' bias holds the sensor offset)
    driven and sensed for the toolbox, and that bias per joint (N m at the joint); read by
    harness.robots.files (the one parser)."""
    from pathlib import Path

    from harness.robots.files import mjcf_spec, plain_mujoco
    from harness.robots.mjcf_export import motor_bias

    model = plain_mujoco(Path(path))
    bias = motor_bias(model)
    return drive_and_sense(mjcf_spec(Path(path)), joint_names(model), bias), bias


def write_inertia(body, standard: np.ndarray) -> None:
    """A spec body given one body's 10 standard parameters (principal moments and axes). A
    consistent body on the edge (a plate, A + B = C) comes out of the toolbox's parameters up
    to 3e-16 kg m^2 past it by rounding, which MuJoCo refuses: its largest moment is lowered
    to the sum of the other two (MuJoCo's own balanceinertia would set all three to their
    mean)."""
    mass, c, moments, quat = body_inertials(standard)
    largest = int(np.argmax(moments))
    a, b = np.delete(moments, largest)
    moments[largest] = min(moments[largest], a + b)
    body.explicitinertial = True
    body.mass, body.ipos, body.inertia, body.iquat = mass, c, moments, quat
    body.fullinertia = np.full(6, np.nan)


def standard_of_pi(pi: np.ndarray) -> np.ndarray:
    """The toolbox's inertial vector (m, h, the 3x3 inertia about the origin, flat) as the
    project's 10 standard parameters (m, h, Ixx, Ixy, Iyy, Ixz, Iyz, Izz)."""
    inertia = np.asarray(pi[4:], float).reshape(3, 3)
    return np.r_[pi[:4], inertia[0, 0], inertia[0, 1], inertia[1, 1], inertia[0, 2],
                 inertia[1, 2], inertia[2, 2]]


def write_pseudo_inertia(body_name: str):
    """The toolbox modifier of a body's pseudo-inertia parameters theta (module docstring)."""
    from mujoco.sysid._src.model_modifier import pi_from_theta

    def modifier(spec: mujoco.MjSpec, param) -> None:
        write_inertia(spec.body(body_name), standard_of_pi(pi_from_theta(param.value)))
    return modifier


@dataclass(frozen=True)
class Region:
    """Where the fit may move the parameters: each body's (the toolbox's body_inertia_param
    arguments: mass x [low, high] of the start, principal stretches x [low, high], shear and
    centre of mass (m) +- around it) and each joint term's (None: BOUNDS; else x [low, high]
    of the start plus FLOOR, the motor's bias +- `bias` N m around its start)."""

    mass: tuple[float, float] = (0.1, 10.0)
    stretch: tuple[float, float] = (0.5, 2.0)
    shear: tuple[float, float] = (-0.5, 0.5)
    com: tuple[float, float] = (-0.5, 0.5)
    joint: tuple[float, float] | None = None
    bias: float | None = None

    def joint_bounds(self, field_name: str, start: float) -> tuple[float, float]:
        if self.joint is None:
            return BOUNDS[field_name]
        return self.joint[0] * start, self.joint[1] * start + FLOOR[field_name]

    def bias_bounds(self, start: float) -> tuple[float, float]:
        return BOUNDS["bias"] if self.bias is None else (start - self.bias, start + self.bias)


WIDE = Region()  # the toolbox's defaults and BOUNDS: a user's fit from the robot's file
NEAR = Region((0.8, 1.25), (0.8, 1.25), (-0.05, 0.05), (-0.02, 0.02), (0.5, 2.0), 1.0)
FLOOR = {"armature": 0.01, "damping": 0.1, "frictionloss": 0.1}  # room a zero start may grow


def peer_parameters(spec: mujoco.MjSpec, model: mujoco.MjModel, off_bounds: bool = True,
                    region: Region = WIDE):
    """The toolbox's ParameterDict of spec (drive_and_sense's), compiled as model: per joint its
    body's pseudo-inertia, armature, damping, frictionloss and its motor's bias, within region,
    started from the spec's values (off_bounds: those at a bound moved OFF_BOUND of the range
    in, as the toolbox advises from a rough start)."""
    sysid = toolbox()
    params = sysid.ParameterDict()
    for j, name in enumerate(joint_names(model)):
        body = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, model.jnt_bodyid[j])
        params.add(sysid.body_inertia_param(
            spec, model, body, sysid.InertiaType.Pseudo, mass_bound_mult=np.array(region.mass),
            ipos_bound_off=np.array(region.com), stretch_bound_mult=np.array(region.stretch),
            shear_bound_off=np.array(region.shear), modifier=write_pseudo_inertia(body)))
        for field_name in JOINT_FIELDS:
            start = joint_value(spec.joint(name), field_name)
            params.add(sysid.Parameter(
                f"{name}_{field_name}", start, *region.joint_bounds(field_name, start),
                modifier=lambda s, p, n=name, f=field_name: set_joint(s.joint(n), f, p.value[0])))
        start = float(spec.actuator(f"torque_{name}").biasprm[0])
        params.add(sysid.Parameter(
            f"{name}_bias", start, *region.bias_bounds(start),
            modifier=lambda s, p, n=name: _set_bias(s.actuator(f"torque_{n}"), p.value[0])))
    if off_bounds:
        params.move_off_bounds(fraction=OFF_BOUND)
    return params


def joint_value(joint, field_name: str) -> float:
    return float(np.ravel(getattr(joint, field_name))[0])


def set_joint(joint, field_name: str, value: float) -> None:
    """A spec joint's armature, damping (MuJoCo 4's first damping coefficient, the linear
    one) or frictionloss."""
    if field_name == "damping":
        joint.damping[0] = value
    else:
        setattr(joint, field_name, value)


def _set_bias(actuator, value: float) -> None:
    actuator.biasprm[0] = value


def standard_parameters(params, model: mujoco.MjModel) -> np.ndarray:
    """13 dof standard parameters of a fitted ParameterDict (peer_parameters')."""
    from mujoco.sysid._src.model_modifier import pi_from_theta

    out, joints = [], {f: [] for f in JOINT_FIELDS}
    for j, name in enumerate(joint_names(model)):
        body = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, model.jnt_bodyid[j])
        out.append(standard_of_pi(pi_from_theta(params[f"{body}_inertia"].value)))
        for f in JOINT_FIELDS:
            joints[f].append(float(params[f"{name}_{f}"].value[0]))
    return np.concatenate([*out, *(joints[f] for f in JOINT_FIELDS)])


def biases(params, model: mujoco.MjModel) -> np.ndarray:
    """Each motor's bias (N m) of a fitted ParameterDict (peer_parameters')."""
    return np.array([float(params[f"{n}_bias"].value[0]) for n in joint_names(model)])
