"""The closed-form baseline: Pinocchio's RNEA on the robot's URDF.

Implements the TorqueModel interface (identification.torque_model). Pinocchio's
`rnea` includes rotor armature but not joint damping, so the URDF's viscous
damping (`model.damping`) is added explicitly; MuJoCo's `mj_inverse` includes
both, which is what the agreement tests compare against.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from identification.torque_model import as_states


class PinocchioModel:
    """Closed-form inverse dynamics tau = M(q) qdd + C(q, qd) qd + g(q) + D qd."""

    def __init__(self, model: pin.Model):
        if model.nq != model.nv:
            raise ValueError("only robots with nq == nv (revolute/prismatic joints) are supported")
        self.model = model
        self.data = model.createData()
        self.dof = model.nv

    def torque(self, q, qd, qdd) -> np.ndarray:
        """Torques (n, dof) in N m at states of shape (n, dof)."""
        q, qd, qdd = as_states(q, qd, qdd, self.dof)
        tau = np.empty_like(q)
        for k in range(len(q)):
            tau[k] = pin.rnea(self.model, self.data, q[k], qd[k], qdd[k])
        return tau + qd * np.asarray(self.model.damping)

    def regressor(self, q, qd, qdd) -> np.ndarray:
        """Stacked joint-torque regressor (n, dof, 10 * nbodies) of the rigid-body part.

        tau_rigid[k] = Y[k] @ pi, pi the standard inertial parameters
        (m, m c, I) of each body. Armature and damping are not in it.
        """
        q, qd, qdd = as_states(q, qd, qdd, self.dof)
        rows = [
            pin.computeJointTorqueRegressor(self.model, self.data, q[k], qd[k], qdd[k]).copy()
            for k in range(len(q))
        ]
        return np.stack(rows)

    def inertial_parameters(self) -> np.ndarray:
        """The standard parameter vector pi matching `regressor` (10 per moving body)."""
        return np.concatenate([self.model.inertias[j].toDynamicParameters()
                               for j in range(1, self.model.njoints)])

    def atom_parameters(self) -> np.ndarray:
        """The URDF's coefficients of every candidate atom (identification.library.kinematic.
        atom_names): the standard parameters, then armature, viscous damping and Coulomb
        friction per joint - the nominal model a fit is pulled toward."""
        m = self.model
        return np.concatenate([self.inertial_parameters(), np.asarray(m.armature, float),
                               np.asarray(m.damping, float), np.asarray(m.friction, float)])

    def symbolic_torque(self, q, qd, qdd):
        """CasADi form of `torque`, verified against RNEA in the tests."""
        from harness.robots.casadi_rnea import symbolic_rnea

        return symbolic_rnea(self.model, q, qd, qdd)
