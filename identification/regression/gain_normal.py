"""The normal equations of a drive-gain fit, known x - diag(current) K = target, kept per joint
(identification.drive_gains): joint j's rows are weighted alike and its gain's column is
non-zero on its rows only, so a pass with new weights or new instruments costs O(N k), and a
jackknife fold's equations are the whole's less its block's."""

from __future__ import annotations

import numpy as np


def gram(known: np.ndarray) -> np.ndarray:
    """(dof, k, k) each joint's known' known."""
    return np.einsum("njk,njl->jkl", known, known, optimize=True)


def cross(known: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(dof, k) each joint's known' x."""
    return np.einsum("njk,nj->jk", known, x)


class GainNormal:
    """The normal equations of known x - diag(current) K = target, kept per joint: joint j's
    rows are weighted alike and its gain's column is non-zero on its rows only, so each pass
    (new weights, new instruments) costs O(N k) instead of O(N k^2); gram: the per-joint
    known' known when already at hand (a jackknife fold's: the whole's less its block's)."""

    def __init__(self, known: np.ndarray, current: np.ndarray, target: np.ndarray,
                 gram: np.ndarray | None = None):
        self.known, self.current, self.target = known, current, target
        self.dof, self.kb = current.shape[1], known.shape[2]
        self.gram = gram(known) if gram is None else gram  # (dof, kb, kb)
        self.cross_t = cross(known, target)  # (dof, kb)
        self.cross_i = cross(known, current)

    def predicted(self, sol: np.ndarray) -> np.ndarray:
        """(N, dof) the currents sol predicts: (known x - target) / K."""
        return (self.known @ sol[:self.kb] - self.target) / sol[self.kb:]

    def residual_std(self, sol: np.ndarray) -> np.ndarray:
        """(dof,) std over the samples of each joint's residual (N m)."""
        resid = self.target - self.known @ sol[:self.kb] + self.current * sol[self.kb:]
        return resid.std(axis=0)

    def _matrix(self, left: np.ndarray, right: np.ndarray, product: np.ndarray,
                w2: np.ndarray) -> np.ndarray:
        """sum_j w_j^2 L_j' R_j with L_j = [known_j, -l_j e_j'] (R_j alike with r): left and
        right the per-joint known_j' l_j and known_j' r_j (dof, kb), product l_j' r_j."""
        kb = self.kb
        out = np.zeros((kb + self.dof, kb + self.dof))
        out[:kb, :kb] = np.tensordot(w2, self.gram, axes=1)
        out[:kb, kb:] = -(w2[:, None] * right).T
        out[kb:, :kb] = -w2[:, None] * left
        out[kb:, kb:] = np.diag(w2 * product)
        return out

    def solve(self, instrument: np.ndarray, w: np.ndarray, covariance: bool = True
              ) -> tuple[np.ndarray, np.ndarray | None]:
        """The instrumental-variable solution (instrument = current: weighted least squares),
        rows of joint j weighted by w_j, and its covariance (None when not asked for)."""
        w2 = w**2
        ci = self.cross_i if instrument is self.current else cross(self.known, instrument)
        za = self._matrix(ci, self.cross_i, np.einsum("nj,nj->j", instrument, self.current), w2)
        zb = np.concatenate([np.tensordot(w2, self.cross_t, axes=1),
                             -w2 * np.einsum("nj,nj->j", instrument, self.target)])
        d = 1.0 / np.sqrt(np.maximum(np.concatenate([
            np.tensordot(w2, np.diagonal(self.gram, axis1=1, axis2=2), axes=1),
            w2 * np.einsum("nj,nj->j", self.current, self.current)]), 1e-300))
        x = d * np.linalg.lstsq(za * np.outer(d, d), d * zb, rcond=None)[0]
        if not covariance:
            return x, None
        zz = self._matrix(ci, ci, np.einsum("nj,nj->j", instrument, instrument), w2)
        resid = (self.target - self.known @ x[:self.kb] + self.current * x[self.kb:]) * w
        dof_left = max(resid.size - len(x), 1)
        inv = np.linalg.pinv(za * np.outer(d, d))
        cov = (inv @ (zz * np.outer(d, d)) @ inv.T) * np.outer(d, d) * float(np.sum(resid**2)) / dof_left
        return x, cov
