"""The bodies of an arm a load can ride on, and the torque of a unit point mass on one.

Which bodies: `candidate_bodies` (the last joints' bodies, among which the data choose: the
measured loop's payload, identify's drive gains' load) and `last_body` (the one a link names,
or the last). The torque: inverse dynamics is linear in the inertial parameters, so a payload
of mass m at the end effector adds m * tau_unit(q, qd, qdd), where tau_unit is the RNEA of the
same kinematic tree carrying nothing but 1 kg at the end-effector point (mass m, first moment
m c, rotational inertia m (|c|^2 I - c c^T) about the joint frame, c the end-effector position
in the last link's joint frame).
"""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin

from harness.errors import UserError

EE_FRAME = "end_effector"


def end_effector_point(model: pin.Model, frame: str = EE_FRAME) -> tuple[int, np.ndarray]:
    """Parent joint index and position (m) of the end-effector frame in that joint's frame.

    Falls back to the last joint's origin if the model has no such frame.
    """
    for f in model.frames:  # a URDF fixed joint and its child link share the name
        if f.name == frame:
            return int(f.parentJoint), np.asarray(f.placement.translation, dtype=float)
    return model.njoints - 1, np.zeros(3)


def unit_payload_model(model: pin.Model, frame: str = EE_FRAME) -> pin.Model:
    """A copy of model whose only mass is 1 kg at the end-effector point, without damping
    or armature."""
    unit = model.copy()
    for j in range(1, unit.njoints):
        unit.inertias[j] = pin.Inertia.Zero()
    joint, c = end_effector_point(model, frame)
    unit.inertias[joint] = pin.Inertia(1.0, c, np.zeros((3, 3)))
    unit.damping[:] = 0.0
    unit.armature[:] = 0.0
    return unit


class PayloadTorque:
    """tau_unit(q, qd, qdd): (n, dof) N m per kg of end-effector payload."""

    def __init__(self, model: pin.Model, frame: str = EE_FRAME):
        self.model = unit_payload_model(model, frame)
        self.data = self.model.createData()

    def __call__(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        out = np.empty_like(q)
        for k in range(len(q)):
            out[k] = pin.rnea(self.model, self.data, q[k], qd[k], qdd[k])
        return out

    def symbolic(self, q, qd, qdd):
        """CasADi form for the planner (harness.robots.casadi_rnea on the unit-payload tree)."""
        from harness.robots.casadi_rnea import symbolic_rnea

        return symbolic_rnea(self.model, q, qd, qdd)


CANDIDATES = 3  # the bodies the last joints move: where a load is looked for


def candidate_bodies(arm, count: int = CANDIDATES) -> tuple:
    """The bodies (identification.closeloop.candidates.payload.LastBody) the last `count` joints move,
    the last first: where the measured loop looks for a load when no link is named; the data
    choose among them (identification.closeloop.candidates.load_body)."""
    from identification.closeloop.candidates.payload import LastBody

    model = arm.pinocchio
    last = model.njoints - 1
    out = []
    for joint in range(last, max(last - count, 0), -1):
        names = [f.name for f in model.frames
                 if f.type == pin.FrameType.BODY and f.parentJoint == joint]
        out.append(LastBody(arm.chain, names[0] if names else model.names[joint],
                            0 if joint == last else joint))
    return tuple(out)


# a revolute joint so named is a gripper's jaw (an arm joint here: harness.robots.urdf), and
# what the gripper holds rides on the body the jaw turns on, not on the jaw
JAW = re.compile(r"gripper|finger|jaw|claw", re.IGNORECASE)


def last_body(arm, link: str | None = None):
    """The body a payload rides on (identification.closeloop.candidates.payload.LastBody): the link
    named (any link of the arm, a fixed one on the body it is fixed to), else the link the
    last joint moves (the first body frame of that joint), or the one before when the last
    joint is a gripper's jaw (JAW: SO-100/101, TALOS's arm, the Z1). UserError for a link
    the arm lacks or one no joint moves."""
    from identification.closeloop.candidates.payload import LastBody

    model = arm.pinocchio
    bodies = [f for f in model.frames if f.type == pin.FrameType.BODY]
    if link is None:
        joint = model.njoints - 1
        joint -= bool(joint > 1 and JAW.search(model.names[joint]))
    else:
        named = [f for f in bodies if f.name == link]
        if not named:
            raise UserError(f"no link of {arm.label} is named {link!r} (the load's body; "
                            f"its links: {', '.join(f.name for f in bodies)})")
        joint = int(named[0].parentJoint)
        if joint == 0:
            raise UserError(f"the load's body {link!r}: no joint moves it (fixed to the base)")
    names = [f.name for f in bodies if f.parentJoint == joint]
    return LastBody(arm.chain, link or (names[0] if names else model.names[joint]),
                    0 if joint == model.njoints - 1 else joint)
