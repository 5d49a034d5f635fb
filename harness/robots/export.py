"""A consistent fit's bodies written into the robot's own file, or as a labelled table.

The standard parameters are those MODEL.json's metrics.physical holds (harness.robots.inertials'
order: per body about its joint's frame, which for a URDF is the child link's frame, then per
joint armature, viscous, Coulomb). urdf: every moving link's <inertial> and its joint's
<dynamics damping friction> (the links below it that the identification held fixed - welded
links, a gripper's fingers - are in its parameters and left massless; URDF has no armature);
mjcf: MuJoCo's model of the robot with the same inertials and armature, the model's friction and
sensor offset in MuJoCo's terms (harness.robots.mjcf_export);
csv: body or joint, parameter, value, unit, nominal, about (the frame of a body's first
moment and inertia: its link frame, not the centre of mass). A model without bodies (the sparse fit on
base atoms, a feature model) exports its terms as csv and refuses urdf/mjcf in one line.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

from harness.errors import UserError
from harness.io import atomic_write
from harness.robots.arm import Arm
from harness.robots.inertials import centroidal_inertia, model_standard_parameters
from harness.robots.mjcf_export import write_mjcf
from identification.library.kinematic import atom_unit
from identification.model import joint_entries

FORMATS = ("urdf", "mjcf", "csv")
BODY_UNITS = (("mass", "kg"), ("mc_x", "kg m"), ("mc_y", "kg m"), ("mc_z", "kg m"),
              ("Ixx", "kg m^2"), ("Ixy", "kg m^2"), ("Iyy", "kg m^2"), ("Ixz", "kg m^2"),
              ("Iyz", "kg m^2"), ("Izz", "kg m^2"))
JOINT_UNITS = (("armature", "kg m^2"), ("viscous", "N m s/rad"), ("coulomb", "N m"))
# the csv's `about` column: what frame a body's parameter is in (MODEL.json's consistent fit
# gives the same standard parameters; a URDF's <inertial> is about the centre of mass)
LINK_FRAME = "the link frame (its joint's)"
ABOUT = {"mc": f"in {LINK_FRAME}",
         "I": f"about the origin of {LINK_FRAME} in its axes; not about the centre of mass"}
CSV_HEADER = "item,parameter,value,unit,nominal,about"


def body_table(params: np.ndarray, arm: Arm) -> list[tuple]:
    """(body or joint, parameter, value, unit, nominal, about) rows of 13 dof standard
    parameters (about: the frame a body's first moment or inertia is in, ABOUT)."""
    model = _pinocchio(arm, params)
    nominal = arm.nominal.atom_parameters()
    dof = model.nv
    names = list(model.names)[1:]
    rows = []
    for j in range(dof):
        body = next((f.name for f in model.frames if f.parentJoint == j + 1
                     and f.type == pin.FrameType.BODY), names[j])
        for k, (name, unit) in enumerate(BODY_UNITS):
            about = ABOUT.get(name[:2] if name.startswith("mc") else name[:1], "")
            rows.append((body, name, params[10 * j + k], unit, nominal[10 * j + k], about))
    for i, (name, unit) in enumerate(JOINT_UNITS):
        for j in range(dof):
            k = (10 + i) * dof + j
            rows.append((names[j], name, params[k], unit, nominal[k], ""))
    return rows


def _pinocchio(arm: Arm, params: np.ndarray) -> pin.Model:
    """The arm's Pinocchio model, UserError when it has not the parameters' joint count."""
    model = arm.pinocchio
    if params.size != 13 * model.nv:
        raise UserError(f"the model has {params.size} standard parameters, robot {arm.label} needs "
                        f"{13 * model.nv} (13 per joint)")
    return model


def term_table(payload: dict) -> list[tuple]:
    """(joint, term, coefficient, unit) rows of a model without bodies: its own terms and
    offset per joint (a feature model's term units are left empty: they depend on the term)."""
    rows = []
    for j, joint in enumerate(joint_entries(payload), start=1):
        for term, coefficient in zip(joint["terms"], joint["coefficients"], strict=True):
            rows.append((f"joint{j}", term, float(coefficient), _term_unit(term)))
        rows.append((f"joint{j}", "offset", float(joint.get("offset", 0.0)), "N m"))
    return rows


def _term_unit(term: str) -> str:
    try:
        return atom_unit(term)
    except (KeyError, ValueError):
        return ""


def _csv(rows: list[tuple], header: str) -> str:
    return header + "\n" + "".join(",".join(f"{x:.10g}" if isinstance(x, float) else str(x)
                                             for x in row) + "\n" for row in rows)


def export_urdf(params: np.ndarray, arm: Arm) -> str:
    """The arm's URDF text with these standard parameters (module docstring)."""
    urdf = arm.entry.urdf
    if urdf is None:
        raise UserError(f"robot {arm.label} has no URDF to rewrite (try --format mjcf)")
    root = ET.parse(urdf).getroot()
    model = _pinocchio(arm, params)
    dof = model.nv
    _absolute_meshes(root, Path(urdf).parent)
    joints = {j.get("name"): j for j in root.findall("joint")}  # not a <transmission>'s
    children = {}
    for j in joints.values():
        children.setdefault(j.find("parent").get("link"), []).append(j)
    links = {link.get("name"): link for link in root.findall("link")}
    arm = set(list(model.names)[1:])
    for k, name in enumerate(list(model.names)[1:dof + 1]):
        joint = joints[name]
        child = joint.find("child").get("link")
        _set_inertial(links[child], *centroidal_inertia(params[10 * k:10 * k + 10]))
        for welded in _welded(child, children, arm):
            _set_inertial(links[welded], 0.0, np.zeros(3), np.zeros((3, 3)))
        dynamics = joint.find("dynamics")
        if dynamics is None:
            dynamics = ET.SubElement(joint, "dynamics")
        dynamics.set("damping", f"{params[11 * dof + k]:.12g}")
        dynamics.set("friction", f"{params[12 * dof + k]:.12g}")
    return ET.tostring(root, encoding="unicode")


def _absolute_meshes(root: ET.Element, folder: Path) -> None:
    """Relative mesh paths made absolute: the exported file is read from elsewhere."""
    for mesh in root.iter("mesh"):
        name = mesh.get("filename", "")
        if name and "://" not in name and not Path(name).is_absolute():
            mesh.set("filename", str((folder / name).resolve()))


def _welded(link: str, children: dict, arm: set[str]) -> list[str]:
    """The links below link reached without an arm joint (fixed links, a gripper's fingers):
    the identification held them fixed, so their mass is in link's parameters."""
    out = []
    for j in children.get(link, []):
        if j.get("name") not in arm:
            name = j.find("child").get("link")
            out += [name, *_welded(name, children, arm)]
    return out


def _set_inertial(link, mass: float, c, inertia) -> None:
    old = link.find("inertial")
    if old is not None:
        link.remove(old)
    inertial = ET.Element("inertial")
    link.insert(0, inertial)
    ET.SubElement(inertial, "origin", xyz=" ".join(f"{x:.12g}" for x in c), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=f"{mass:.12g}")
    names = {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2),
             "izz": (2, 2)}
    ET.SubElement(inertial, "inertia", {k: f"{inertia[i]:.12g}" for k, i in names.items()})


