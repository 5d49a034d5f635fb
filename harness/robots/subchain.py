"""An arm inside a whole robot's URDF: the joints between two links (`--chain BASE:TIP`),
every other joint held fixed.

A whole robot's description (a torso, two arms, a head, wheels: TIAGo, TALOS) is one tree;
the harness identifies and plans one serial arm of it. hold_outside_chain turns every moving
joint that is not on the path from the base link down to the tip link into a fixed joint at
its held position, folded into the joint's origin: the position stated for it (`--hold
JOINT=POSITION,...`), else 0 (the URDF's zero, the joint's origin as written), or the nearest
limit when 0 lies outside [lower, upper]. What it holds is returned
(joint, type, position in rad or m) and recorded with the arm (Arm.record's `held`).

The robot's root link stays the world frame: the held torso, head and other arm stay in place
(the gravity direction and every position are in the root's frame, as in the full model), and
what hangs below the tip (a hand, its fingers) stays on the last link. The chain's dynamics
are then those of Pinocchio's buildReducedModel of the whole model locked at the same
positions (checked in tests/test_subchain.py).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from harness.errors import UserError

MOVING = ("revolute", "continuous", "prismatic", "floating", "planar")


HOLD_MARK = "@"  # a chain's text with stated holds: BASE:TIP@JOINT=POSITION,...


def parse_chain(text: str) -> tuple[str, str]:
    """(base link, tip link) of 'BASE:TIP' (stated holds after HOLD_MARK left out); UserError
    otherwise."""
    parts = text.split(HOLD_MARK, 1)[0].split(":")
    if len(parts) != 2 or not all(p.strip() for p in parts):
        raise UserError(f"--chain must be BASE_LINK:TIP_LINK (two link names), got {text!r}")
    return parts[0].strip(), parts[1].strip()


def parse_hold(text: str) -> tuple[tuple[str, float], ...]:
    """((joint, position), ...) of 'JOINT=POSITION,...' (rad or m), or of a chain's text after
    HOLD_MARK; () for none; UserError unless each is a name and a finite number."""
    text = text.split(HOLD_MARK, 1)[1] if HOLD_MARK in text else ("" if ":" in text else text)
    out = []
    for item in filter(None, (i.strip() for i in text.split(","))):
        name, _, value = item.partition("=")
        try:
            position = float(value)
        except ValueError:
            position = float("nan")
        if not name.strip() or not np.isfinite(position):
            raise UserError(f"--hold must be JOINT=POSITION[,...] (rad, or m for a prismatic "
                            f"joint), got {item!r}")
        out.append((name.strip(), position))
    return tuple(out)


def chain_path(root: ET.Element, base: str, tip: str, source: str) -> list[ET.Element]:
    """The joints from base down to tip (base first); UserError naming what is wrong."""
    links = {link.get("name") for link in root.iter("link")}
    for role, name in (("base", base), ("tip", tip)):
        if name not in links:
            raise UserError(f"URDF {source}: --chain {role} link '{name}' is not a link of the "
                            f"robot ({len(links)} links)")
    into = {j.find("child").get("link"): j for j in root.findall("joint")
            if j.find("child") is not None}
    path, link = [], tip
    while link != base:
        joint = into.get(link)
        if joint is None:
            raise UserError(f"URDF {source}: --chain tip link '{tip}' does not hang below base "
                            f"link '{base}' (its root is '{link}')")
        path.append(joint)
        link = joint.find("parent").get("link")
    if not any(j.get("type") in MOVING for j in path):
        raise UserError(f"URDF {source}: no moving joint between links '{base}' and '{tip}'")
    return path[::-1]


def hold_outside_chain(root: ET.Element, base: str, tip: str, source: str,
                       stated: tuple[tuple[str, float], ...] = ()) -> list[dict]:
    """Every moving joint of root (a URDF, changed in place) off the path from base to tip
    made fixed at its held position (module docstring), or at the position stated for it
    (--hold: UserError for a joint that is not held or a position outside its limits); the
    held joints, in file order: {"joint", "type", "position"} (rad, or m for a prismatic
    joint)."""
    on_path = {id(j) for j in chain_path(root, base, tip, source)}
    stated_at = dict(stated)
    held = []
    for joint in root.findall("joint"):
        kind = joint.get("type")
        if kind not in MOVING or id(joint) in on_path:
            continue
        position = stated_at.pop(joint.get("name", ""), None)
        position = _held_position(joint) if position is None else _within(joint, position,
                                                                           source)
        _fold(joint, position)
        joint.set("type", "fixed")
        for child in [c for c in joint if c.tag in ("mimic", "limit", "dynamics", "axis",
                                                    "safety_controller", "calibration")]:
            joint.remove(child)
        held.append({"joint": joint.get("name", ""), "type": kind, "position": position})
    if stated_at:
        raise UserError(f"URDF {source}: --hold names joint '{next(iter(stated_at))}', which is "
                        f"not a moving joint off the chain {base}:{tip}")
    return held


def _within(joint: ET.Element, position: float, source: str) -> float:
    """position, UserError when it lies outside the joint's limits."""
    limit = joint.find("limit")
    if joint.get("type") in ("revolute", "prismatic") and limit is not None:
        lower, upper = float(limit.get("lower", 0)), float(limit.get("upper", 0))
        if not lower == upper == 0 and not lower <= position <= upper:
            raise UserError(f"URDF {source}: --hold {joint.get('name')}={position:g} is outside "
                            f"its limits [{lower:g}, {upper:g}]")
    return position


def _held_position(joint: ET.Element) -> float:
    """0, or the nearest of the joint's limits when 0 lies outside them."""
    limit = joint.find("limit")
    if joint.get("type") not in ("revolute", "prismatic") or limit is None:
        return 0.0
    lower, upper = float(limit.get("lower", 0)), float(limit.get("upper", 0))
    if lower == upper == 0 or lower > upper:  # ROS's "no limit"
        return 0.0
    return float(min(max(0.0, lower), upper))


def _fold(joint: ET.Element, position: float) -> None:
    """The joint's origin moved to where its child sits at position (rad or m)."""
    if position == 0.0:
        return
    import pinocchio as pin

    origin = joint.find("origin")
    if origin is None:
        origin = ET.SubElement(joint, "origin")
    xyz = np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])
    rotation = pin.rpy.rpyToMatrix(*[float(v) for v in origin.get("rpy", "0 0 0").split()])
    axis_element = joint.find("axis")
    axis = np.array([float(v) for v in (axis_element.get("xyz", "1 0 0") if axis_element
                                        is not None else "1 0 0").split()])
    axis = axis / np.linalg.norm(axis)
    if joint.get("type") == "prismatic":
        xyz = xyz + rotation @ (axis * position)
    else:
        rotation = rotation @ pin.exp3(axis * position)
    origin.set("xyz", " ".join(repr(float(v)) for v in xyz))
    origin.set("rpy", " ".join(repr(float(v)) for v in pin.rpy.matrixToRpy(rotation)))
