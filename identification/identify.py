"""Identify a torque model from data: the one front door (validate, split, fit, score).

`identify(q, qd, qdd, tau, library, holdout, tau_clean, regressor)` fits the regressor
(identification.regression.torque: per joint, coupled, jointwise, on base atoms, physically
consistent) on the first 1 - holdout of the samples and scores it on the rest, in time order;
relative RMS error is ||tau_hat - tau_clean|| / ||tau_clean|| per joint there (tau when no
clean torque is given), each held-out run with its sensor offset by the rule of
identification.closeloop.closed.offsets (held_out_offset) on a measured log. The regression target
is the raw measured torque, not a denoised one: denoising only correlates the residuals
(docs/identification.md, 'identification.identify'). Without a regressor,
identification.choice picks the library's default (coupled when the library has atoms).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import numpy as np
from threadpoolctl import threadpool_limits

from identification.choice import choose_regressor
from identification.closeloop.closed.offsets import (
    RULE,
    ScoredRun,
    held_out_offset,
    run_tail,
    scored_torques,
    whole_run,
)
from identification.errors import IdentificationError
from identification.library.base import Conditioning
from identification.metrics import HELD_OUT, error_measure, error_reference, rel_error
from identification.parameter_intervals import parameter_intervals
from identification.regression.base import validation_mask
from identification.regression.coupled import AtomBasis
from identification.regression.torque import TorqueRegressor
from identification.torque_model import TorqueModel


@dataclass(frozen=True)
class Identification:
    """A fitted model and how well it does on the held-out part."""

    model: TorqueModel  # with per-joint `offsets` (N m)
    heldout_rel_rmse: np.ndarray  # (dof,); NaN when holdout is 0 (no held-out part)
    heldout_mse: np.ndarray  # (dof,) N^2 m^2; NaN when holdout is 0
    conditioning: Conditioning
    seconds: float
    regressions: tuple = field(default=(), repr=False)  # SparseRegression per joint, or
    # one CoupledRegression
    method: str = "per-joint"
    basis: AtomBasis | None = field(default=None, repr=False)  # coupled: the atoms
    physical: dict = field(default_factory=dict)  # consistent: prior, weight, consistency
    scored: tuple = field(default=(), repr=False)  # ScoredRun per held-out run (a measured log)
    trained: tuple = field(default=(), repr=False)  # each training run's trained samples
    reference: str = "measured"  # the held-out errors' (identification.metrics.REFERENCES)
    intervals: dict = field(default_factory=dict)  # the printed readings' 95 % intervals
    # (identification.parameter_intervals; empty when not asked for)

    def metrics(self) -> dict:
        """JSON metrics; the held-out errors are null when nothing was held out (holdout 0)."""
        out = {"method": self.method,
               "heldout_rel_rmse": _nullable(self.heldout_rel_rmse),
               "heldout_mse": _nullable(self.heldout_mse),
               "error_measure": error_measure(self.reference, HELD_OUT),
               "library_size": self.conditioning.size,
               "library_rank": self.conditioning.rank,
               "library_condition": self.conditioning.condition,
               "alpha": [r.alpha_ for r in self.regressions],
               "pass_rate": [r.pass_rate_ for r in self.regressions],
               "seconds": self.seconds}
        if self.method == "coupled":
            out["noise_sigma"] = self.regressions[0].sigma_.tolist()
            if hasattr(self.regressions[0], "structure_"):  # held to the rigid-body structure
                out["rigid_body"] = self.regressions[0].structure_
        if self.scored:  # a measured log: each held-out run's offset and where it came from
            out["heldout_runs"] = [r.to_json(self.model) for r in self.scored]
        if self.physical:
            # the nominal and the ellipsoids are in MODEL.json's bodies
            out["physical"] = {k: v for k, v in self.physical.items()
                               if k not in ("nominal", "ellipsoids")}
        return out

    def sensor_offsets(self) -> dict:
        """MODEL.json's sensor_offsets: the offset a run the model was not trained on is
        scored with (held_out_offset: `predict` reads it), each training run's and each
        held-out run's (N m per joint), and the rule."""
        model = self.model
        return {"new_run": held_out_offset(model, list(self.trained)).tolist(),
                "training": [held_out_offset(model, [r]).tolist() for r in self.trained],
                "heldout": [r.offset(model).tolist() for r in self.scored], "rule": RULE}

    def lagrangian(self) -> dict:
        """Coupled method: the identified Lagrangian {atoms, coefficients, base/folded atoms}."""
        if self.method != "coupled":
            return {}
        reg, names = self.regressions[0], self.basis.names
        kept = np.flatnonzero(reg.support_)
        return {"atoms": [names[k] for k in kept], "coefficients": reg.coef_[kept].tolist(),
                "candidate_atoms": len(names), "base_atoms": len(reg.base_),
                "folded_atoms": [names[k] for k in reg.folded_]}


