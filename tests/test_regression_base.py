"""The regressors' common base (identification.regression.base), checked on every regressor:
exact recovery of a known truth from noise-free data, the fit / predict contract, and one
clear error for bad input or a predict before fit."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.exceptions import NotFittedError

from identification.errors import IdentificationError
from identification.regression.base import Regressor
from identification.regression.coupled import CoupledRegression
from identification.regression.oracle import BaseParameterRegression, fit_base_parameters
from identification.regression.peers import PeerRegression, tune
from identification.regression.sparse import SparseRegression

N, DOF, P = 1000, 3, 10

# name: (a fresh regressor, stacked over joints, sparse truth)
REGRESSORS = {
    "sparse": (SparseRegression, False, True),
    "coupled": (CoupledRegression, True, True),
    "oracle": (BaseParameterRegression, True, False),
    "STLSQ": (lambda: PeerRegression("STLSQ"), False, True),
    "SSR": (lambda: PeerRegression("SSR"), False, True),
}


def _problem(stacked: bool, sparse: bool):
    """Noise-free data with a known truth: X (n, p) or (n, dof, p), coef (p,), offset, y."""
    rng = np.random.default_rng(7)
    shape = (N, DOF, P) if stacked else (N, P)
    x = rng.normal(size=shape) * rng.uniform(0.5, 5.0, P)  # varied column scales
    coef = np.zeros(P)
    if sparse:
        coef[[1, 4, 8]] = [2.0, -0.7, 0.3]
    else:
        coef[:] = rng.uniform(-2.0, 2.0, P)
    offset = np.array([0.3, -0.2, 0.1]) if stacked else 0.4
    return x, coef, offset, x @ coef + offset


@pytest.fixture(params=list(REGRESSORS))
def case(request):
    make, stacked, sparse = REGRESSORS[request.param]
    return make, _problem(stacked, sparse)


def test_every_regressor_recovers_a_noise_free_truth(case):
    make, (x, coef, offset, y) = case
    reg = make()
    assert isinstance(reg, Regressor)
    assert reg.fit(x, y) is reg
    np.testing.assert_allclose(reg.coef_, coef, rtol=0, atol=1e-9)
    np.testing.assert_allclose(reg.intercept_, offset, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(reg.support_, coef != 0)
    assert reg.n_features_in_ == P


def test_predict_is_the_torque_without_the_offset(case):
    make, (x, coef, offset, y) = case
    reg = make().fit(x, y)
    assert reg.predict(x).shape == y.shape
    np.testing.assert_allclose(reg.predict(x[:7]), x[:7] @ coef, rtol=0, atol=1e-8)
    np.testing.assert_allclose(reg.predict(x, offset=True), y, rtol=0, atol=1e-8)


def test_predict_before_fit_is_an_error(case):
    make, (x, *_) = case
    with pytest.raises(NotFittedError, match="not fitted"):
        make().predict(x)


@pytest.mark.parametrize("where", ["X", "y"])
def test_nan_input_is_an_identification_error(case, where):
    make, (x, _, _, y) = case
    x, y = x.copy(), y.copy()
    (x if where == "X" else y)[5] = np.nan
    with pytest.raises(IdentificationError, match=f"{where} contains NaN or inf"):
        make().fit(x, y)


def test_mismatched_rows_are_an_identification_error(case):
    make, (x, _, _, y) = case
    with pytest.raises(IdentificationError, match="must have shape"):
        make().fit(x, y[:-1])
    with pytest.raises(IdentificationError, match="must have shape"):
        make().fit(x[:, 0] if x.ndim == 3 else x[:, :, None], y)  # wrong number of axes


def test_predict_checks_its_input(case):
    make, (x, _, _, y) = case
    reg = make().fit(x, y)
    with pytest.raises(IdentificationError, match="columns"):
        reg.predict(x[..., :-1])
    bad = x.copy()
    bad[0] = np.inf
    with pytest.raises(IdentificationError, match="NaN or inf"):
        reg.predict(bad)


def test_hyper_parameters_round_trip_through_sklearn_clone(case):
    """get_params covers every setting: a clone refits to the very same numbers."""
    make, (x, _, _, y) = case
    reg = make()
    twin = clone(reg)
    assert twin.get_params() == reg.get_params()
    np.testing.assert_array_equal(twin.fit(x, y).coef_, reg.fit(x, y).coef_)


def test_coupled_fits_a_copy_of_its_selector():
    x, _, _, y = _problem(True, True)
    selector = SparseRegression(block=40)
    reg = CoupledRegression(selector=selector).fit(x, y)
    assert not hasattr(selector, "candidates_")  # the given selector is left unfitted
    assert reg.get_params()["selector__block"] == 40
    np.testing.assert_array_equal(reg.offsets_, reg.intercept_)


def test_the_function_forms_are_the_classes():
    """fit_base_parameters and tune (what the bench calls) are the regressors' fits."""
    x, coef, _, y = _problem(True, False)
    fit = fit_base_parameters(x, y)
    assert isinstance(fit, BaseParameterRegression)
    np.testing.assert_array_equal(fit.columns, np.arange(P))
    x, coef, _, y = _problem(False, True)
    peer = tune("SSR", x, y)
    assert isinstance(peer, PeerRegression) and peer.setting_name == "terms" and peer.setting == 3
    np.testing.assert_array_equal(peer.coef, peer.coef_)
    assert peer.intercept == peer.intercept_ and peer.seconds >= 0
