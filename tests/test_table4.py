"""Table IV systems: printed equations, Lagrangian consistency, recovery at 5 % noise, and
pysindy as an independent peer on the same libraries."""

from __future__ import annotations

import numpy as np
import pytest

from harness.paper.identification.table4 import (
    CONSISTENT_DOUBLE_PENDULUM,
    SYSTEMS,
    fit_system,
    lagrangian_residual,
)
from identification.identify import identify
from identification.library.features import parse_feature

BY_NAME = {s.name: s for s in (*SYSTEMS, CONSISTENT_DOUBLE_PENDULUM)}


@pytest.mark.parametrize("name", list(BY_NAME))
def test_library_spans_the_true_equations(name):
    s = BY_NAME[name]
    lib = s.library()
    for eq in s.true:
        assert {parse_feature(t, s.dof).name for t in eq} <= set(lib.names)


def test_printed_double_pendulum_is_not_lagrangian_but_the_corrected_one_is():
    printed, consistent = BY_NAME["double pendulum"], CONSISTENT_DOUBLE_PENDULUM
    m = printed.motion()
    assert min(lagrangian_residual(printed, m)) > 0.1
    assert max(lagrangian_residual(consistent, m)) < 1e-12
    assert printed.true[1] == consistent.true[1]  # eq. 2 as printed is physical


def test_consistent_double_pendulum_is_point_masses():
    """m1 = 2.5, m2 = 0.5 kg, l1 = 1, l2 = 2 m, g = 9.8: the textbook Euler-Lagrange coefficients."""
    m1, m2, l1, l2, g = 2.5, 0.5, 1.0, 2.0, 9.8
    eq1, eq2 = CONSISTENT_DOUBLE_PENDULUM.true
    assert eq1 == pytest.approx({"qdd1": (m1 + m2) * l1**2, "qdd2*cos(q1-q2)": m2 * l1 * l2,
                                 "qd2^2*sin(q1-q2)": m2 * l1 * l2, "sin(q1)": (m1 + m2) * g * l1})
    assert eq2 == pytest.approx({"qdd2": m2 * l2**2, "qdd1*cos(q1-q2)": m2 * l1 * l2,
                                 "qd1^2*sin(q1-q2)": -m2 * l1 * l2, "sin(q2)": m2 * g * l2})


@pytest.mark.parametrize("name", list(BY_NAME))
def test_noise_free_fit_is_exact(name):
    f = fit_system(BY_NAME[name], noise=0.0)
    assert f.max_error < 1e-8 and not any(f.extra_terms)


@pytest.mark.parametrize("name", list(BY_NAME))
def test_five_percent_noise_coefficients_within_three_standard_errors(name):
    f = fit_system(BY_NAME[name], noise=0.05)
    assert not any(f.extra_terms)
    for c in f.coefficients:
        assert abs(c.ours - c.true) <= 3 * c.stderr + 1e-12, c


@pytest.mark.parametrize("name", list(BY_NAME))
def test_issue_bar_every_coefficient_within_one_percent_on_the_bench_seed(name):
    """Issue #3's acceptance bar, on the draw the bench reports (fit_system's defaults: 5 %
    noise, seed 8): every coefficient within 1 % of the truth, no extra term. The
    three-standard-error test above is the statistical check; this one pins the bar."""
    f = fit_system(BY_NAME[name])
    assert not any(f.extra_terms)
    for c in f.coefficients:
        assert c.error <= 0.01, c
    assert f.max_error <= 0.01


def test_coupled_fit_shares_the_coupling_coefficient():
    f = fit_system(CONSISTENT_DOUBLE_PENDULUM, noise=0.05)
    shared = [c.ours * np.sign(c.true) for c in f.coefficients if abs(abs(c.true) - 1.0) < 1e-12]
    assert len(shared) == 4 and np.ptp(shared) < 1e-12  # m2 l1 l2 appears once in L
    assert f.max_error < 0.01


@pytest.mark.parametrize("name", list(BY_NAME))
def test_pysindy_agrees_on_noise_free_data(name):
    """An independent sparse regressor (pysindy STLSQ) on the same library finds the same model."""
    import pysindy as ps

    s = BY_NAME[name]
    m = s.motion(1500)
    tau = s.torque(m)
    lib = s.library()
    theta = lib.evaluate(m.q, m.qd, m.qdd)
    ours = identify(m.q, m.qd, m.qdd, tau, lib, 0.25, method="per-joint")
    for j in range(s.dof):
        coef = ps.STLSQ(threshold=1e-3, alpha=0.0, normalize_columns=True).fit(theta, tau[:, j]).coef_.ravel()
        theirs = {n: c for n, c in zip(lib.names, coef, strict=True) if c != 0}
        got = dict(zip(ours.model.joints[j].terms, ours.model.joints[j].coefficients, strict=True))
        assert set(theirs) == set(got)
        np.testing.assert_allclose([theirs[k] for k in got], list(got.values()), rtol=1e-6)


def test_jointwise_fits_only_the_lagrangian_equation_by_atoms():
    """Printed double pendulum: eq. 2 passes the F-test (atoms, shared coupling), eq. 1 fails."""
    from identification.regression.coupled import CoupledRegression
    from identification.regression.sparse import SparseRegression

    s = BY_NAME["double pendulum"]
    m = s.motion()
    tau = s.torque(m)
    noisy = tau + 0.05 * tau.std(0) * np.random.default_rng(3).normal(size=tau.shape)
    r = identify(m.q, m.qd, m.qdd, noisy, s.library(), 0.25, tau, method="jointwise")
    assert isinstance(r.regressions[0], SparseRegression)
    assert isinstance(r.regressions[1], CoupledRegression)
    eq2 = dict(zip(r.model.joints[1].terms, r.model.joints[1].coefficients, strict=True))
    assert eq2["qdd1*cos(q1-q2)"] == pytest.approx(-eq2["qd1^2*sin(q1-q2)"], rel=1e-12)


def test_restriction_pvalue_separates_nested_truth_from_misfit():
    from identification.regression.coupled import restriction_pvalue

    rng = np.random.default_rng(0)
    full = rng.normal(size=(2000, 6))
    y_in = full[:, :2] @ [1.0, -2.0] + 0.1 * rng.normal(size=2000)
    y_out = y_in + 0.05 * full[:, 5]
    assert restriction_pvalue(full[:, :2], full, y_in) > 0.01
    assert restriction_pvalue(full[:, :2], full, y_out) < 1e-6
