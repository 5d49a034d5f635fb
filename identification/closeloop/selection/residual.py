"""Residual diagnostics: how big, how white, and what it looks like.

The residual r = measured torque - declared model, per joint (N m). Torque
sensor noise is white, while the dynamics sampled at 200 Hz are smooth, so the
white-noise level is estimated from the residual's second differences
(var(d^2 r) = 6 sigma^2 for white noise) without knowing the model; what the
residual carries above that level is structure.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2

LJUNG_BOX_LAGS = 20


@dataclass(frozen=True)
class JointDiagnostics:
    """Diagnostics of one joint's residual; torques in N m."""

    joint: int
    rms: float  # residual RMS
    noise_sigma: float  # white-noise level estimated from second differences
    structure: float  # RMS of the part above the white noise, in units of noise_sigma
    ljung_box_q: float
    ljung_box_p: float  # p-value of "the residual is white" over LJUNG_BOX_LAGS lags
    correlations: dict[str, float]  # |corr| of residual with each candidate signal

    def to_json(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def noise_sigma(r: np.ndarray) -> np.ndarray:
    """White-noise std per column from second differences (N m)."""
    return np.std(np.diff(r, n=2, axis=0), axis=0) / np.sqrt(6.0)


def ljung_box(x: np.ndarray, lags: int = LJUNG_BOX_LAGS) -> tuple[float, float]:
    """Ljung-Box Q statistic and p-value (chi2 with `lags` dof) of a 1-D series."""
    x = np.asarray(x, dtype=float) - np.mean(x)
    n = len(x)
    denom = float(x @ x)
    if denom == 0.0 or n <= lags + 1:
        return 0.0, 1.0
    rho = np.array([x[:-k] @ x[k:] / denom for k in range(1, lags + 1)])
    q = float(n * (n + 2) * np.sum(rho**2 / (n - np.arange(1, lags + 1))))
    return q, float(chi2.sf(q, lags))


def _abs_corr(a: np.ndarray, b: np.ndarray) -> float:
    a, b = a - a.mean(), b - b.mean()
    den = np.linalg.norm(a) * np.linalg.norm(b)
    return float(abs(a @ b) / den) if den > 0 else 0.0


def diagnose(r: np.ndarray, signals: dict[str, np.ndarray] | None = None) -> list[JointDiagnostics]:
    """Per-joint diagnostics of residual r (n, dof).

    signals: name -> (n, dof) candidate torque columns; a column that is zero on a
    joint (an effect of another joint) is skipped for that joint.
    """
    sigma = noise_sigma(r)
    out = []
    for j in range(r.shape[1]):
        rms = float(np.sqrt(np.mean(r[:, j] ** 2)))
        s = max(float(sigma[j]), 1e-300)
        excess = np.sqrt(max(rms**2 - s**2, 0.0)) / s
        q, p = ljung_box(r[:, j])
        corr = {name: _abs_corr(r[:, j], col[:, j]) for name, col in (signals or {}).items()
                if np.any(col[:, j] != 0) and np.ptp(col[:, j]) > 0}
        out.append(JointDiagnostics(j + 1, rms, float(sigma[j]), float(excess), q, p, corr))
    return out
