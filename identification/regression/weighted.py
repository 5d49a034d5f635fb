"""Weighted least squares on stacked atom designs with a per-joint offset (the refit of every
coupled fit, identification.regression.coupled) and the t-statistic of an atom added to a
support without refitting the rows (its forward step)."""

from __future__ import annotations

import numpy as np


def _offset_design(design: np.ndarray, cols) -> np.ndarray:
    """Stack design columns `cols` with one offset indicator per joint: (n*dof, k+dof)."""
    n, dof, _ = design.shape
    eye = np.broadcast_to(np.eye(dof), (n, dof, dof))
    return np.concatenate([design[:, :, cols], eye], axis=2).reshape(n * dof, -1)


def weighted_lstsq(design: np.ndarray, tau: np.ndarray, cols, sigma: np.ndarray):
    """Weighted least squares of tau (n, dof) on design[:, :, cols] + per-joint offsets:
    coefficients of cols, offsets (dof,), residual (n, dof), their covariance (scaled)."""
    n, dof = tau.shape
    x = _offset_design(design, list(cols)) * np.tile(1.0 / sigma, n)[:, None]
    sol = np.linalg.lstsq(x, tau.reshape(-1) * np.tile(1.0 / sigma, n), rcond=None)[0]
    resid = tau - (x @ sol).reshape(n, dof) * sigma
    scale = float(np.sum((resid / sigma) ** 2)) / max(n * dof - x.shape[1], 1)
    cov = scale * np.linalg.pinv(x.T @ x)[:-dof, :-dof]
    return sol[:-dof], sol[-dof:], resid, cov


class WeightedGram:
    """Normal equations of the weighted, stacked design (every atom + per-joint offsets):
    the t-statistic of an atom added to a support without refitting the rows. Used to rank
    candidates only; kept supports are refitted by weighted_lstsq."""

    def __init__(self, design: np.ndarray, tau: np.ndarray, sigma: np.ndarray):
        n, dof, p = design.shape
        x = _offset_design(design, list(range(p))) * np.tile(1.0 / sigma, n)[:, None]
        y = tau.reshape(-1) * np.tile(1.0 / sigma, n)
        scale = 1.0 / np.maximum(np.linalg.norm(x, axis=0), 1e-300)  # unit columns: t is
        x = x * scale  # scale-free, and the small solves stay well conditioned
        self.gram, self.rhs, self.yy = x.T @ x, x.T @ y, float(y @ y)
        self.rows, self.offsets = len(y), np.arange(p, p + dof)

    def added_t(self, support: np.ndarray, candidates: np.ndarray) -> np.ndarray:
        """|t| of each candidate atom when it alone is added to support (+ offsets)."""
        out = np.zeros(len(candidates))
        for i, k in enumerate(candidates):
            cols = np.concatenate([support, [k], self.offsets])
            g = self.gram[np.ix_(cols, cols)]
            inv = np.linalg.pinv(g)
            coef = inv @ self.rhs[cols]
            rss = max(self.yy - coef @ self.rhs[cols], 0.0)
            var = rss / max(self.rows - len(cols), 1) * inv[len(support), len(support)]
            out[i] = abs(coef[len(support)]) / max(np.sqrt(max(var, 0.0)), 1e-300)
        return out
