"""The study identification_draws and what it reads of a selection
(harness.identify.selection): seeds apart, the noise-free terms and the selection's ceiling."""

from __future__ import annotations

import numpy as np

from harness.identify.fits import arm_identification
from harness.identify.outside_default import datasets, judges
from harness.identify.scoring import HOLDOUT, fixed_fit, score_draw
from harness.identify.selection import ceiling_errors, selection
from harness.robots.arm import Arm
from harness.studies.identification_draws import (
    DECISION_JUDGE,
    DECISION_SEEDS,
    DEV_JUDGE,
    DEV_SEEDS,
    FIRST_FRESH_JUDGE,
    FIRST_FRESH_SEEDS,
    FRESH_JUDGE,
    FRESH_SEEDS,
)
from identification.regression.coupled import AtomBasis


def test_fresh_seeds_are_apart_from_development_and_every_scored_seed():
    from harness.bench.identification import FRESH_SEED, LEVELS, NEXT_RUNS
    from harness.identify import outside_default
    from harness.identify.excitation import FRESH_DRAWS
    from harness.identify.excitation import FRESH_JUDGE as EXCITE_JUDGE

    used = (set(DEV_SEEDS) | {DEV_JUDGE, FRESH_SEED, EXCITE_JUDGE} | set(NEXT_RUNS)
            | set(FRESH_DRAWS) | {s for seeds in LEVELS.values() for s in seeds}
            | set(outside_default.DEV_SEEDS) | set(outside_default.FRESH_SEEDS)
            | {outside_default.DEV_JUDGE, outside_default.FRESH_JUDGE})
    # the sets a default was decided on (the first fresh set, the decision's) score nothing
    decided = set(FIRST_FRESH_SEEDS) | set(DECISION_SEEDS) | {FIRST_FRESH_JUDGE, DECISION_JUDGE}
    assert len(set(FRESH_SEEDS)) == len(FRESH_SEEDS) >= 10
    assert len(set(DECISION_SEEDS)) == len(DECISION_SEEDS) >= 10
    assert not (set(FRESH_SEEDS) | {FRESH_JUDGE}) & (used | decided)
    assert not (set(DECISION_SEEDS) | {DECISION_JUDGE}) & (used | set(FIRST_FRESH_SEEDS))


def test_the_selection_record_of_a_free_coupled_fit_on_a_lynxmotion_draw():
    """The prior library's coupled fit, left free: on its noise-free draw it keeps the
    atoms whose torque a rigid body gives (least squares on them is exact on a fresh motion);
    at 5 % it keeps the same atoms, and its judge errors are the ceiling's (weighted least
    squares on those atoms, computed apart)."""
    arm = Arm.of("lynxmotion")
    fit = fixed_fit(*arm_identification(arm, rigid_body=False))
    motions = judges(arm, DEV_JUDGE, 2000)
    data = datasets(arm, DEV_SEEDS[:1], 2000, ("fourier",), (0.05,))[0]
    d = score_draw(data, {"free": fit}, arm.nominal, motions)
    record = selection(fit, data, HOLDOUT, d["free"]["kept"], motions)
    assert record["dropped"] == [] and record["spurious"] == []
    assert 0 < len(record["needed"]) < len(fit.library.atoms)
    for judge, errors in record["ceiling"].items():
        np.testing.assert_allclose(d["free"][judge], errors, rtol=0.02)
    clean = type(data)(data.t, data.q, data.qd, data.qdd, data.tau_clean, data.tau_clean,
                       data.meta)
    atoms = AtomBasis.from_atoms(fit.library.atoms, 3, fit.library.name)
    exact = ceiling_errors(atoms, clean, 1500, record["needed"], motions)
    assert max(max(e) for e in exact.values()) <= 1e-8


