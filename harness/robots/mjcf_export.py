"""The MJCF `export --format mjcf` writes: MuJoCo's model of the robot with a consistent fit's
bodies and armature, the model's friction and sensor offset in MuJoCo's own terms
(harness.robots.native_friction), at full precision, with what was approximated said in a
comment at its top."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np

from harness.robots.arm import Arm
from harness.robots.inertials import set_standard_parameters
from harness.robots.native_friction import inverse_gap, native_friction, set_native_friction


def full_precision(path: str, model: mujoco.MjModel) -> ET.ElementTree:
    """The MJCF at path with every body's inertial and every joint's armature, damping and
    frictionloss (and its solreffriction, solimpfriction) rewritten from model at full
    precision. MuJoCo's writer keeps 6 significant digits: a consistent fit leaves thin links
    on the edge of the triangle inequality (the Panda's link 5: A + B - C = 9e-9 of C = 0.018
    kg m^2), which 6 digits break, and plain MuJoCo then refuses the file ('inertia must
    satisfy A + B >= C')."""
    def text(values) -> str:
        return " ".join(f"{v:.17g}" for v in np.atleast_1d(values))
    tree = ET.parse(path)
    for body in tree.getroot().iter("body"):
        i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body.get("name", ""))
        inertial = body.find("inertial")
        if i < 0 or inertial is None:
            continue
        inertial.attrib.pop("fullinertia", None)
        inertial.set("pos", text(model.body_ipos[i]))
        inertial.set("quat", text(model.body_iquat[i]))
        inertial.set("mass", text(model.body_mass[i]))
        inertial.set("diaginertia", text(model.body_inertia[i]))
    for joint in tree.getroot().iter("joint"):
        j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, joint.get("name", ""))
        if j < 0:
            continue
        dof = model.jnt_dofadr[j]
        joint.set("armature", text(model.dof_armature[dof]))
        joint.set("damping", text(model.dof_damping[dof]))
        joint.set("frictionloss", text(model.dof_frictionloss[dof]))
        joint.set("solreffriction", text(model.dof_solref[dof]))
        joint.set("solimpfriction", text(model.dof_solimp[dof]))
    return tree


def write_mjcf(path: str, payload: dict, params: np.ndarray, arm: Arm, offset, log,
                report: list[str] | None) -> None:
    """MuJoCo's model of the arm at path with the identified bodies, the model's friction in
    MuJoCo's terms (harness.robots.native_friction) and a motor per joint whose bias holds the
    sensor offset (_bias_motors); a comment in the file (and report) says what was approximated and, given
    a log, the torque RMS gap per joint of the file's inverse dynamics against the model."""
    from harness.robots.files import model_to_save, plain_mujoco

    model = set_standard_parameters(model_to_save(arm.entry), params)
    frictions = native_friction(payload, params, arm.velocity_limit)
    set_native_friction(model, frictions)
    offset = np.zeros(model.njnt) if offset is None else np.asarray(offset, float)
    bias = -(offset + np.array([f.constant for f in frictions]))
    mujoco.mj_saveLastXML(path, model)
    tree = full_precision(path, model)
    root = tree.getroot()
    _bias_motors(root, model, bias)
    tree.write(path)
    lines = approximation_lines(frictions, bias)
    if log is not None:
        gap = inverse_gap(plain_mujoco(Path(path)), bias, *log)
        lines.append("torque RMS gap per joint on the log's states (mj_inverse of this file, "
                     "less its motors' bias, against the model's torque): "
                     + ", ".join(f"{g:.3g}" for g in gap) + " N m")
    root.insert(0, ET.Comment(" " + "\n     ".join(lines) + " "))
    tree.write(path)
    if report is not None:
        report.extend(lines)


def approximation_lines(frictions, bias: np.ndarray) -> list[str]:
    """What the MJCF holds of the model's friction and offset, and what it approximates."""
    lines = ["exported by torquebench: joint friction as MuJoCo's frictionloss f (its linear "
             "zone eps set by solimpfriction's dmin) + damping d, fitted to the model's "
             "friction on [-V, V] rad/s; a motor per joint (the file's own, else "
             "'sensor_torque_<joint>'): ctrl x gain x gear = the torque the sensor reads, the force on "
             "the joint that + bias (less the sensor offset and the fit's constant)"]
    for j, f in enumerate(frictions, start=1):
        own = f", its own column {f.own:.3g} N m approximated" if f.own else ""
        lines.append(f"joint {j}: f {f.frictionloss:.4g} N m, eps {f.width:.3g} rad/s, d "
                     f"{f.damping:.4g} N m s/rad, bias {bias[j - 1]:.4g} N m{own}; friction RMS "
                     f"gap {f.gap:.3g} N m over V = {f.speed:.3g}")
    return lines


def motor_bias(model: mujoco.MjModel) -> np.ndarray:
    """Each joint's motors' bias (N m at the joint: biasprm[0] x gear, summed over the
    actuators on the joint), what _bias_motors wrote: the force on the joint is the torque the
    sensor reads + this."""
    bias = np.zeros(model.njnt)
    for a in range(model.nu):
        if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT:
            bias[model.actuator_trnid[a, 0]] += model.actuator_biasprm[a, 0] \
                * model.actuator_gear[a, 0]
    return bias


def _bias_motors(root: ET.Element, model: mujoco.MjModel, bias: np.ndarray) -> None:
    """Each joint's motor given the bias (N m at the joint): the file's own motor on the joint
    where it has one (_motor_of), its bias made affine, else a new motor
    'sensor_torque_<joint>' of gear 1; its control is the torque the sensor reads."""
    actuators = root.find("actuator")
    if actuators is None:
        actuators = ET.SubElement(root, "actuator")
    elements = list(actuators)  # in the compiled model's order
    for j in range(model.njnt):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
        own = [a for a in range(min(model.nu, len(elements))) if _motor_of(model, a, j)]
        if len(own) == 1:
            element, gear = elements[own[0]], model.actuator_gear[own[0], 0]
            element.tag = "general"  # MuJoCo's writer gives one already; <motor> has no bias
        else:
            element, gear = ET.SubElement(actuators, "general", name=f"sensor_torque_{name}",
                                          joint=name, ctrllimited="false"), 1.0
        element.set("biastype", "affine")
        element.set("biasprm", f"{bias[j] / gear:.17g} 0 0")


def _motor_of(model: mujoco.MjModel, actuator: int, joint: int) -> bool:
    """Whether the actuator is a plain motor of the joint: a joint transmission, no dynamics,
    a fixed gain and no bias (so the bias is free to hold the offset)."""
    return (model.actuator_trntype[actuator] == mujoco.mjtTrn.mjTRN_JOINT
            and model.actuator_trnid[actuator, 0] == joint
            and model.actuator_dyntype[actuator] == mujoco.mjtDyn.mjDYN_NONE
            and model.actuator_gaintype[actuator] == mujoco.mjtGain.mjGAIN_FIXED
            and model.actuator_biastype[actuator] == mujoco.mjtBias.mjBIAS_NONE)
