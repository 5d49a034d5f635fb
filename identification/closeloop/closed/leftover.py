"""What the named effects leave on held-out runs, per joint: said, not forced onto a name.

A joint is unexplained when its held-out residual stays above its sensor noise by more
than LEFT noise sigmas RMS (the noise from second differences of the residual, run by run,
identification.closeloop.selection.residual.noise_sigma): structure the catalogue does not span.
What is left is described by its correlation with the joint's position, velocity and the
time within its run (a drift). A sensor offset is a property of a run, not of the robot:
the residual's shape is described about each run's own mean (the scores take the offset
from samples they do not count: identification.closeloop.closed.offsets).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.closeloop.selection.residual import noise_sigma

LEFT = 1.0  # noise sigmas RMS of structure left: twice the noise's power
ROUNDING = 1e-9  # of the joint's torque RMS: a residual below it is rounding, not structure


@dataclass(frozen=True)
class Leftover:
    """Per joint (dof,): held-out residual RMS and noise (N m), structure (noise sigmas),
    correlation of the residual with q, qd and the time within its run."""

    rms: np.ndarray
    noise: np.ndarray
    structure: np.ndarray
    corr_q: np.ndarray
    corr_qd: np.ndarray
    corr_time: np.ndarray

    @property
    def unexplained_joints(self) -> tuple[int, ...]:
        return tuple(int(j) + 1 for j in np.flatnonzero(self.structure > LEFT))

    def to_json(self) -> list[dict]:
        unexplained = set(self.unexplained_joints)
        return [{"joint": j + 1, "unexplained": j + 1 in unexplained,
                 "residual_rms": float(self.rms[j]), "noise_sigma": float(self.noise[j]),
                 "structure_sigmas": float(self.structure[j]),
                 "correlation": {"position": float(self.corr_q[j]),
                                 "velocity": float(self.corr_qd[j]),
                                 "time": float(self.corr_time[j])}}
                for j in range(len(self.rms))]


def _corr(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    a, b = a - a.mean(axis=0), b - b.mean(axis=0)
    den = np.sqrt(np.sum(a**2, axis=0) * np.sum(b**2, axis=0))
    return np.where(den > 0, np.sum(a * b, axis=0) / np.maximum(den, 1e-300), 0.0)


def leftover(model, runs: list[tuple[np.ndarray, ...]]) -> Leftover:
    """The residual of model on runs [(q, qd, qdd, tau)] (held out), per joint, about each
    run's own mean."""
    residuals = [r[3] - model.torque(r[0], r[1], r[2]) for r in runs]
    residuals = [r - r.mean(axis=0) for r in residuals]
    res = np.concatenate(residuals)
    lengths = np.array([len(r) for r in residuals], float)
    noise = np.sqrt(np.sum([n * noise_sigma(r) ** 2 for n, r in zip(lengths, residuals,
                                                                    strict=True)], axis=0)
                    / lengths.sum())
    rms = np.sqrt(np.mean(res**2, axis=0))
    tau_rms = np.sqrt(np.mean(np.concatenate([r[3] for r in runs]) ** 2, axis=0))
    noise = np.maximum(noise, ROUNDING * tau_rms)  # a noise-free run: no rounding "structure"
    structure = np.sqrt(np.maximum(rms**2 - noise**2, 0.0)) / np.maximum(noise, 1e-300)
    time = np.concatenate([np.linspace(0.0, 1.0, len(r)) for r in residuals])[:, None]
    q, qd = (np.concatenate([r[i] for r in runs]) for i in (0, 1))
    return Leftover(rms, noise, structure, _corr(res, q), _corr(res, qd),
                    _corr(res, np.broadcast_to(time, res.shape)))
