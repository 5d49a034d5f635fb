"""pysindy peers tuned like our regression, for a like-for-like comparison (issue #3, item 4).

Each peer's hyper-parameter is swept over a grid and chosen on the same validation blocks
inside the training data as SparseRegression (sparse.validation_mask), by the same rule:
the sparsest candidate whose validation error is within one paired standard error (or the
relative `tolerance`) of the best. The chosen setting is then refit on all training rows.
As in ours, the data are centred (an unpenalized intercept: the sensor bias) and the columns
scaled to unit std, so coefficients and thresholds are in torque units per column std and
do not depend on the number of rows.

- STLSQ: `threshold` swept over `n_grid` values, log-spaced over 1e-6..1 x std(y).
- SSR: its elimination path (one coefficient dropped per iteration, max_iter = p - 1) is
  its stopping hyper-parameter; every point of the path is a candidate (this covers every
  `kappa`, which only picks a point of the same path).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np

from identification.regression.sparse import validation_mask


@dataclass(frozen=True)
class PeerFit:
    """One tuned peer on one target: chosen setting, coefficients on the raw library."""

    name: str
    setting_name: str  # "threshold" (STLSQ, torque units per column std) or "terms" (SSR)
    setting: float
    coef: np.ndarray  # (p,) on the unscaled library columns
    intercept: float
    seconds: float  # sweep + selection + refit

    def predict(self, theta: np.ndarray, offset: bool = False) -> np.ndarray:
        return theta @ self.coef + (self.intercept if offset else 0.0)


def _standardize(theta, y, rows):
    mean_x, mean_y = theta[rows].mean(0), y[rows].mean()
    scale = theta[rows].std(0)
    scale[scale == 0] = 1.0
    return (theta - mean_x) / scale, y - mean_y, mean_x, mean_y, scale


def choose(candidates, x_val, y_val, tolerance: float = 0.002):
    """(setting, coef) candidates on standardized columns -> the sparsest within one paired
    standard error of the best validation MSE (ties: the lower MSE)."""
    sq = [(y_val - x_val @ c) ** 2 for _, c in candidates]
    best = int(np.argmin([s.mean() for s in sq]))
    floor = 1e-14 * float(np.mean(y_val**2))  # exact data: round-off is no evidence
    good = []
    for k, s in enumerate(sq):
        d = s - sq[best]
        if d.mean() <= max(d.std() / np.sqrt(len(d)), tolerance * sq[best].mean()) + floor:
            good.append((int(np.count_nonzero(candidates[k][1])), s.mean(), k))
    return candidates[min(good)[2]]


def _stlsq(threshold: float):
    import pysindy as ps

    # thresholds above every coefficient are grid points too: pysindy warns, we just score them
    warnings.filterwarnings("ignore", "Sparsity parameter is too big", UserWarning)
    return ps.STLSQ(threshold=threshold, alpha=0.0, normalize_columns=False, max_iter=20)


def _ssr_path(x, y) -> list[np.ndarray]:
    import pysindy as ps

    opt = ps.SSR(alpha=0.0, normalize_columns=False, max_iter=max(x.shape[1] - 1, 1))
    opt.fit(x, y)
    # history_[0] is the array SSR then updates in place (pysindy 2.1): the full fit is redone
    full = np.linalg.lstsq(x, y, rcond=None)[0]
    return [full] + [np.asarray(h).ravel() for h in opt.history_[1:]]


def tune(name: str, theta: np.ndarray, y: np.ndarray, n_grid: int = 30, block: int = 50,
         every: int = 5) -> PeerFit:
    """Tune pysindy's `name` ("STLSQ" or "SSR") on theta (n, p), y (n,) training rows."""
    start = time.perf_counter()
    theta, y = np.asarray(theta, float), np.asarray(y, float)
    val = validation_mask(len(y), block, every)
    xs, yc, *_ = _standardize(theta, y, ~val)
    if name == "STLSQ":
        grid = y[~val].std() * np.logspace(-6, 0, n_grid)
        cands = [(t, _stlsq(t).fit(xs[~val], yc[~val]).coef_.ravel()) for t in grid]
    elif name == "SSR":
        cands = [(float(np.count_nonzero(c)), c) for c in _ssr_path(xs[~val], yc[~val])]
    else:
        raise ValueError(f"unknown peer {name!r}: STLSQ or SSR")
    setting, _ = choose(cands, xs[val], yc[val])
    xs, yc, mean_x, mean_y, scale = _standardize(theta, y, slice(None))
    if name == "STLSQ":
        coef = _stlsq(setting).fit(xs, yc).coef_.ravel()
    else:
        coef = next(c for c in _ssr_path(xs, yc) if np.count_nonzero(c) <= setting)
    coef = coef / scale
    return PeerFit(name, "threshold" if name == "STLSQ" else "terms", float(setting), coef,
                   float(mean_y - mean_x @ coef), time.perf_counter() - start)