def _nullable(x: np.ndarray) -> list:
    return [None if np.isnan(v) else float(v) for v in x]


def check_data(q, qd, qdd, tau, n_features: int) -> tuple[np.ndarray, ...]:
    """Arrays as float (n, dof), enough of them and excited; IdentificationError with one
    clear line otherwise."""
    arrays = as_arrays(q, qd, qdd, tau)
    check_excited(arrays, n_features)
    return arrays


def as_arrays(q, qd, qdd, tau) -> tuple[np.ndarray, ...]:
    """Arrays as float (n, dof) of one shape, finite; IdentificationError otherwise."""
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
    return tuple(arrays)


def check_excited(arrays: tuple[np.ndarray, ...], n_features: int) -> None:
    """IdentificationError unless (q, qd, qdd, tau) have more samples than features, every
    joint moves and every torque varies."""
    n, dof = arrays[0].shape
    if n <= n_features:
        raise IdentificationError(f"{n} training samples for {n_features} library features: "
                                  "need more samples than features")
    for j in range(dof):
        if np.ptp(arrays[3][:, j]) == 0:
            raise IdentificationError(f"torque of joint {j + 1} is constant: nothing to identify")
        if np.ptp(arrays[0][:, j]) == 0:
            raise IdentificationError(f"joint {j + 1} does not move (q{j + 1} constant): not excited")


def _score(pred, truth) -> tuple[np.ndarray, np.ndarray]:
    return rel_error(pred, truth), np.mean((pred - truth) ** 2, axis=0)


def identify(q, qd, qdd, tau, library, holdout: float = 0.25, tau_clean=None,
             regressor: TorqueRegressor | None = None, method: str | None = None,
             runs=None, interval_blocks: int = 0) -> Identification:
    """Fit `regressor` (by default the library's, identification.choice.choose_regressor with
    `method`) on the first 1 - holdout of the samples, score on the rest.

    holdout 0 fits on all samples (closed-loop re-identification) and scores nothing: the
    held-out errors are NaN, never a training-data error under a held-out name. runs: (n,)
    labels of the runs the samples come from (several logs): each run fitted with its own
    sensor offset where the regressor can (per_run_offsets), warned where it cannot.
    interval_blocks > 0: each printed reading's 95 % interval, the fit redone without each of
    that many contiguous blocks of every training run (identification.parameter_intervals)."""
    regressor = choose_regressor(library, method) if regressor is None else regressor
    n_features = regressor.min_samples(library)
    # thousands of rows by tens of columns: one BLAS thread is faster (no thread contention;
    # docs/identification.md, 'identification.identify')
    with threadpool_limits(limits=1, user_api="blas"):
        q, qd, qdd, tau, n = split_training(q, qd, qdd, tau, library.dof, library.name, holdout,
                                            n_features)
        start = time.perf_counter()
        fit = regressor.fit(library, q[:n], qd[:n], qdd[:n], tau[:n], **_runs(regressor, runs, n))
        seconds = time.perf_counter() - start
        trained, scored = split_runs((q, qd, qdd, tau), n, runs)
        rel, mse = heldout_errors(fit.model, q, qd, qdd, tau, tau_clean, n, scored)
        intervals = (parameter_intervals(regressor, library, q[:n], qd[:n], qdd[:n], tau[:n],
                                         fit, None if runs is None else np.asarray(runs)[:n],
                                         interval_blocks) if interval_blocks else {})
    return Identification(fit.model, rel, mse, fit.conditioning, seconds, fit.regressions,
                          fit.method, fit.basis, fit.physical,
                          tuple(scored) if tau_clean is None else (), tuple(trained),
                          error_reference(tau_clean is not None), intervals)


