"""Noise decomposition (paper II.A): y = x + v, x by Tikhonov smoothing.

x = argmin ||y - x||^2 + weight ||L x||^2 with L = D2 D2, the squared
second-difference operator of the authors' code (so the penalty is a fourth
difference and the smoother keeps cubic trends untouched). With reflective
boundaries D2 is diagonalized by the orthonormal DCT-II, eigenvalues
-(2 - 2 cos(pi k / n)), so the solve costs one DCT pair and the smoothing
weight can be chosen by generalized cross-validation (GCV) from the data
instead of the paper's hand-set weight = 1. The boundary rows differ from the
authors' one-sided stencils; only the first and last few samples notice.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.fft import dct, idct
from scipy.optimize import minimize_scalar

from identification.errors import IdentificationError


@dataclass(frozen=True)
class Denoised:
    """Per-column decomposition: signal + noise = measurement (same units as the input)."""

    signal: np.ndarray  # (n, m) estimated noise-free data x
    noise: np.ndarray  # (n, m) estimated noise v = y - x
    weight: np.ndarray  # (m,) smoothing weight per column (dimensionless, per sample^4)
    dof_used: np.ndarray  # (m,) trace of the smoother: effective number of parameters


def _penalty_eigenvalues(n: int) -> np.ndarray:
    """Eigenvalues of L^T L for L = D2 D2 with reflective boundaries."""
    mu = 2.0 - 2.0 * np.cos(np.pi * np.arange(n) / n)
    return mu**4


def _gcv(log_weight: float, coeffs: np.ndarray, eig: np.ndarray) -> float:
    h = 1.0 / (1.0 + np.exp(log_weight) * eig)
    n = len(coeffs)
    return n * float(np.sum(((1 - h) * coeffs) ** 2)) / (n - h.sum()) ** 2


def _check(y: np.ndarray) -> np.ndarray:
    y = np.asarray(y, dtype=float)
    y2 = y.reshape(len(y), -1) if y.ndim else y
    if y.ndim not in (1, 2) or len(y2) < 8:
        raise IdentificationError(
            f"denoise needs at least 8 samples in a 1-D or 2-D array, got shape {y.shape}")
    if not np.all(np.isfinite(y2)):
        raise IdentificationError("denoise: signal contains NaN or inf")
    return y2


def denoise(y, weight: float | None = None) -> Denoised:
    """Split y (n,) or (n, m) into signal and noise, column by column.

    weight=None chooses each column's weight by minimizing GCV over
    1e-4..1e14 (log-scale); a number uses that weight (the paper: 1).
    """
    y2 = _check(y)
    eig = _penalty_eigenvalues(len(y2))
    coeffs = dct(y2, type=2, norm="ortho", axis=0)
    weights = np.empty(y2.shape[1])
    for j in range(y2.shape[1]):
        if weight is not None:
            weights[j] = weight
        else:
            best = minimize_scalar(_gcv, bounds=(np.log(1e-4), np.log(1e14)), method="bounded",
                                   args=(coeffs[:, j], eig), options={"xatol": 1e-3})
            weights[j] = float(np.exp(best.x))
    h = 1.0 / (1.0 + weights[None, :] * eig[:, None])
    signal = idct(h * coeffs, type=2, norm="ortho", axis=0)
    shape = np.shape(y)
    return Denoised(signal.reshape(shape), (y2 - signal).reshape(shape), weights, h.sum(axis=0))
