"""Tuned pysindy peers (identification.regression.peers): the sweep picks the true support on
sparse data, the refit equals least squares on the kept columns, and the selection rule is
the sparsest candidate within one paired standard error of the best."""

from __future__ import annotations

import numpy as np
import pytest

from identification.regression.base import validation_mask
from identification.regression.peers import choose, tune


@pytest.fixture(scope="module")
def sparse_problem():
    rng = np.random.default_rng(0)
    n, p = 3000, 20
    mix = np.eye(p) + 0.3 * rng.normal(size=(p, p))  # correlated columns, varied scales
    theta = rng.normal(size=(n, p)) @ mix * rng.uniform(0.1, 10.0, p)
    true = np.zeros(p)
    true[[1, 4, 7, 12]] = [0.5, -2.0, 0.05, 1.0]
    clean = theta @ true + 3.0  # the offset is the sensor bias: an intercept, not a term
    y = clean + 0.05 * clean.std() * rng.normal(size=n)
    return theta, y, true


@pytest.mark.parametrize("name", ["STLSQ", "SSR"])
def test_tuned_peer_finds_the_true_support(sparse_problem, name):
    theta, y, true = sparse_problem
    fit = tune(name, theta, y)
    np.testing.assert_array_equal(np.flatnonzero(fit.coef), np.flatnonzero(true))
    np.testing.assert_allclose(fit.coef[true != 0], true[true != 0], rtol=0.05)
    assert fit.intercept == pytest.approx(3.0, abs=0.1)
    assert fit.setting_name == ("threshold" if name == "STLSQ" else "terms")
    if name == "SSR":
        assert fit.setting == 4


@pytest.mark.parametrize("name", ["STLSQ", "SSR"])
def test_refit_is_least_squares_on_the_kept_columns(sparse_problem, name):
    """Cross-check against numpy: the peer's final coefficients are the unbiased least-squares
    fit (with intercept) of its own support on all rows."""
    theta, y, _ = sparse_problem
    fit = tune(name, theta, y)
    kept = np.flatnonzero(fit.coef)
    design = np.column_stack([theta[:, kept], np.ones(len(y))])
    sol = np.linalg.lstsq(design, y, rcond=None)[0]
    np.testing.assert_allclose(fit.coef[kept], sol[:-1], rtol=1e-8)
    assert fit.intercept == pytest.approx(sol[-1], rel=1e-8)


def test_choose_prefers_the_sparsest_statistically_tied_candidate():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(2000, 3))
    y = x @ [1.0, 0.5, 0.0] + 0.1 * rng.normal(size=2000)
    full = np.linalg.lstsq(x, y, rcond=None)[0]
    two = np.array([*np.linalg.lstsq(x[:, :2], y, rcond=None)[0], 0.0])
    one = np.array([np.linalg.lstsq(x[:, :1], y, rcond=None)[0][0], 0.0, 0.0])
    setting, coef = choose([("full", full), ("two", two), ("one", one)], x, y)
    assert setting == "two"  # drops the null column, keeps the real 0.5 term


def test_validation_blocks_are_ours():
    """The peers select on the same validation rows as SparseRegression (block 50, every 5th)."""
    mask = validation_mask(500)
    assert mask.sum() == 100 and mask[200:250].all() and not mask[:200].any()


def test_unknown_peer_is_an_error(sparse_problem):
    theta, y, _ = sparse_problem
    with pytest.raises(ValueError, match="unknown peer"):
        tune("SR3", theta, y)