def test_the_study_s_prior_fit_is_identify_s_with_a_urdf_perturbed_per_draw():
    """`--prior nominal (perturbed URDF)`: identify's consistent fit (its bounds, metric and
    weights) whose prior is, on each draw, not the URDF that made the data: every body's mass
    off by at most 30 % (read from Pinocchio's model), and another prior on another draw."""
    from harness.studies.identification_draws import ARMS, PERTURBED, named_fit

    arm = Arm.of("ur5")
    options = dict(ARMS["ur5"][0])["--prior nominal (perturbed URDF)"]
    assert options[PERTURBED]
    fit = named_fit(arm, options)
    _, identify_s = arm_identification(arm, prior="nominal")
    first, second = fit.regressor(DEV_SEEDS[0]), fit.regressor(DEV_SEEDS[1])
    for setting in ("ellipsoids", "prior_metric", "lambdas", "choose_friction"):
        assert getattr(first, setting) == getattr(identify_s, setting)
    truth = np.array([arm.pinocchio.inertias[j].mass for j in range(1, arm.pinocchio.njoints)])
    for prior in (first.nominal, second.nominal):
        masses = prior[0:10 * arm.dof:10]
        assert np.all(np.abs(masses / truth - 1) <= 0.3) and np.any(np.abs(masses / truth - 1) > 0.01)
    assert not np.allclose(first.nominal, second.nominal)


def test_the_largest_error_ratio_is_a_worst_case_against_a_worst_case():
    """summarize's largest_error_ratio_per_joint: the fit's largest error over draws and judges
    over the oracle's largest, per joint (computed here apart); never above the worst per-draw
    ratio (max f / max o <= f_k / o_k at the fit's largest), and below it where the oracle
    had a lucky draw."""
    from harness.identify.outside_default import JUDGES, summarize

    rng = np.random.default_rng(3)
    draws = [{"noise": 0.05, "fit": {j: rng.uniform(0.5, 2.0, 3).tolist() for j in JUDGES},
              "oracle": {j: rng.uniform(0.5, 2.0, 3).tolist() for j in JUDGES}} for _ in range(6)]
    draws[0]["oracle"][JUDGES[0]][2] = 0.01  # a lucky oracle on joint 3
    s = summarize(draws, "fit", "oracle", lambda d: "all")["all"]
    fit = np.array([[d["fit"][j] for j in JUDGES] for d in draws])
    oracle = np.array([[d["oracle"][j] for j in JUDGES] for d in draws])
    expected = fit.max(axis=(0, 1)) / oracle.max(axis=(0, 1))
    np.testing.assert_allclose(s["largest_error_ratio_per_joint"], expected, rtol=1e-12)
    assert np.all(np.array(s["largest_error_ratio_per_joint"]) <= np.array(s["worst_per_joint"]))
    assert s["worst_per_joint"][2] > 20 > 2 > s["largest_error_ratio_per_joint"][2]


def test_the_twin_is_the_oracle_on_the_same_law_of_noise_drawn_again():
    """The reference row: the same motion and clean torque, the noise of the draw's law (each
    joint's std within 10 % of the draw's) but not the draw's (correlation below 0.1); with no
    noise the twin's oracle is the oracle (judge errors equal)."""
    from harness.studies.identification_draws import twin, twin_errors

    arm = Arm.of("lynxmotion")
    data = datasets(arm, DEV_SEEDS[:1], 2000, ("fourier",), (0.05,))[0]
    other = twin(data)
    np.testing.assert_array_equal(other.q, data.q)
    np.testing.assert_array_equal(other.tau_clean, data.tau_clean)
    drawn, again = data.tau - data.tau_clean, other.tau - other.tau_clean
    for j in range(arm.dof):
        assert 0.9 <= np.std(again[:, j]) / np.std(drawn[:, j]) <= 1.1
        assert abs(np.corrcoef(drawn[:, j], again[:, j])[0, 1]) < 0.1
    motions = judges(arm, DEV_JUDGE, 2000)
    clean = datasets(arm, DEV_SEEDS[:1], 2000, ("fourier",), (0.0,))[0]
    oracle = score_draw(clean, {}, arm.nominal, motions)["oracle"]
    for judge, errors in twin_errors(arm, clean, motions).items():
        np.testing.assert_allclose(errors, oracle[judge], rtol=1e-6, atol=1e-12)
