"""Effect dictionary, payload torque, extended model and selection on synthetic residuals."""

from __future__ import annotations

import casadi as ca
import mujoco
import numpy as np
import pinocchio as pin
import pytest

from harness.closeloop.plants import Variant, variant_text
from harness.data.generate import inverse_torques
from harness.robots.arm import Arm
from harness.robots.baseline import PinocchioModel
from harness.robots.bodies import PayloadTorque
from identification.closeloop.candidates.effects import EffectTerm, build_dictionary, effect_torque
from identification.closeloop.closed.extended import ExtendedModel
from identification.closeloop.selection.bic import select_effects
from identification.closeloop.selection.residual import ljung_box, noise_sigma
from identification.closeloop.selection.screening import screen


def _states(n=600, seed=0):
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 6, n)[:, None]
    w = rng.uniform(0.5, 2.0, (3, 3))
    q = sum(np.sin(w[k] * t + k) for k in range(3)) * 0.5 + np.array([0, 1.5, -1.5])
    qd = sum(w[k] * np.cos(w[k] * t + k) for k in range(3)) * 0.5
    qdd = sum(-w[k] ** 2 * np.sin(w[k] * t + k) for k in range(3)) * 0.5
    return q, qd, qdd


@pytest.fixture(scope="module")
def pmodel():
    return Arm.of("lynxmotion").pinocchio


def test_payload_torque_matches_mujoco_payload_body(pmodel):
    """Unit payload x mass = MuJoCo's inverse-dynamics difference of a plant with that body."""
    q, qd, qdd = _states(50)
    plain = mujoco.MjModel.from_xml_string(variant_text(Variant()))
    loaded = mujoco.MjModel.from_xml_string(variant_text(Variant(payload=0.07)))
    expected = inverse_torques(loaded, q, qd, qdd) - inverse_torques(plain, q, qd, qdd)
    got = 0.07 * PayloadTorque(pmodel)(q, qd, qdd)
    np.testing.assert_allclose(got, expected, atol=1e-7)


def test_payload_torque_is_rnea_difference(pmodel):
    """Pinocchio cross-check: link3 inertia plus a point mass at the end effector."""
    q, qd, qdd = _states(20)
    heavy = pmodel.copy()
    heavy.inertias[3] = heavy.inertias[3] + pin.Inertia(0.2, np.array([0.187, 0, 0]), np.zeros((3, 3)))
    diff = PinocchioModel(heavy).torque(q, qd, qdd) - PinocchioModel(pmodel).torque(q, qd, qdd)
    np.testing.assert_allclose(0.2 * PayloadTorque(pmodel)(q, qd, qdd), diff, atol=1e-12)


def test_joint_effects_match_mujoco_passive_forces():
    """mj_inverse of a plant with damping, armature and stiffness = declared + effect torques."""
    q, qd, qdd = _states(50)
    v = Variant((("viscous", 1, 0.03), ("armature", 2, 0.004), ("spring", 3, 0.2)))
    plant = mujoco.MjModel.from_xml_string(variant_text(v))
    base = mujoco.MjModel.from_xml_string(variant_text(Variant()))
    terms = (EffectTerm("viscous", 1, 0.03), EffectTerm("armature", 2, 0.004),
             EffectTerm("spring", 3, 0.2))
    expected = inverse_torques(plant, q, qd, qdd) - inverse_torques(base, q, qd, qdd)
    np.testing.assert_allclose(effect_torque(terms, q, qd, qdd), expected, atol=1e-10)


@pytest.mark.parametrize("fallback", [(), (2,)])
def test_extended_model_symbolic_equals_numeric(pmodel, fallback):
    payload = PayloadTorque(pmodel)
    terms = (EffectTerm("viscous", 1, 0.02), EffectTerm("coulomb", 2, 0.05, 0.01, 0.02),
             EffectTerm("armature", 3, 0.003), EffectTerm("offset", 1, -0.1),
             EffectTerm("spring", 2, 0.3), EffectTerm("payload", 3, 0.08))
    declared = PinocchioModel(pmodel)
    model = ExtendedModel(declared, terms, payload, payload.symbolic, fallback)
    q, qd, qdd = _states(5)
    if fallback:  # the fallback joint is the declared model's, the others carry the effects
        np.testing.assert_allclose(model.torque(q, qd, qdd)[:, 1], declared.torque(q, qd, qdd)[:, 1])
        assert not np.allclose(model.torque(q, qd, qdd)[:, 0], declared.torque(q, qd, qdd)[:, 0])
    x = [ca.SX.sym(n, 3) for n in ("q", "qd", "qdd")]
    f = ca.Function("tau", x, [model.symbolic_torque(*x)])
    for k in range(5):
        np.testing.assert_allclose(np.asarray(f(q[k], qd[k], qdd[k])).ravel(),
                                   model.torque(q[k:k + 1], qd[k:k + 1], qdd[k:k + 1])[0], atol=1e-10)