def export_model(payload: dict, arm: Arm, fmt: str, out: str | Path, offset=None, log=None,
                 report: list[str] | None = None) -> str:
    """Write MODEL.json's payload for arm in fmt to out, whole or not at all; what it wrote,
    in words. mjcf: offset (dof,) N m is the sensor offset its motors' bias holds (None:
    zero); log (q, qd, qdd, the torque the model says the sensor reads) measures what the
    approximation costs (write_mjcf); report collects what was approximated, in lines."""
    if fmt not in FORMATS:
        raise UserError(f"--format must be one of {', '.join(FORMATS)}, got {fmt}")
    params = model_standard_parameters(payload)
    if params is None:
        if fmt != "csv":
            raise UserError(f"this model has no bodies (a sparse or feature model: identifiable "
                            f"combinations only); export it as csv, or identify with --prior "
                            f"nominal|flat for a {fmt}")
        text = _csv(term_table(payload), "joint,term,coefficient,unit")
    elif fmt == "csv":
        text = _csv(body_table(params, arm), CSV_HEADER)
    elif fmt == "urdf":
        text = export_urdf(params, arm)
    else:
        atomic_write(out, lambda tmp: write_mjcf(tmp, payload, params, arm, offset, log, report),
                     suffix=".xml")
        return f"robot {arm.label}'s MuJoCo model with the identified bodies and friction"
    atomic_write(out, lambda tmp: Path(tmp).write_text(text), suffix="." + fmt)
    if params is None:
        return "the model's terms (it has no bodies)"
    if fmt == "csv":
        return (f"robot {arm.label}'s identified bodies and joints beside the URDF's (first "
                f"moments and inertias about {LINK_FRAME}, not the centre of mass)")
    armature = params[10 * arm.pinocchio.nv:11 * arm.pinocchio.nv]
    dropped = ("" if not np.any(armature) else "; the identified armature ("
               + ", ".join(f"{a:.3g}" for a in armature) + " kg m^2) is not in it: URDF has "
               "none (--format mjcf or csv keeps it)")
    return f"robot {arm.label}'s URDF with the identified bodies{dropped}"
