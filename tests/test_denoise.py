"""Denoising: DCT solve equals the explicit Tikhonov solve; GCV beats no smoothing."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from identification.errors import IdentificationError
from identification.regression.denoise import denoise


def _explicit(y: np.ndarray, weight: float) -> np.ndarray:
    """(I + w L^T L)^-1 y with L = D2 D2, D2 the reflective second difference (sparse solve)."""
    n = len(y)
    d1 = sp.diags([-np.ones(n - 1), np.ones(n - 1)], [0, 1], shape=(n - 1, n))
    d2 = -(d1.T @ d1)  # rows [1, -2, 1], reflective ends
    lop = d2 @ d2
    return spla.spsolve((sp.identity(n) + weight * (lop.T @ lop)).tocsc(), y)


def test_dct_solution_equals_explicit_tikhonov():
    rng = np.random.default_rng(0)
    y = np.sin(np.linspace(0, 6, 300)) + 0.1 * rng.normal(size=300)
    for w in (1.0, 1e3, 1e6):
        np.testing.assert_allclose(denoise(y, w).signal, _explicit(y, w), atol=1e-9)


def test_gcv_denoising_reduces_noise_at_five_percent():
    rng = np.random.default_rng(1)
    t = np.linspace(0, 20, 4000)
    clean = np.column_stack([np.sin(2 * np.pi * 0.3 * t) + 0.3 * np.cos(2 * np.pi * 1.1 * t),
                             np.cos(2 * np.pi * 0.2 * t)])
    noisy = clean + 0.05 * clean.std(0) * (rng.normal(size=clean.shape) + 0.2)
    out = denoise(noisy)
    before = np.mean((noisy - clean) ** 2, axis=0)
    after = np.mean((out.signal - clean) ** 2, axis=0)
    assert np.all(before / after >= 1.8)
    np.testing.assert_allclose(out.signal + out.noise, noisy)
    assert np.all(out.weight > 1.0)  # data asks for more smoothing than the paper's weight 1


def test_denoise_rejects_bad_signal():
    with pytest.raises(IdentificationError, match="NaN"):
        denoise(np.array([1.0, np.nan] * 10))
    with pytest.raises(IdentificationError, match="at least 8"):
        denoise(np.ones(3))
