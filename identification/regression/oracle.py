"""The roboticist's oracle: weighted least squares on the true (base-parameter) regressor.

When the structure is known, tau = Y(q, qd, qdd) pi is linear in the standard
inertial parameters pi; only a subset of combinations (the base parameters)
is identifiable. Column-pivoted QR of the stacked regressor picks independent
columns; each joint's rows are weighted by 1/sigma_j, sigma_j estimated from
an unweighted first fit (two-step WLS). A per-joint offset absorbs the sensor
bias, as in the sparse model. The caller supplies Y (e.g. from Pinocchio's
joint-torque regressor), so identification stays harness-free.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from identification.regression.base import Regressor


def base_columns(regressor: np.ndarray, rtol: float = 1e-8) -> np.ndarray:
    """Independent columns of the stacked (n*dof, p) regressor, by pivoted QR."""
    stacked = regressor.reshape(-1, regressor.shape[-1])
    norms = np.linalg.norm(stacked, axis=0)
    usable = np.flatnonzero(norms > 0)
    _, r, perm = scipy.linalg.qr(stacked[:, usable] / norms[usable], mode="economic", pivoting=True)
    diag = np.abs(np.diag(r))
    rank = int(np.sum(diag > rtol * diag[0]))
    return np.sort(usable[perm[:rank]])


def _design(regressor: np.ndarray, columns: np.ndarray) -> np.ndarray:
    n, dof, _ = regressor.shape
    offsets = np.zeros((n, dof, dof))
    offsets[:, np.arange(dof), np.arange(dof)] = 1.0
    return np.concatenate([regressor[:, :, columns], offsets], axis=2)


class BaseParameterRegression(Regressor):
    """Two-step WLS of tau (n, dof) on the base columns of a regressor (n, dof, p) + offsets.

    rtol: pivoted-QR rank tolerance of base_columns. fit sets columns_ (the base columns,
    indices into the standard parameter vector), coef_ (p,) (the base parameter estimates on
    columns_, zero elsewhere), support_, intercept_ (dof,) N m and sigma_ (dof,) the residual
    std per joint, N m.
    """

    stacked = True

    def __init__(self, rtol: float = 1e-8):
        self.rtol = rtol

    def _fit(self, regressor: np.ndarray, tau: np.ndarray) -> None:
        columns = base_columns(regressor, self.rtol)
        design = _design(regressor, columns)
        n, dof, k = design.shape
        sigma = np.ones(dof)
        for _ in range(2):
            w = (1.0 / sigma)[None, :, None]
            sol = np.linalg.lstsq((design * w).reshape(-1, k), (tau / sigma).reshape(-1), rcond=None)[0]
            resid = tau - design @ sol
            sigma = np.maximum(resid.std(axis=0), 1e-300)
        self.columns_, self.sigma_ = columns, sigma
        self._set_coef(regressor.shape[-1], columns, sol[: len(columns)])
        self.intercept_ = sol[len(columns):]

    def _predict(self, regressor: np.ndarray) -> np.ndarray:
        return regressor[:, :, self.columns_] @ self.coef_[self.columns_]

    @property
    def columns(self) -> np.ndarray:
        """columns_ (the name fit_base_parameters' callers read)."""
        return self.columns_


def fit_base_parameters(regressor: np.ndarray, tau: np.ndarray) -> BaseParameterRegression:
    """BaseParameterRegression().fit(regressor, tau): the oracle fit."""
    return BaseParameterRegression().fit(regressor, tau)