@pytest.mark.parametrize("effect,joint,value", [
    ("viscous", 1, 0.02), ("coulomb", 2, 0.05), ("armature", 3, 0.01), ("offset", 2, 0.04),
    ("spring", 3, 0.1), ("payload", 3, 0.05)])
def test_selection_names_the_planted_effect(pmodel, effect, joint, value):
    """Synthetic residual = one effect + 2 % white noise: that effect, within 2 %."""
    q, qd, qdd = _states(1500)
    payload = PayloadTorque(pmodel)
    dictionary = build_dictionary(q, qd, qdd, payload)
    tau = effect_torque((EffectTerm(effect, joint, value),), q, qd, qdd, payload)
    sigma = 0.02 * np.maximum(tau.std(axis=0), 1e-3) + 1e-4
    residual = tau + np.random.default_rng(1).normal(size=tau.shape) * sigma
    sel = select_effects(residual, dictionary, noise_sigma(residual))
    assert [(t.effect, t.joint) for t in sel.terms] == [(effect, joint)]
    assert sel.terms[0].coefficient == pytest.approx(value, rel=0.02)


def test_selection_names_nothing_in_white_noise(pmodel):
    q, qd, qdd = _states(1500)
    residual = np.random.default_rng(2).normal(size=q.shape) * 0.01
    sel = select_effects(residual, build_dictionary(q, qd, qdd, PayloadTorque(pmodel)),
                         noise_sigma(residual))
    assert sel.terms == ()


def test_ljung_box_and_noise_level():
    rng = np.random.default_rng(3)
    white = rng.normal(size=3000)
    ar = np.zeros(3000)
    for k in range(1, 3000):
        ar[k] = 0.5 * ar[k - 1] + white[k]
    assert ljung_box(white)[1] > 1e-3
    assert ljung_box(ar)[1] < 1e-6
    smooth = np.sin(np.linspace(0, 20, 3000))[:, None]
    assert noise_sigma(smooth + 0.05 * white[:, None])[0] == pytest.approx(0.05, rel=0.05)


@pytest.mark.parametrize("joint,friction", [(1, 0.05), (2, 0.05), (3, 0.05), (3, 0.01)])
def test_coulomb_column_is_mujoco_frictionloss(joint, friction):
    """mj_inverse of a frictionloss plant = declared + f clip((qd + qdd/b) / (R f / b)), with
    b = 2 / (dmax timeconst) and R = (1 - dmin) / dmin * dof_invweight0 (effects.py)."""
    q, qd, qdd = _states(400)
    qd = qd * 0.2  # slow enough to spend time in the linear zone
    plant = mujoco.MjModel.from_xml_string(variant_text(Variant((("coulomb", joint, friction),))))
    base = mujoco.MjModel.from_xml_string(variant_text(Variant()))
    expected = inverse_torques(plant, q, qd, qdd) - inverse_torques(base, q, qd, qdd)
    dmin, dmax = plant.dof_solimp[joint - 1, :2]
    b = 2.0 / (dmax * plant.dof_solref[joint - 1, 0])
    eps = (1 - dmin) / dmin * plant.dof_invweight0[joint - 1] * friction / b
    got = effect_torque((EffectTerm("coulomb", joint, friction, 1.0 / b, eps),), q, qd, qdd)
    linear = np.abs(qd[:, joint - 1] + qdd[:, joint - 1] / b) < eps
    assert 0 < linear.mean() < 1  # both regimes are exercised
    np.testing.assert_allclose(got, expected, atol=1e-10)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_screening_names_the_robust_effect_and_rejects_stand_ins(seed):
    """A viscous effect on joint 1 beside structure no candidate spans on joint 2 (a
    q3 sin q1 torque): the viscous term is named at its value; the spring and offset that
    stand in for the structure, and a spurious armature, are rejected with a reason."""
    q, qd, qdd = _states(2000, seed)
    rng = np.random.default_rng(seed)
    sigma = np.full(3, 0.002)
    residual = rng.normal(0.0, 1.0, q.shape) * sigma
    residual[:, 0] += 0.02 * qd[:, 0]
    residual[:, 1] += 0.3 * q[:, 2] * np.sin(q[:, 0])
    terms = (EffectTerm("viscous", 1, 0.02), EffectTerm("spring", 2, 0.1),
             EffectTerm("offset", 2, 0.1), EffectTerm("armature", 3, 0.01))
    result = screen(residual, [], terms, sigma, q, qd, qdd)
    assert [(t.effect, t.joint) for t in result.named] == [("viscous", 1)]
    assert result.named[0].coefficient == pytest.approx(0.02, rel=0.05)
    assert {(c.term.effect, c.term.joint) for c in result.candidates} == {
        ("spring", 2), ("offset", 2), ("armature", 3)}
    assert all(c.reason for c in result.candidates)
    assert result.fallback == ()
    assert np.all(result.validation_after <= result.validation_before)
