"""The CasADi RNEA equals Pinocchio's RNEA (plus damping) and has its derivatives."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from harness.robots.arm import Arm
from harness.robots.baseline import PinocchioModel
from harness.robots.casadi_rnea import symbolic_rnea


def _function(model: pin.Model) -> ca.Function:
    q, qd, qdd = (ca.SX.sym(name, model.nv) for name in ("q", "qd", "qdd"))
    return ca.Function("rnea", [q, qd, qdd], [symbolic_rnea(model, q, qd, qdd)])


@pytest.mark.parametrize("robot", ["lynxmotion", "double_pendulum", "ur5"])
def test_matches_pinocchio_rnea(robot):
    model = Arm.of(robot).pinocchio
    baseline = PinocchioModel(model)
    rnea = _function(model)
    rng = np.random.default_rng(0)
    q, qd, qdd = (rng.uniform(-3, 3, (20, model.nv)) for _ in range(3))
    expected = baseline.torque(q, qd, qdd)
    got = np.stack([np.asarray(rnea(q[k], qd[k], qdd[k])).ravel() for k in range(20)])
    assert np.max(np.abs(got - expected)) < 1e-12 * max(1.0, np.max(np.abs(expected)))


def test_armature_and_damping_are_included():
    model = Arm.of("lynxmotion").pinocchio.copy()  # changed here: the Arm's is shared
    model.armature = np.array([0.01, 0.02, 0.03])
    model.damping = np.array([0.1, 0.2, 0.3])
    rnea = _function(model)
    rng = np.random.default_rng(1)
    q, qd, qdd = (rng.uniform(-2, 2, 3) for _ in range(3))
    expected = PinocchioModel(model).torque(q, qd, qdd)[0]
    assert np.allclose(np.asarray(rnea(q, qd, qdd)).ravel(), expected, atol=1e-12)


@pytest.mark.parametrize("robot", ["lynxmotion", "ur5"])
def test_derivatives_match_compute_rnea_derivatives(robot):
    model = Arm.of(robot).pinocchio
    data = model.createData()
    q, qd, qdd = (ca.SX.sym(name, model.nv) for name in ("q", "qd", "qdd"))
    tau = symbolic_rnea(model, q, qd, qdd)
    jac = ca.Function("rnea_jacobians", [q, qd, qdd], [ca.jacobian(tau, q), ca.jacobian(tau, qd),
                                            ca.jacobian(tau, qdd)])
    rng = np.random.default_rng(2)
    x = [rng.uniform(-2, 2, model.nv) for _ in range(3)]
    dq, dv, da = pin.computeRNEADerivatives(model, data, *x)
    got = [np.asarray(j) for j in jac(*x)]
    assert np.allclose(got[0], dq, atol=1e-10)
    assert np.allclose(got[1], dv + np.diag(model.damping), atol=1e-10)
    assert np.allclose(got[2], np.triu(da) + np.triu(da, 1).T, atol=1e-10)
