"""The regressors' common base, in scikit-learn's manner (as pysindy's optimizers share one).

A regressor's hyper-parameters are its __init__ arguments, stored unchanged, so that
scikit-learn's BaseEstimator gives get_params / set_params / clone / repr. `fit(X, y)` does
the common work once: it checks the data (finite float arrays; X (n, p) with y (n,), or,
for a regressor `stacked` over joints, X (n, dof, p) with y (n, dof)), then runs the
subclass's core step `_fit` and returns self. What a fit learns ends in "_":

- coef_ (p,): one coefficient per column of X, zero off the support;
- support_ (p,) bool: the kept columns;
- intercept_: the unpenalized offset (the sensor bias), a float, or (dof,) when stacked;
- n_features_in_: p, checked again by predict.

`predict(X)` is the torque model X @ coef_ *without* intercept_: as in identification.feature_model,
the sensor bias is not torque; `predict(X, offset=True)` adds it. Predicting before fit raises
scikit-learn's NotFittedError; bad data raise IdentificationError.

Also here: what several regressors share arithmetic for, the validation blocks, the
centring / column scaling of the sparse selectors, and the centring per run of several runs.
"""

from __future__ import annotations

import abc
from typing import ClassVar, Self

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from identification.errors import IdentificationError


def validation_mask(n: int, block: int = 50, every: int = 5) -> np.ndarray:
    """Every `every`-th block of `block` consecutive samples is validation."""
    return (np.arange(n) // block) % every == every - 1


def within_runs(x: np.ndarray, runs) -> np.ndarray:
    """x (n, ...) less each run's mean over its samples (runs: (n,) run labels; None or a
    single run: x less its mean). Fitting on this is fitting a free offset per run and joint
    (Frisch-Waugh-Lovell): a sensor offset that differs between runs is not fitted as
    dynamics."""
    runs = np.zeros(len(x), int) if runs is None else np.asarray(runs)
    out = np.array(x, dtype=float)
    for r in np.unique(runs):
        out[runs == r] -= out[runs == r].mean(axis=0)
    return out


def run_centring(runs):
    """(several, centred) for run labels (n,) or None: whether the samples come from more than
    one run, and within_runs on them then (the identity for one run)."""
    several = runs is not None and len(np.unique(runs)) > 1
    return several, ((lambda x: within_runs(x, runs)) if several else (lambda x: x))


def standardize(x: np.ndarray, y: np.ndarray, rows):
    """Centre x (n, p) and y (n,) on `rows` and scale x's columns to unit std there (columns
    constant there are left unscaled): (xs, yc, mean_x, mean_y, scale)."""
    mean_x, mean_y = x[rows].mean(0), y[rows].mean()
    scale = x[rows].std(0)
    scale[scale == 0] = 1.0
    return (x - mean_x) / scale, y - mean_y, mean_x, mean_y, scale


class Regressor(BaseEstimator, abc.ABC):
    """fit(X, y) -> self, predict(X); subclasses write only `_fit` (and `_predict` if X @ coef_
    is not their torque model)."""

    stacked: ClassVar[bool] = False  # X (n, dof, p), y (n, dof) instead of X (n, p), y (n,)

    def fit(self, X, y) -> Self:
        """Check X and y, fit; sets coef_, support_, intercept_ and the subclass's attributes."""
        X, y = self._check_X(X), self._as_float(y, "y")
        if y.shape != X.shape[:-1]:
            want = "(n_samples, n_joints)" if self.stacked else "(n_samples,)"
            raise IdentificationError(
                f"{type(self).__name__}: y must have shape {want} = {X.shape[:-1]} to match X "
                f"{X.shape}, got {y.shape}")
        if len(y) == 0 or X.shape[-1] == 0:
            raise IdentificationError(f"{type(self).__name__}: no samples or no columns in X {X.shape}")
        self.n_features_in_ = X.shape[-1]
        self._fit(X, y)
        return self

    @abc.abstractmethod
    def _fit(self, X: np.ndarray, y: np.ndarray) -> None:
        """The core step on checked float arrays: must set coef_, support_ and intercept_."""

    def predict(self, X, offset: bool = False) -> np.ndarray:
        """Torque X @ coef_: (n,), or (n, dof) when stacked; offset=True adds intercept_."""
        check_is_fitted(self, "coef_")
        X = self._check_X(X)
        if X.shape[-1] != self.n_features_in_:
            raise IdentificationError(f"{type(self).__name__}: X has {X.shape[-1]} columns, the fit "
                                      f"had {self.n_features_in_}")
        pred = self._predict(X)
        return pred + self.intercept_ if offset else pred

    def _predict(self, X: np.ndarray) -> np.ndarray:
        return X @ self.coef_

    def _set_coef(self, n_features: int, kept, values: np.ndarray) -> None:
        """coef_ (zero but on the kept columns, which get `values`) and support_."""
        self.coef_ = np.zeros(n_features)
        self.coef_[kept] = values
        self.support_ = np.zeros(n_features, bool)
        self.support_[kept] = True

    def _check_X(self, X) -> np.ndarray:
        X = self._as_float(X, "X")
        if X.ndim != (3 if self.stacked else 2):
            want = "(n_samples, n_joints, n_columns)" if self.stacked else "(n_samples, n_columns)"
            raise IdentificationError(f"{type(self).__name__}: X must have shape {want}, "
                                      f"got {X.shape}")
        return X

    def _as_float(self, a, name: str) -> np.ndarray:
        try:
            a = np.asarray(a, dtype=float)
        except (TypeError, ValueError) as e:
            raise IdentificationError(f"{type(self).__name__}: {name} is not numeric ({e})") from None
        if not np.all(np.isfinite(a)):
            raise IdentificationError(f"{type(self).__name__}: {name} contains NaN or inf")
        return a
