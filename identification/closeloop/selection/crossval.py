"""Block cross-validation of effect columns over a base design, for any subset, fast.

The problem is one weighted least-squares regression stacked over joints: the target
(n, dof) ~ base columns (n, dof, p) + effect columns (n, dof, m), rows of joint j weighted
by w_j. For each of B contiguous blocks of samples (the validation block), the base is
fitted on the other blocks; by the Frisch-Waugh-Lovell theorem the effects' coefficients
of the joint fit are the least-squares fit of the base-projected effect columns to the
base-projected target, and the validation block's residual is the target's minus the
effects' "base-corrected" columns (each column minus the base's prediction of it from the
training blocks). Both are computed once per block, so scoring a subset of effects costs
one small least-squares fit per block.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg


@dataclass(frozen=True)
class Fold:
    """One validation block: projected training columns and corrected validation columns."""

    train_target: np.ndarray  # (r,) base-projected weighted target on the training rows
    train_effects: np.ndarray  # (r, m)
    held_target: np.ndarray  # (h, dof) base-corrected weighted target on the validation rows
    held_effects: np.ndarray  # (h, dof, m)


def _fold(base, target, effects, train: np.ndarray, held: np.ndarray,
          refit_offset: bool = False) -> Fold:
    p, m = base.shape[2], effects.shape[2]
    q, r, perm = scipy.linalg.qr(base[train].reshape(-1, p), mode="economic", pivoting=True)
    diag = np.abs(np.diag(r))
    rank = int(np.sum(diag > 1e-10 * diag[0])) if len(diag) else 0
    q, r, keep = q[:, :rank], r[:rank, :rank], perm[:rank]
    vt = np.concatenate([target[train].reshape(-1, 1), effects[train].reshape(-1, m)], axis=1)
    coef = np.linalg.solve(r, q.T @ vt)  # the base's fit of every column on the training rows
    proj = vt - q @ (q.T @ vt)
    vh = np.concatenate([target[held][:, :, None], effects[held]], axis=2)
    corrected = vh - (base[held][:, :, keep] @ coef)
    if refit_offset:  # a constant per joint refitted on the held rows: every column demeaned
        corrected = corrected - corrected.mean(axis=0)
    return Fold(proj[:, 0], proj[:, 1:], corrected[:, :, 0], corrected[:, :, 1:])


@dataclass(frozen=True)
class BlockValidation:
    """Block cross-validation of subsets of effects over a fixed base."""

    folds: tuple[Fold, ...]
    dof: int

    @classmethod
    def build(cls, base: np.ndarray, target: np.ndarray, effects: np.ndarray,
              weights: np.ndarray, blocks: int | list[np.ndarray],
              refit_offset: bool = False) -> BlockValidation:
        """base (n, dof, p), target (n, dof), effects (n, dof, m), weights (dof,) per joint;
        blocks: how many contiguous blocks, or the sample indices of each (one run each);
        refit_offset: each validation block scored with a constant per joint of its own
        refitted (a held-out run's sensor offset, which the other runs cannot give)."""
        w = np.asarray(weights, float)
        base, target, effects = base * w[None, :, None], target * w, effects * w[None, :, None]
        n = len(target)
        folds = []
        for block in (np.array_split(np.arange(n), blocks) if isinstance(blocks, int) else blocks):
            held = np.zeros(n, bool)
            held[block] = True
            folds.append(_fold(base, target, effects, ~held, held, refit_offset))
        return cls(tuple(folds), target.shape[1])

    def sse(self, subset: list[int]) -> np.ndarray:
        """Per-joint weighted sum of squared validation errors with the effects in subset."""
        return np.sum(self.sse_folds(subset), axis=0)

    def sse_folds(self, subset: list[int]) -> np.ndarray:
        """(blocks, dof): the same per validation block."""
        out = np.zeros((len(self.folds), self.dof))
        for k, f in enumerate(self.folds):
            resid = f.held_target
            if subset:
                c, *_ = np.linalg.lstsq(f.train_effects[:, subset], f.train_target, rcond=None)
                resid = resid - f.held_effects[:, :, subset] @ c
            out[k] = np.sum(resid**2, axis=0)
        return out


def weighted_fit(base: np.ndarray, target: np.ndarray, effects: np.ndarray,
                 weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients of the base (p,) and of the effects (m,) fitted jointly by weighted least
    squares on all rows; base columns the data cannot resolve get 0 (minimum norm)."""
    w = np.asarray(weights, float)
    X = np.concatenate([base, effects], axis=2) * w[None, :, None]
    coef, *_ = np.linalg.lstsq(X.reshape(-1, X.shape[2]), (target * w).ravel(), rcond=None)
    return coef[:base.shape[2]], coef[base.shape[2]:]
