"""The roboticist's oracle: weighted least squares on the true (base-parameter) regressor.

When the structure is known, tau = Y(q, qd, qdd) pi is linear in the standard
inertial parameters pi; only a subset of combinations (the base parameters)
is identifiable. Column-pivoted QR of the stacked regressor picks independent
columns; each joint's rows are weighted by 1/sigma_j, sigma_j estimated from
an unweighted first fit (two-step WLS). A per-joint offset absorbs the sensor
bias, as in the sparse model. Pure numpy: the caller supplies Y (e.g. from
Pinocchio's joint-torque regressor), so identification stays harness-free.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg


@dataclass(frozen=True)
class BaseParameterFit:
    """Base columns of the stacked regressor, their values and the per-joint offsets."""

    columns: np.ndarray  # indices into the standard parameter vector
    values: np.ndarray  # base parameter estimates
    offsets: np.ndarray  # (dof,) N m
    sigma: np.ndarray  # (dof,) residual std per joint, N m

    def predict(self, regressor: np.ndarray) -> np.ndarray:
        """Torque (n, dof) without offsets from a regressor of shape (n, dof, p)."""
        return regressor[:, :, self.columns] @ self.values


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


def fit_base_parameters(regressor: np.ndarray, tau: np.ndarray) -> BaseParameterFit:
    """Two-step WLS of tau (n, dof) on the base columns of regressor (n, dof, p) + offsets."""
    columns = base_columns(regressor)
    design = _design(regressor, columns)
    n, dof, k = design.shape
    sigma = np.ones(dof)
    for _ in range(2):
        w = (1.0 / sigma)[None, :, None]
        sol = np.linalg.lstsq((design * w).reshape(-1, k), (tau / sigma).reshape(-1), rcond=None)[0]
        resid = tau - design @ sol
        sigma = np.maximum(resid.std(axis=0), 1e-300)
    return BaseParameterFit(columns, sol[: len(columns)], sol[len(columns):], sigma)
