"""The closed-form baseline as a CasADi expression, for the planner.

The `pin` wheel has no `pinocchio.casadi`, so the Newton-Euler recursion runs on
the model's kinematic chain (identification.library.chain.rnea) with the model's
numeric inertial parameters; rotor armature (`model.armature * qdd`) and viscous
damping (`model.damping * qd`) are added so that the expression equals
`PinocchioModel.torque` (checked in the tests against `pin.rnea` to ~1e-12 N m).

Supported: trees of 1-DOF revolute joints (RX/RY/RZ and unaligned axes).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pinocchio as pin

from identification.library.chain import KinematicChain, rnea


def symbolic_rnea(model: pin.Model, q, qd, qdd):
    """Joint torques (nv x 1, N m) of `model` at CasADi column vectors q, qd, qdd.

    Equals pin.rnea(model, data, q, qd, qdd) + model.damping * qd.
    """
    chain = KinematicChain.from_pinocchio(model)
    params = np.concatenate([model.inertias[j].toDynamicParameters()
                             for j in range(1, model.njoints)])
    armature = ca.DM(np.asarray(model.armature, dtype=float))
    damping = ca.DM(np.asarray(model.damping, dtype=float))
    return rnea(chain, q, qd, qdd, ca.DM(params)) + armature * qdd + damping * qd
