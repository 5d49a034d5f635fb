"""pysindy peers tuned like our regression, for a like-for-like comparison.

Each peer's hyper-parameter is swept over a grid and chosen on the same validation blocks
inside the training data as SparseRegression (base.validation_mask), by the same rule:
the sparsest candidate whose validation error is within one paired standard error (or the
relative `tolerance`) of the best. The chosen setting is then refit on all training rows.
As in ours, the data are centred (an unpenalized intercept: the sensor bias) and the columns
scaled to unit std, so coefficients and thresholds are in torque units per column std and
do not depend on the number of rows. PeerRegression is the tuned peer as a Regressor
(regression.base); tune(name, theta, y) fits one.

- STLSQ: `threshold` swept over `n_grid` values, log-spaced over 1e-6..1 x std(y).
- SSR: its elimination path (one coefficient dropped per iteration, max_iter = p - 1) is
  its stopping hyper-parameter; every point of the path is a candidate (this covers every
  `kappa`, which only picks a point of the same path).
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from identification.regression.base import Regressor, standardize, validation_mask

PEERS = ("STLSQ", "SSR")


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


def _stlsq_coef(threshold: float, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """pysindy's STLSQ coefficients (p,) at threshold on x (n, p), y (n,)."""
    import pysindy as ps

    opt = ps.STLSQ(threshold=threshold, alpha=0.0, normalize_columns=False, max_iter=20)
    with warnings.catch_warnings():
        # thresholds above every coefficient are grid points too: pysindy warns, we score them
        warnings.filterwarnings("ignore", "Sparsity parameter is too big", UserWarning)
        return opt.fit(x, y).coef_.ravel()


def _ssr_path(x, y) -> list[np.ndarray]:
    import pysindy as ps

    opt = ps.SSR(alpha=0.0, normalize_columns=False, max_iter=max(x.shape[1] - 1, 1))
    opt.fit(x, y)
    # history_[0] is the array SSR then updates in place (pysindy 2.1): the full fit is redone
    full = np.linalg.lstsq(x, y, rcond=None)[0]
    return [full] + [np.asarray(h).ravel() for h in opt.history_[1:]]


class PeerRegression(Regressor):
    """pysindy's `name` ("STLSQ" or "SSR") tuned on validation blocks inside theta (n, p),
    y (n,). fit sets setting_ (the chosen threshold, torque units per column std, or number
    of terms), coef_ (p,) on the unscaled library columns, intercept_, support_ and seconds_
    (sweep + selection + refit)."""

    def __init__(self, name: str = "STLSQ", n_grid: int = 30, block: int = 50, every: int = 5):
        self.name, self.n_grid, self.block, self.every = name, n_grid, block, every

    @property
    def setting_name(self) -> str:
        return "threshold" if self.name == "STLSQ" else "terms"

    def _fit(self, theta: np.ndarray, y: np.ndarray) -> None:
        if self.name not in PEERS:
            raise ValueError(f"unknown peer {self.name!r}: STLSQ or SSR")
        start = time.perf_counter()
        val = validation_mask(len(y), self.block, self.every)
        xs, yc, *_ = standardize(theta, y, ~val)
        if self.name == "STLSQ":
            grid = y[~val].std() * np.logspace(-6, 0, self.n_grid)
            cands = [(t, _stlsq_coef(t, xs[~val], yc[~val])) for t in grid]
        else:
            cands = [(float(np.count_nonzero(c)), c) for c in _ssr_path(xs[~val], yc[~val])]
        setting, _ = choose(cands, xs[val], yc[val])
        xs, yc, mean_x, mean_y, scale = standardize(theta, y, slice(None))
        if self.name == "STLSQ":
            coef = _stlsq_coef(setting, xs, yc)
        else:
            coef = next(c for c in _ssr_path(xs, yc) if np.count_nonzero(c) <= setting)
        coef = coef / scale
        self.setting_, self.coef_, self.support_ = float(setting), coef, coef != 0
        self.intercept_ = float(mean_y - mean_x @ coef)
        self.seconds_ = time.perf_counter() - start

    # the names the study (harness.paper.studies.paper_identification) reads from tune's result
    coef = property(lambda self: self.coef_)
    intercept = property(lambda self: self.intercept_)
    setting = property(lambda self: self.setting_)
    seconds = property(lambda self: self.seconds_)


def tune(name: str, theta: np.ndarray, y: np.ndarray, n_grid: int = 30, block: int = 50,
         every: int = 5) -> PeerRegression:
    """Tune pysindy's `name` ("STLSQ" or "SSR") on theta (n, p), y (n,) training rows."""
    return PeerRegression(name, n_grid, block, every).fit(theta, y)
