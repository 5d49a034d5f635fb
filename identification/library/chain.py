"""A kinematic chain of revolute joints and its inverse dynamics in CasADi.

The chain holds what a robot's kinematics give and nothing of its inertia: for
each joint its parent, its placement in the parent's frame and its axis, and
gravity. `rnea` is the recursive Newton-Euler algorithm on it (local frames,
motion vectors as [linear; angular], the spatial algebra Pinocchio runs) for any
inertial parameters, numeric or symbolic, per body in the standard order

    pi_j = (m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz),

the rotational inertia taken about the joint frame's origin (Pinocchio's
`Inertia.toDynamicParameters`). The torque is linear in them, so the joint-torque
regressor Y(q, qd, qdd) is the exact Jacobian of `rnea` with respect to pi
(identification.library.kinematic), and with a robot's numeric pi it is the
closed-form model the planner differentiates (harness.robots.casadi_rnea).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import casadi as ca
import numpy as np

PARAMETERS = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
UNITS = {"m": "kg", "mcx": "kg m", "mcy": "kg m", "mcz": "kg m", "Ixx": "kg m^2",
         "Ixy": "kg m^2", "Iyy": "kg m^2", "Ixz": "kg m^2", "Iyz": "kg m^2", "Izz": "kg m^2"}


class ChainError(ValueError):
    """A model that is not a tree of 1-DOF revolute joints on a fixed base."""


@dataclass(frozen=True)
class KinematicChain:
    """Joints j = 0..dof-1 of a fixed-base tree of revolute joints (kinematics only).

    parents[j]: index of the parent joint, -1 for the base; rotations[j] (3, 3) and
    translations[j] (3,) m: the joint frame's placement in the parent joint's frame at
    q = 0; axes[j] (3,): unit rotation axis in the joint's own frame; gravity (3,) m/s^2.
    """

    name: str
    parents: tuple[int, ...]
    rotations: np.ndarray
    translations: np.ndarray
    axes: np.ndarray
    gravity: np.ndarray

    @property
    def dof(self) -> int:
        return len(self.parents)

    @classmethod
    def from_pinocchio(cls, model, name: str = "") -> KinematicChain:
        """The chain of a pinocchio.Model, read from its joint placements and motion
        subspaces only (never its inertias). ChainError for anything but 1-DOF revolute
        joints on a fixed base."""
        import pinocchio as pin

        if model.njoints < 2:
            raise ChainError(f"model {name or model.name} has no moving joint")
        data = model.createData()
        pin.forwardKinematics(model, data, pin.neutral(model))
        axes = []
        for j in range(1, model.njoints):
            joint = model.joints[j]
            if joint.nq != 1 or joint.nv != 1:
                kind = "floating base" if joint.nv == 6 else f"{joint.shortname()} joint"
                raise ChainError(f"joint '{model.names[j]}' is a {kind}: only a fixed base with "
                                 "1-DOF revolute joints is supported")
            s = np.asarray(data.joints[j].S).reshape(6)
            if np.linalg.norm(s[:3]) > 1e-12 or np.linalg.norm(s[3:]) < 1e-12:
                raise ChainError(f"joint '{model.names[j]}' is prismatic: only revolute arm joints "
                                 "are supported (hold it fixed)")
            axes.append(s[3:] / np.linalg.norm(s[3:]))
        placements = [model.jointPlacements[j] for j in range(1, model.njoints)]
        return cls(name or model.name, tuple(int(p) - 1 for p in list(model.parents)[1:]),
                   np.array([p.rotation for p in placements]),
                   np.array([p.translation for p in placements]), np.array(axes),
                   np.asarray(model.gravity.linear, dtype=float).copy())

    def digest(self) -> str:
        """A hash of the kinematics (placements, axes, gravity; rounded to 1e-9)."""
        h = hashlib.sha256(repr(self.parents).encode())
        for x in (self.rotations, self.translations, self.axes, self.gravity):
            h.update(np.round(np.asarray(x, dtype=float), 9).tobytes())
        return h.hexdigest()[:16]


def _rotation(axis: np.ndarray, angle) -> ca.SX:
    """Rodrigues' rotation about a constant unit axis by a symbolic angle (rad)."""
    k = ca.DM([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return ca.DM.eye(3) + ca.sin(angle) * k + (1 - ca.cos(angle)) * (k @ k)


def _inertia_times(p, v, w):
    """Spatial force (f, n) = I (v, w) of a body with standard parameters p (10,) about its
    frame origin: f = m v - h x w, n = I_O w + h x v, h = m c."""
    m, h = p[0], ca.vertcat(p[1], p[2], p[3])
    inertia = ca.vertcat(ca.horzcat(p[4], p[5], p[7]), ca.horzcat(p[5], p[6], p[8]),
                         ca.horzcat(p[7], p[8], p[9]))
    return m * v - ca.cross(h, w), inertia @ w + ca.cross(h, v)


def rnea(chain: KinematicChain, q, qd, qdd, params):
    """Rigid-body joint torques (dof x 1, N m) at CasADi column vectors q, qd, qdd.

    params: (10 * dof) standard inertial parameters, numeric or symbolic (PARAMETERS order,
    joint by joint)."""
    n = chain.dof
    v, w, a, al = [None] * n, [None] * n, [None] * n, [None] * n
    force, moment, rot = [None] * n, [None] * n, [None] * n
    zero = ca.DM.zeros(3)
    for j in range(n):
        axis = ca.DM(chain.axes[j])
        rot[j] = ca.DM(chain.rotations[j]) @ _rotation(chain.axes[j], q[j])
        p, parent = ca.DM(chain.translations[j]), chain.parents[j]
        pv, pw, pa, pal = ((zero, zero, ca.DM(-chain.gravity), zero) if parent < 0 else
                           (v[parent], w[parent], a[parent], al[parent]))
        # the parent's motion in this joint's frame: X^-1 (v, w) = R^T (v - p x w, w);
        # the base accelerates up against gravity (a fictitious force)
        vj = rot[j].T @ (pv - ca.cross(p, pw))
        wj = rot[j].T @ pw + axis * qd[j]
        aj = rot[j].T @ (pa - ca.cross(p, pal))
        alj = rot[j].T @ pal + axis * qdd[j]
        # (v, w) x (0, axis qd): the velocity-product acceleration
        v[j], w[j] = vj, wj
        a[j], al[j] = aj + ca.cross(vj, axis * qd[j]), alj + ca.cross(wj, axis * qd[j])
        pj = params[10 * j:10 * j + 10]
        f, nm = _inertia_times(pj, a[j], al[j])
        hf, hn = _inertia_times(pj, v[j], w[j])
        force[j] = f + ca.cross(w[j], hf)
        moment[j] = nm + ca.cross(w[j], hn) + ca.cross(v[j], hf)
    tau = [None] * n
    for j in range(n - 1, -1, -1):
        tau[j] = ca.dot(ca.DM(chain.axes[j]), moment[j])
        parent = chain.parents[j]
        if parent >= 0:
            fp = rot[j] @ force[j]
            force[parent] = force[parent] + fp
            moment[parent] = (moment[parent] + rot[j] @ moment[j]
                              + ca.cross(ca.DM(chain.translations[j]), fp))
    return ca.vertcat(*tau)
