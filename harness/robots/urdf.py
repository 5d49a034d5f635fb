"""URDF text prepared for both engines: the arm's joints only, no meshes.

A robot description often carries more than the arm: gripper fingers (prismatic
joints at the end of the chain), meshes behind `package://` paths. The harness
identifies and plans the arm, so:
- a prismatic joint with no revolute joint below it (a finger, a gripper jaw) is
  held fixed (its link's inertia stays, rigidly attached at its zero position);
- a prismatic joint with revolute joints below it is an arm joint the harness cannot
  handle, and a floating or planar joint is a moving base: both are errors;
- a continuous joint (an unbounded revolute joint: Pinocchio would give it a (cos, sin)
  configuration, nq = 2 for nv = 1) is read as a revolute joint over one turn,
  [-pi, pi], keeping its effort and velocity limits: every command works with one angle
  per joint, and no conversion between configurations is needed anywhere;
- a link inertia MuJoCo refuses (a principal moment <= 0, or one larger than the other two
  together: finger_edu's izz = 0, which Pinocchio accepts) is repaired to the nearest one it
  takes (repair_inertias: the smallest moments raised, the axes kept), said once on stderr
  and recorded (Arm.record's `repaired_inertias`), in the text both engines read;
- given a chain (base link, tip link: `--chain`), every joint off the path between them is
  held fixed first (harness.robots.subchain), so a whole robot's arm is such an arm;
- visual and collision geometry is dropped (inertias come from <inertial>), and ROS's
  lower = upper = 0 "no limit" removed, so MuJoCo loads the file without warnings;
- a joint's Coulomb friction (<dynamics friction>) is dropped: MuJoCo would make
  it a frictionloss constraint inside mj_inverse (a soft constraint, not sign(qd) times a
  constant), absent from Pinocchio's RNEA, the baseline (Unitree's Z1 states 1-2 N m: 3.6 %
  of the peak torque apart); viscous damping stays in both (PinocchioModel adds it). The
  torque data are the rigid body's and the damping's; Coulomb friction is what the
  close-the-loop plants and the bench's next-run draws add, each with its own known law.
The same text goes to MuJoCo (mj compile) and Pinocchio (buildModelFromXML), so the
two models agree by construction (checked in the tests).
"""

from __future__ import annotations

import math
import re
import sys
import xml.etree.ElementTree as ET

import numpy as np

from harness.errors import UserError
from harness.robots.subchain import hold_outside_chain

MOVING = ("revolute", "continuous")
# Attributes that hold numbers: a NaN or inf there is one clear error, never a model that
# one engine accepts with a warning and the other refuses.
NUMERIC = ("xyz", "rpy", "value", "ixx", "ixy", "ixz", "iyy", "iyz", "izz", "lower", "upper",
           "effort", "velocity", "damping", "friction")


def _check_numbers(root: ET.Element, source: str) -> None:
    """UserError naming the first numeric attribute that is not a list of finite numbers."""
    for element in root.iter():
        for key in NUMERIC:
            raw = element.get(key)
            if raw is None or (key == "value" and element.tag != "mass"):  # a material's name
                continue
            try:
                ok = all(math.isfinite(float(v)) for v in raw.split())
            except ValueError:
                ok = False
            if not ok:
                raise UserError(f"invalid URDF {source}: <{element.tag} {key}=\"{raw}\">: "
                                "expected finite numbers")


MOMENT_FLOOR = 1e-6  # a repaired principal moment: at least this fraction of the largest
MOMENT_MIN = 1e-9  # kg m^2, and at least this
MUJOCO_MIN = 1e-15  # mjMINVAL: MuJoCo refuses a principal moment not above it
# of the largest moment, above the triangle inequality's equality: MuJoCo checks A + B >= C on
# its own eigenvalues of the written tensor, which at equality can round either way (the
# Allegro hand's link_15.0 was refused after a repair to equality)
TRIANGLE_SLACK = 1e-6
KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
_said: set[tuple[str, str]] = set()


def repair_inertias(root: ET.Element) -> list[dict]:
    """Every link inertia MuJoCo would refuse, repaired in place to the nearest valid one:
    its principal moments (eigenvalues) raised to at least MOMENT_FLOOR of the largest (and
    MOMENT_MIN), then the smallest raised until the two smaller hold the largest (a rigid
    body's triangle inequality, with TRIANGLE_SLACK), its principal axes kept. One entry per
    link repaired: the link, the inertia before and after (ixx, ixy, ixz, iyy, iyz, izz; kg m^2)."""
    repairs = []
    for link in root.iter("link"):
        inertia = link.find("inertial/inertia")
        if inertia is None:
            continue
        try:
            v = [float(inertia.get(k, "0")) for k in KEYS]
        except ValueError:  # not a number: the engines' reading says so
            continue
        if not any(v):  # no inertia stated (a frame): MuJoCo takes it unless the body moves
            continue
        matrix = np.array([[v[0], v[1], v[2]], [v[1], v[3], v[4]], [v[2], v[4], v[5]]])
        moments, axes = np.linalg.eigh(matrix)
        if moments[0] > MUJOCO_MIN and moments[0] + moments[1] >= moments[2]:
            continue  # MuJoCo's checks: positive moments, the triangle inequality
        fixed = np.maximum(moments, max(MOMENT_FLOOR * moments[-1], MOMENT_MIN))
        fixed[0] = max(fixed[0], fixed[2] - fixed[1] + TRIANGLE_SLACK * fixed[2])
        new = axes @ np.diag(fixed) @ axes.T
        after = [new[0, 0], new[0, 1], new[0, 2], new[1, 1], new[1, 2], new[2, 2]]
        for key, value in zip(KEYS, after, strict=True):
            inertia.set(key, repr(float(value)))
        repairs.append({"link": link.get("name", ""), "before": v,
                        "after": [float(x) for x in after]})
    return repairs


