"""Identify a torque model from data: validate, split, condition, regress, score.

The held-out part is the last `holdout` fraction in time order; relative RMS
error is ||tau_hat - tau_clean|| / ||tau_clean|| per joint on it (tau when no
clean torque is given). The regression target is the raw measured torque:
denoising is reported separately (it did not help selection, see the bench).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from identification.errors import IdentificationError
from identification.library import Conditioning, Library, conditioning, warn_if_rank_deficient
from identification.model import IdentifiedModel, JointModel
from identification.sparse import SparseRegression


@dataclass(frozen=True)
class Identification:
    """A fitted model and how well it does on the held-out part."""

    model: IdentifiedModel
    heldout_rel_rmse: np.ndarray  # (dof,)
    heldout_mse: np.ndarray  # (dof,) N^2 m^2
    conditioning: Conditioning
    seconds: float
    regressions: tuple = field(default=(), repr=False)  # fitted SparseRegression per joint

    def metrics(self) -> dict:
        return {"heldout_rel_rmse": self.heldout_rel_rmse.tolist(),
                "heldout_mse": self.heldout_mse.tolist(),
                "library_size": self.conditioning.size,
                "library_rank": self.conditioning.rank,
                "library_condition": self.conditioning.condition,
                "alpha": [r.alpha_ for r in self.regressions],
                "pass_rate": [r.pass_rate_ for r in self.regressions],
                "seconds": self.seconds}


def check_data(q, qd, qdd, tau, n_features: int) -> tuple[np.ndarray, ...]:
    """Arrays as float (n, dof); IdentificationError with one clear line otherwise."""
    arrays = []
    for name, x in (("q", q), ("qd", qd), ("qdd", qdd), ("tau", tau)):
        x = np.asarray(x, dtype=float)
        if x.ndim == 1:
            x = x[:, None]
        if x.ndim != 2:
            raise IdentificationError(f"{name} must be a 2-D array (samples, dof), got shape {x.shape}")
        if not np.all(np.isfinite(x)):
            raise IdentificationError(f"{name} contains NaN or inf")
        arrays.append(x)
    if len({a.shape for a in arrays}) != 1:
        shapes = ", ".join(f"{n}{a.shape}" for n, a in zip(("q", "qd", "qdd", "tau"), arrays, strict=True))
        raise IdentificationError(f"shape mismatch: {shapes}")
    n, dof = arrays[0].shape
    if n <= n_features:
        raise IdentificationError(f"{n} training samples for {n_features} library features: need more samples than features")
    for j in range(dof):
        if np.ptp(arrays[3][:, j]) == 0:
            raise IdentificationError(f"torque of joint {j + 1} is constant: nothing to identify")
        if np.ptp(arrays[0][:, j]) == 0:
            raise IdentificationError(f"joint {j + 1} does not move (q{j + 1} constant): not excited")
    return tuple(arrays)


def _score(model, q, qd, qdd, truth) -> tuple[np.ndarray, np.ndarray]:
    err = model.torque(q, qd, qdd) - truth
    return np.linalg.norm(err, axis=0) / np.linalg.norm(truth, axis=0), np.mean(err**2, axis=0)


def identify(q, qd, qdd, tau, library: Library, holdout: float = 0.25, tau_clean=None,
             regression: SparseRegression | None = None) -> Identification:
    """Fit every joint's torque on the first 1 - holdout of the samples, score on the rest."""
    if not 0.0 <= holdout < 1.0:
        raise IdentificationError(f"holdout must be in [0, 1), got {holdout}")
    q, qd, qdd, tau = check_data(q, qd, qdd, tau, 0)
    if q.shape[1] != library.dof:
        raise IdentificationError(f"data has {q.shape[1]} joints, library {library.name} has {library.dof}")
    n_train = int(round(len(q) * (1 - holdout)))
    check_data(q[:n_train], qd[:n_train], qdd[:n_train], tau[:n_train], len(library))
    start = time.perf_counter()
    theta = library.evaluate(q, qd, qdd)
    cond = conditioning(theta[:n_train], library.names)
    warn_if_rank_deficient(cond)
    joints, fits = [], []
    for j in range(library.dof):
        reg = SparseRegression(**(regression.__dict__ if regression else {}))
        reg.fit(theta[:n_train], tau[:n_train, j])
        kept = np.flatnonzero(reg.support_)
        joints.append(JointModel(tuple(library.names[k] for k in kept),
                                 tuple(float(reg.coef_[k]) for k in kept), reg.intercept_))
        fits.append(reg)
    seconds = time.perf_counter() - start
    model = IdentifiedModel(library.dof, tuple(joints), library.name)
    truth = tau if tau_clean is None else check_data(q, qd, qdd, tau_clean, 0)[3]
    rows = slice(n_train, None) if n_train < len(q) else slice(None)
    rel, mse = _score(model, q[rows], qd[rows], qdd[rows], truth[rows])
    return Identification(model, rel, mse, cond, seconds, tuple(fits))