def _runs(regressor, runs, n: int) -> dict:
    """fit's runs keyword for the first n samples: none for a single run."""
    if runs is None or len(np.unique(np.asarray(runs)[:n])) < 2:
        return {}
    if getattr(regressor, "per_run_offsets", False):
        return {"runs": np.asarray(runs)[:n]}
    warnings.warn("several runs fitted with one sensor offset per joint (this regressor has "
                  "no offset per run: use the kinematic library or --prior nominal)",
                  RuntimeWarning, stacklevel=3)
    return {}


def split_training(q, qd, qdd, tau, dof: int, name: str, holdout: float, n_features: int):
    """Validated arrays and the number of training samples (the first 1 - holdout)."""
    if not 0.0 <= holdout < 1.0:
        raise IdentificationError(f"holdout must be in [0, 1), got {holdout}")
    q, qd, qdd, tau = as_arrays(q, qd, qdd, tau)
    if q.shape[1] != dof:
        raise IdentificationError(f"data has {q.shape[1]} joints, library {name} has {dof}")
    n_train = int(round(len(q) * (1 - holdout)))
    if holdout > 0 and n_train >= len(q):
        raise IdentificationError(f"holdout {holdout} of {len(q)} samples leaves no held-out sample")
    check_excited((q[:n_train], qd[:n_train], qdd[:n_train], tau[:n_train]), n_features)
    if not validation_mask(n_train).any():  # the selection scores alpha on validation blocks
        raise IdentificationError(f"{n_train} training samples are too few: the selection "
                                  "validates on every 5th block of 50 samples (needs more than 200)")
    return q, qd, qdd, tau, n_train


def split_runs(samples: tuple, n_train: int, runs=None) -> tuple[list[tuple], list[ScoredRun]]:
    """The training runs' samples (q, qd, qdd, tau) (each run's part among the first n_train)
    and the held-out runs, in order, each with its offset by the rule
    (identification.closeloop.closed.offsets): a held-out part of a run trained on from that run's
    trained samples, a run never trained on from every training run's."""
    labels = np.zeros(len(samples[0]), int) if runs is None else np.asarray(runs)
    trained_part = np.arange(len(labels)) < n_train
    trained = {k: tuple(a[trained_part & (labels == k)] for a in samples)
               for k in dict.fromkeys(labels[:n_train].tolist())}
    scored = []
    for k in dict.fromkeys(labels[n_train:].tolist()):
        held = tuple(a[~trained_part & (labels == k)] for a in samples)
        scored.append(run_tail(trained[k], held) if k in trained
                      else whole_run(held, list(trained.values())))
    return list(trained.values()), scored


def heldout_errors(model, q, qd, qdd, tau, tau_clean, n_train: int,
                   scored: list[ScoredRun] | None = None):
    """Held-out errors against the clean torque, or, without one (a measured log), against
    the measured torque, which carries the sensor offsets: the model's torque plus each
    held-out run's offset (scored: split_runs' runs; None: the held-out part one run) is
    then what predicts the measurement."""
    if n_train >= len(q):
        nan = np.full(q.shape[1], np.nan)  # holdout 0 (a final fit on all data): no held-out error
        return nan, nan
    if tau_clean is not None:
        truth = as_arrays(q, qd, qdd, tau_clean)[3][n_train:]
        return _score(model.torque(q[n_train:], qd[n_train:], qdd[n_train:]), truth)
    if scored is None:
        scored = split_runs((q, qd, qdd, tau), n_train)[1]
    return _score(*scored_torques(model, scored))
