"""Sparse regression of one torque (paper II.B, II.C, III.F): a Regressor (regression.base).

Lasso over a swept alpha gives each alpha a support; the proportional filter
then repeatedly drops the fraction 1 - pass_rate of the kept terms with the
smallest standardized coefficients, refitting by least squares, until the
validation error rises. Alpha and pass rate are chosen on validation blocks
held out of the fit (the paper chose them on the training fit, which always
prefers the largest model), preferring the sparsest candidate whose validation
error is statistically indistinguishable from the best: the mean of the
per-sample squared-residual differences against the best is below its
standard error (a paired one-standard-error rule) or below the relative
`tolerance` (rule="tolerance" uses only the latter). The kept terms are then refit without
shrinkage on all the data. An unpenalized intercept absorbs a constant sensor
bias; it is reported as `intercept_` and is not a library term.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from sklearn.exceptions import ConvergenceWarning
from sklearn.linear_model import lasso_path

from identification.regression.base import Regressor, standardize, validation_mask


@dataclass(frozen=True)
class Candidate:
    """One (alpha, pass_rate) outcome: kept columns and their validation MSE."""

    alpha: float
    pass_rate: float
    support: tuple[int, ...]
    validation_mse: float


class _Normal:
    """Normal equations of centred, column-scaled data: cheap subset least squares."""

    def __init__(self, x: np.ndarray, y: np.ndarray):
        self.gram, self.rhs, self.yy, self.n = x.T @ x, x.T @ y, float(y @ y), len(y)

    def solve(self, support) -> np.ndarray:
        s = list(support)
        return np.linalg.lstsq(self.gram[np.ix_(s, s)], self.rhs[s], rcond=None)[0]

    def significance(self, support, coef) -> np.ndarray:
        """|coef| / its standard error up to the common noise factor (a t-statistic)."""
        s = list(support)
        inv_diag = np.diag(np.linalg.pinv(self.gram[np.ix_(s, s)]))
        return np.abs(coef) / np.sqrt(np.maximum(inv_diag, 1e-300))

    def mse(self, support, coef) -> float:
        s = list(support)
        sq = self.yy - 2 * coef @ self.rhs[s] + coef @ self.gram[np.ix_(s, s)] @ coef
        return max(sq, 0.0) / self.n


class SparseRegression(Regressor):
    """Lasso + proportional filter + unbiased refit, with held-out selection.

    fit(theta (n, p) library, y (n,) target) sets coef_, intercept_, support_, stderr_ (each
    kept coefficient's standard error), alpha_, pass_rate_, candidates_ (every tried alpha
    and pass rate) and alphas_.
    """

    def __init__(self, n_alphas: int = 30, alpha_ratio: float = 1e-5,
                 pass_rates=(0.5, 0.7, 0.8, 0.9), tolerance: float = 0.002,
                 rise_tolerance: float = 1e-9, block: int = 50, every: int = 5,
                 rank_by: str = "t", rule: str = "1se"):
        self.n_alphas, self.alpha_ratio, self.rule = n_alphas, alpha_ratio, rule
        self.pass_rates, self.tolerance, self.rise_tolerance = pass_rates, tolerance, rise_tolerance
        self.block, self.every, self.rank_by = block, every, rank_by

    def _prune(self, support, fit: _Normal, val: _Normal, pass_rate: float, floor: float):
        """Proportional filter: drop the weakest (1 - pass_rate) share until the error rises."""
        support = tuple(support)
        err = val.mse(support, fit.solve(support))
        while len(support) > 1:
            coef = fit.solve(support)
            drop = max(1, int(np.floor((1 - pass_rate) * len(support))))
            weight = fit.significance(support, coef) if self.rank_by == "t" else np.abs(coef)
            order = np.argsort(weight, kind="stable")
            trial = tuple(sorted(np.asarray(support)[np.sort(order[drop:])]))
            trial_err = val.mse(trial, fit.solve(trial))
            if trial_err > err * (1 + self.rise_tolerance) + floor:
                break
            support, err = trial, trial_err
        return support, err

    def _fit(self, theta: np.ndarray, y: np.ndarray) -> None:
        mask = validation_mask(len(y), self.block, self.every)
        xs, yc, *_ = standardize(theta, y, ~mask)
        chosen = self.select(xs[~mask], yc[~mask], xs[mask], yc[mask])
        self._refit(theta, y, chosen.support)

    def select(self, x_fit: np.ndarray, y_fit: np.ndarray, x_val: np.ndarray,
               y_val: np.ndarray) -> Candidate:
        """The chosen (alpha, pass rate, support) on centred, column-scaled fit/validation data.

        Sets candidates_, alphas_, alpha_ and pass_rate_.
        """
        fit, val = _Normal(x_fit, y_fit), _Normal(x_val, y_val)
        floor = 1e-14 * float(y_fit @ y_fit) / len(y_fit)
        with warnings.catch_warnings():  # tiny alphas on exact data converge slowly; harmless
            warnings.simplefilter("ignore", ConvergenceWarning)
            alphas, coefs, _ = lasso_path(x_fit, y_fit, alphas=self.n_alphas,
                                          eps=self.alpha_ratio, max_iter=5000, tol=1e-8)
        cands, memo = [], {}
        for a, c in zip(alphas, coefs.T, strict=True):
            start = tuple(np.flatnonzero(c)) or (int(np.argmax(np.abs(x_fit.T @ y_fit))),)
            for r in self.pass_rates:
                if (start, r) not in memo:  # neighbouring alphas often share a support
                    memo[start, r] = self._prune(start, fit, val, r, floor)
                cands.append(Candidate(float(a), r, *memo[start, r]))
        good = self._good(cands, fit, x_val, y_val, floor)
        chosen = min(good, key=lambda c: (len(c.support), c.validation_mse))
        self.candidates_, self.alphas_ = cands, alphas
        self.alpha_, self.pass_rate_ = chosen.alpha, chosen.pass_rate
        return chosen

    def _good(self, cands, fit: _Normal, x_val, y_val, floor: float) -> list[Candidate]:
        """Candidates as good as the best on validation: within `tolerance` (rule 'tolerance')
        or, rule '1se', within the larger of that and one paired standard error of the
        per-sample squared-residual differences against the best."""
        best = min(cands, key=lambda c: c.validation_mse)
        if self.rule != "1se":
            limit = best.validation_mse * (1 + self.tolerance) + floor
            return [c for c in cands if c.validation_mse <= limit]

        def squared(support):
            s = list(support)
            return (y_val - x_val[:, s] @ fit.solve(s)) ** 2

        ref, memo, good = squared(best.support), {}, []
        for c in cands:
            if c.support not in memo:
                d = squared(c.support) - ref
                slack = max(d.std() / np.sqrt(len(d)), self.tolerance * best.validation_mse)
                memo[c.support] = d.mean() <= slack + floor
            if memo[c.support]:
                good.append(c)
        return good

    def _refit(self, theta: np.ndarray, y: np.ndarray, support) -> None:
        """Unbiased least squares of the kept terms plus intercept on all samples; stderr_
        holds each kept coefficient's standard error (residual variance x (X^T X)^-1)."""
        s = list(support)
        design = np.column_stack([theta[:, s], np.ones(len(y))])
        sol, *_ = np.linalg.lstsq(design, y, rcond=None)
        resid = y - design @ sol
        var = float(resid @ resid) / max(len(y) - design.shape[1], 1)
        cov = var * np.linalg.pinv(design.T @ design)
        self._set_coef(theta.shape[1], s, sol[:-1])
        self.stderr_ = np.zeros(theta.shape[1])
        self.stderr_[s] = np.sqrt(np.maximum(np.diag(cov)[:-1], 0.0))
        self.intercept_ = float(sol[-1])
