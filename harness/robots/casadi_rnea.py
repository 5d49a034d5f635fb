"""Recursive Newton-Euler inverse dynamics in CasADi, built from a Pinocchio model.

The `pin` wheel has no `pinocchio.casadi`, so the planner gets the closed-form
baseline as a CasADi expression here: the same spatial-algebra RNEA Pinocchio
runs (local frames, motion vectors as [linear; angular]), with the joint
placements, axes and inertias read from the `pin.Model`. Rotor armature
(`model.armature * qdd`) and viscous damping (`model.damping * qd`) are added
so that the expression equals `PinocchioModel.torque` (checked in the tests
against `pin.rnea` to ~1e-12 N m).

Supported: trees of 1-DOF revolute joints (RX/RY/RZ and unaligned axes).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pinocchio as pin


def _joint_axes(model: pin.Model) -> list[np.ndarray]:
    """Unit rotation axis of each joint (index 1..njoints-1) in its own frame."""
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    axes = [np.zeros(3)]
    for j in range(1, model.njoints):
        if model.joints[j].nv != 1 or model.joints[j].nq != 1:
            raise ValueError(f"joint {model.names[j]}: only 1-DOF revolute joints are supported")
        S = np.asarray(data.joints[j].S).reshape(6)
        if np.linalg.norm(S[:3]) > 1e-12:
            raise ValueError(f"joint {model.names[j]} is prismatic; only revolute is supported")
        axes.append(S[3:] / np.linalg.norm(S[3:]))
    return axes


def _rotation(axis: np.ndarray, angle) -> ca.SX:
    """Rodrigues' rotation about a constant unit axis by a symbolic angle (rad)."""
    K = ca.DM(pin.skew(axis))
    return ca.DM.eye(3) + ca.sin(angle) * K + (1 - ca.cos(angle)) * (K @ K)


def _motion_cross(v, w, mv, mw):
    """Spatial motion cross product (v, w) x (mv, mw)."""
    return ca.cross(w, mv) + ca.cross(v, mw), ca.cross(w, mw)


def _inertia_times(inertia: pin.Inertia, v, w):
    """Spatial force (f, n) = I (v, w) of a rigid body about its frame origin."""
    c = ca.DM(inertia.lever)
    f = inertia.mass * (v - ca.cross(c, w))
    n = ca.DM(inertia.inertia) @ w + ca.cross(c, f)
    return f, n


def symbolic_rnea(model: pin.Model, q, qd, qdd):
    """Joint torques (nv x 1, N m) of `model` at CasADi column vectors q, qd, qdd.

    Equals pin.rnea(model, data, q, qd, qdd) + model.damping * qd.
    """
    axes = _joint_axes(model)
    parents = list(model.parents)
    n = model.njoints
    gravity = -np.asarray(model.gravity.linear)
    v = [ca.DM.zeros(3)] * n
    w = [ca.DM.zeros(3)] * n
    a = [ca.DM(gravity)] + [None] * (n - 1)  # base accelerates up: gravity as fictitious force
    al = [ca.DM.zeros(3)] * n
    rot, trans, force, moment = [None] * n, [None] * n, [None] * n, [None] * n
    for j in range(1, n):
        i = model.joints[j].idx_v
        placement = model.jointPlacements[j]
        R = ca.DM(placement.rotation) @ _rotation(axes[j], q[i])
        p = ca.DM(placement.translation)
        rot[j], trans[j] = R, p
        pj = parents[j]
        # Parent motion expressed in this joint's frame: X^-1 (v, w) = R^T (v - p x w, w).
        vj = R.T @ (v[pj] - ca.cross(p, w[pj]))
        wj = R.T @ w[pj] + ca.DM(axes[j]) * qd[i]
        aj = R.T @ (a[pj] - ca.cross(p, al[pj]))
        alj = R.T @ al[pj] + ca.DM(axes[j]) * qdd[i]
        cv, cw = _motion_cross(vj, wj, ca.DM.zeros(3), ca.DM(axes[j]) * qd[i])
        v[j], w[j], a[j], al[j] = vj, wj, aj + cv, alj + cw
        f, nm = _inertia_times(model.inertias[j], a[j], al[j])
        hf, hn = _inertia_times(model.inertias[j], v[j], w[j])
        # v x* h for the momentum h = I v
        force[j] = f + ca.cross(w[j], hf)
        moment[j] = nm + ca.cross(w[j], hn) + ca.cross(v[j], hf)
    tau = [None] * model.nv
    for j in range(n - 1, 0, -1):
        i = model.joints[j].idx_v
        tau[i] = ca.dot(ca.DM(axes[j]), moment[j])
        pj = parents[j]
        if pj > 0:
            fp = rot[j] @ force[j]
            force[pj] = force[pj] + fp
            moment[pj] = moment[pj] + rot[j] @ moment[j] + ca.cross(trans[j], fp)
    tau = ca.vertcat(*tau)
    armature = ca.DM(np.asarray(model.armature, dtype=float))
    damping = ca.DM(np.asarray(model.damping, dtype=float))
    return tau + armature * qdd + damping * qd