def _say(source: str, repairs: list[dict]) -> None:
    """One note on stderr per repaired link and file, the first time it is read."""
    for r in repairs:
        if (source, r["link"]) in _said:
            continue
        _said.add((source, r["link"]))
        changed = ", ".join(f"{k} {a:.3g} -> {b:.3g}" for k, a, b in
                            zip(KEYS, r["before"], r["after"], strict=True) if a != b)
        print(f"note: {source}: the inertia of link '{r['link']}' is not one MuJoCo accepts (a "
              f"principal moment <= 0 or over the other two together); repaired to the nearest "
              f"valid one: {changed} kg m^2", file=sys.stderr)


def arm_urdf(text: str, source: str, chain: tuple[str, str] | None = None,
             hold: tuple[tuple[str, float], ...] = ()) -> str:
    """The URDF with non-arm joints held fixed; UserError if it is not a fixed-base arm.
    chain: (base link, tip link): the arm between them, every other joint held fixed, at
    the positions hold states for some (harness.robots.subchain)."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise UserError(f"invalid URDF {source}: {exc}") from None
    if root.tag != "robot":
        raise UserError(f"invalid URDF {source}: the root element is <{root.tag}>, not <robot>")
    _check_numbers(root, source)
    held_outside = hold_outside_chain(root, *chain, source, hold) if chain else []
    joints = root.findall("joint")
    below: dict[str, list[ET.Element]] = {}
    for joint in joints:
        parent = joint.find("parent")
        if parent is not None:
            below.setdefault(parent.get("link", ""), []).append(joint)

    def moves_below(joint: ET.Element) -> bool:
        child = joint.find("child")
        stack = list(below.get(child.get("link", "") if child is not None else "", []))
        while stack:
            j = stack.pop()
            if j.get("type") in MOVING:
                return True
            c = j.find("child")
            stack += below.get(c.get("link", "") if c is not None else "", [])
        return False

    continuous = [j for j in joints if j.get("type") == "continuous"]
    coulomb = [d for j in joints for d in j.findall("dynamics") if d.get("friction") is not None]
    repaired = repair_inertias(root)
    _say(source, repaired)
    if continuous or coulomb or repaired or held_outside:
        for joint in continuous:
            _one_turn(joint)
        for dynamics in coulomb:
            del dynamics.attrib["friction"]
        text = ET.tostring(root, encoding="unicode")
    held = []
    for joint in joints:
        kind, name = joint.get("type"), joint.get("name")
        if kind in ("floating", "planar"):
            raise UserError(f"URDF {source}: joint '{name}' is {kind}: a moving base is not "
                            "supported (fixed-base serial arms only; a whole robot's arm: "
                            "--chain BASE_LINK:TIP_LINK)")
        if kind == "prismatic":
            if moves_below(joint):
                raise UserError(f"URDF {source}: prismatic arm joint '{name}' is not supported "
                                "(revolute arm joints only; a whole robot's arm: --chain "
                                "BASE_LINK:TIP_LINK holds the joints off it fixed)")
            held.append(name)
    if not held:
        return text
    pattern = "|".join(re.escape(n) for n in held)
    text = re.sub(rf'(<joint\b[^>]*name="(?:{pattern})"[^>]*type=")prismatic"', r'\1fixed"', text)
    text = re.sub(rf'(<joint\b[^>]*type=")prismatic("[^>]*name="(?:{pattern})")', r"\1fixed\2", text)
    return re.sub(r"<mimic\b[^>]*/>", "", text)


def _one_turn(joint: ET.Element) -> None:
    """A continuous joint made a revolute joint over [-pi, pi], in place; an effort or
    velocity limit it states is kept (urdfdom requires both on a revolute joint: a missing
    one is written unbounded, 1e6)."""
    joint.set("type", "revolute")
    limit = joint.find("limit")
    if limit is None:
        limit = ET.SubElement(joint, "limit")
    limit.set("lower", repr(-math.pi))
    limit.set("upper", repr(math.pi))
    for key in ("effort", "velocity"):
        if limit.get(key) is None:
            limit.set(key, "1e6")


def strip_geometry(urdf_text: str) -> str:
    """Drop <visual> and <collision> blocks and tell MuJoCo to keep every body."""
    text = re.sub(r"<visual\b.*?</visual>", "", urdf_text, flags=re.S)
    text = re.sub(r"<collision\b.*?</collision>", "", text, flags=re.S)
    # ROS writes lower = upper = 0 for "no limit"; MuJoCo would warn and ignore it.
    text = re.sub(r'lower="0"\s+upper="0"', "", text)
    compiler = (
        '<mujoco><compiler angle="radian" discardvisual="true" fusestatic="false" '
        'inertiafromgeom="false" autolimits="true"/></mujoco>'
    )
    return re.sub(r"(<robot\b[^>]*>)", r"\1" + compiler, text, count=1)
