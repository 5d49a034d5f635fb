"""The next-run experiment (harness.experiments.next_run): its nominal model is the perturbed
URDF's RNEA (recomputed by Pinocchio on a model with those inertias), its rule outcome is
what its errors say, and the identified model beats the perturbed nominal by far."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from harness.experiments.next_run import RULE_RMS, law_torque, next_run, two_runs
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import load_pinocchio
from identification.metrics import rel_error


def test_next_run_scores_what_it_says():
    robot, seed = "ur5", 7
    out = next_run(robot, seed, samples=1500)
    errors = {k: np.array(v) for k, v in out["errors"].items()}
    # the nominal is the perturbed URDF's RNEA: Pinocchio on a model with those inertias
    runs = two_runs(robot, seed, samples=1500)
    model = load_pinocchio(robot)
    for j in range(1, model.njoints):
        model.inertias[j] = pin.Inertia.FromDynamicParameters(runs.nominal[10 * (j - 1):10 * j])
    s = runs.second
    wrong = PinocchioModel(model).torque(s.q, s.qd, s.qdd)
    np.testing.assert_allclose(errors["nominal"], rel_error(wrong, runs.truth_second), rtol=1e-8)
    rms = np.sqrt(np.mean(runs.truth_second**2, axis=0))
    np.testing.assert_allclose(out["torque_rms"], rms)
    assert out["rule_joints"] == np.flatnonzero(rms > RULE_RMS).tolist()
    holds = [j for j in out["rule_joints"] if errors["identified"][j] <= errors["nominal"][j]
             and errors["identified"][j] <= errors["least_squares"][j]]
    assert out["rule_holds_on"] == holds
    assert out["median_ratio_to_least_squares"] == np.median(errors["identified"]
                                                             / errors["least_squares"])
    assert np.all(errors["identified"] < 0.2 * errors["nominal"])


def test_friction_law_is_odd_around_its_shift_and_offset():
    law = {"viscous": np.array([0.1]), "coulomb": np.array([0.5]), "width": np.array([0.01]),
           "shift": np.array([0.0]), "stribeck": np.array([0.2]), "speed": np.array([0.1]),
           "offset": np.array([0.3])}
    qd = np.linspace(-1, 1, 11)[:, None]
    tau = law_torque(law, qd) - 0.3
    np.testing.assert_allclose(tau, -tau[::-1], atol=1e-12)
    assert law_torque(law, np.array([[1.0]]))[0, 0] > 0.3 + 0.5 + 0.1 - 1e-3
