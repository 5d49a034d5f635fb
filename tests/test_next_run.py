"""The next-run experiment (harness.identify.next_run): its nominal model is the perturbed
URDF's RNEA (recomputed by Pinocchio on a model with those inertias), its rule outcome is
what its errors say, and the identified model beats the perturbed nominal by far."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from harness.identify.next_run import RULE_RMS, law_torque, next_run, rule_targets, two_runs
from harness.identify.peers import joint_friction_columns
from harness.robots.arm import Arm
from harness.robots.baseline import PinocchioModel
from identification.metrics import rel_error


def test_next_run_scores_what_it_says():
    arm, seed = Arm.of("ur5"), 7
    out = next_run(arm, seed, samples=1500)
    errors = {k: np.array(v) for k, v in out["errors"].items()}
    # the nominal is the perturbed URDF's RNEA: Pinocchio on a model with those inertias
    runs = two_runs(arm, seed, samples=1500)
    model = arm.pinocchio.copy()
    for j in range(1, model.njoints):
        model.inertias[j] = pin.Inertia.FromDynamicParameters(runs.nominal[10 * (j - 1):10 * j])
    s = runs.second
    wrong = PinocchioModel(model).torque(s.q, s.qd, s.qdd)
    np.testing.assert_allclose(errors["nominal"], rel_error(wrong, runs.truth_second), rtol=1e-8)
    # the least-squares peer recomputed independently: Pinocchio's joint-torque regressor
    # (not the library's atoms) plus the friction columns, on both runs, scored here
    first, n = runs.first, len(runs.first.q)
    states = [np.r_[a, b] for a, b in ((first.q, s.q), (first.qd, s.qd), (first.qdd, s.qdd))]
    X = np.concatenate([arm.nominal.regressor(*states),
                        joint_friction_columns(states[1])], axis=2)
    tau = np.r_[runs.tau_first, runs.tau_second]
    coef, *_ = np.linalg.lstsq(X[:n].reshape(-1, X.shape[2]), tau[:n].ravel(), rcond=None)
    truth = runs.truth_second
    ls = np.sqrt((((X @ coef)[n:] - truth) ** 2).sum(axis=0) / (truth ** 2).sum(axis=0))
    np.testing.assert_allclose(errors["least_squares"], ls, rtol=1e-6)
    # every joint judged carries load, and the rule judges at least one joint (never vacuous)
    rms = np.sqrt((truth ** 2).sum(axis=0) / len(truth))
    # *_from_1 numbers joints from 1, as the report's tables; the older fields from 0
    assert out["rule_joints"] == [j - 1 for j in out["rule_joints_from_1"]]
    assert out["rule_holds_on"] == [j - 1 for j in out["rule_holds_on_from_1"]]
    assert out["rule_joints"] and all(rms[j - 1] > min(RULE_RMS, 0.25 * rms.max())
                                      for j in out["rule_joints_from_1"])
    for j in out["rule_holds_on_from_1"]:
        assert errors["identified"][j - 1] <= min(errors["nominal"][j - 1], ls[j - 1] * (1 + 1e-6))
    assert out["median_ratio_to_least_squares"] == pytest.approx(
        np.median(errors["identified"] / ls), rel=1e-6)
    assert np.all(errors["identified"] < 0.2 * errors["nominal"])


def test_friction_law_is_odd_around_its_shift_and_offset():
    law = {"viscous": np.array([0.1]), "coulomb": np.array([0.5]), "width": np.array([0.01]),
           "shift": np.array([0.0]), "stribeck": np.array([0.2]), "speed": np.array([0.1]),
           "offset": np.array([0.3])}
    qd = np.linspace(-1, 1, 11)[:, None]
    tau = law_torque(law, qd) - 0.3
    np.testing.assert_allclose(tau, -tau[::-1], atol=1e-12)
    assert law_torque(law, np.array([[1.0]]))[0, 0] > 0.3 + 0.5 + 0.1 - 1e-3


def test_the_rule_judges_a_small_arm_too():
    """On the Lynxmotion, whose joints all stay below RULE_RMS, the rule still judges the
    joints that carry its load, so its target can be missed (it read '>= 0 joints')."""
    out = next_run(Arm.of("lynxmotion"), 3, samples=1500)
    assert max(out["torque_rms"]) < RULE_RMS and out["rule_joints"]
    target = rule_targets([out])[0]
    assert target.target == len(out["rule_joints"]) >= 1 and target.measured is not None
