"""The exported MJCF holds the model's friction and sensor offset in MuJoCo's own terms: read
by plain MuJoCo, its inverse dynamics (friction constraints included) less its motors' bias
is the torque the model says the sensor reads, on a motion away from rest."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
from scipy.special import expit

from harness.robots.arm import Arm
from harness.robots.export import export_model
from harness.robots.files import plain_mujoco

SLOPE, SHIFT = 30.0, 0.03  # s/rad, rad/s: the sigmoid's shape (one of identification's grid)
COULOMB, PHI1 = 0.08, 0.1  # N m: joint 1's Coulomb, joint 2's sigmoid
ARMATURE, VISCOUS = 1e-4, 0.02  # kg m^2, N m s/rad on every joint
OFFSET = np.array([0.01, -0.02, 0.03])  # N m, the sensor's
# N m: the sigmoid's departure from f sign(qd) + d qd + k beyond 0.5 rad/s, as a share of phi1
# (its tail e^(-30 * 0.53) is 1e-7; the fit over [-10, 10] rad/s leaves d and k of ~1e-3 phi1)
TOLERANCE = 0.01 * PHI1


def _model(arm: Arm) -> dict:
    """Bodies nominal, armature and viscous on every joint, Coulomb on joint 1 and a sigmoid
    in place of Coulomb on joint 2."""
    dof = arm.dof
    params = arm.nominal.atom_parameters().copy()
    params[10 * dof:11 * dof], params[11 * dof:12 * dof] = ARMATURE, VISCOUS
    params[12 * dof] = COULOMB
    sigmoid = {"law": "sigmoid", "shape": [SLOPE, SHIFT]}
    return {"body_parameters": params.tolist(), "dof": dof,
            "friction": [{"law": "viscous-coulomb", "shape": []}, sigmoid,
                         {"law": "viscous", "shape": []}],
            "joints": [{"terms": [], "coefficients": []},
                       {"terms": ["sigmoid2"], "coefficients": [PHI1]},
                       {"terms": [], "coefficients": []}]}


def _sensor(arm: Arm, q, qd, qdd) -> np.ndarray:
    """The model's torque written out: Pinocchio's RNEA on the nominal bodies, armature,
    viscous, Coulomb (sign: the speeds are away from zero), the sigmoid, the offset."""
    pinocchio = arm.pinocchio
    data = pinocchio.createData()
    body = np.array([pin.rnea(pinocchio, data, *x) for x in zip(q, qd, qdd, strict=True)])
    tau = body + ARMATURE * qdd + VISCOUS * qd
    tau[:, 0] += COULOMB * np.sign(qd[:, 0])
    tau[:, 1] += PHI1 * (expit(SLOPE * (qd[:, 1] + SHIFT)) - expit(SLOPE * SHIFT))
    return tau + OFFSET


def test_the_exported_mjcf_holds_coulomb_sigmoid_and_offset(tmp_path):
    arm = Arm.of("lynxmotion")
    assert not np.any(arm.pinocchio.armature)  # the body torque is RNEA's alone
    out = tmp_path / "model.xml"
    export_model(_model(arm), arm, "mjcf", out, offset=OFFSET)
    model = plain_mujoco(out)
    assert model.dof_frictionloss[0] > 0 and model.dof_frictionloss[1] > 0
    assert model.nu == 3  # the file's own motors hold the bias
    bias = np.zeros(3)
    np.add.at(bias, model.actuator_trnid[:, 0], model.actuator_gear[:, 0]
              * model.actuator_biasprm[:, 0])
    rng = np.random.default_rng(11)
    n = 40
    low, high = arm.position_limits
    q = rng.uniform(np.maximum(low, -2), np.minimum(high, 2), (n, 3))
    qd = rng.choice([-1, 1], (n, 3)) * rng.uniform(0.5, 1.5, (n, 3))
    qdd = rng.uniform(-2, 2, (n, 3))
    data = mujoco.MjData(model)
    ctrl = np.empty((n, 3))
    for i in range(n):
        data.qpos[:], data.qvel[:], data.qacc[:] = q[i], qd[i], qdd[i]
        mujoco.mj_inverse(model, data)
        ctrl[i] = data.qfrc_inverse - bias
    assert np.max(np.abs(ctrl - _sensor(arm, q, qd, qdd))) < TOLERANCE
    assert "approximated" in out.read_text()
