"""Torque of a unit point mass at the end effector, from the declared Pinocchio model.

Inverse dynamics is linear in the inertial parameters, so a payload of mass m
at the end effector adds m * tau_unit(q, qd, qdd), where tau_unit is the RNEA
of the same kinematic tree carrying nothing but 1 kg at the end-effector point
(mass m, first moment m c, rotational inertia m (|c|^2 I - c c^T) about the
joint frame, c the end-effector position in the last link's joint frame).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

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


def last_body(arm):
    """The arm's last body (identification.closeloop.payload.LastBody): its chain and the name
    of the link its last joint moves (the first body frame of that joint)."""
    from identification.closeloop.payload import LastBody

    model = arm.pinocchio
    joint = model.njoints - 1
    names = [f.name for f in model.frames
             if f.type == pin.FrameType.BODY and f.parentJoint == joint]
    return LastBody(arm.chain, names[0] if names else model.names[joint])
