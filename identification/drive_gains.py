"""Joint drive gains identified with the dynamics, from an unloaded and a loaded run.

A log of motor currents i (A) measures the torque up to each joint's drive gain K_j
(N m/A): tau_j = K_j i_j. The rigid-body torque is linear in the inertial parameters, so
every joint's equation is homogeneous in (parameters, friction, K): without more, the gains
and the dynamics are known only up to one common scale. A second run carrying a load of
known mass M on the last body fixes it (Gautier & Briot 2014, 'Global identification of
joint drive gains and dynamic parameters of robots', J. Dyn. Sys., Meas., Control 136(5)):

    unloaded run:  Y_U beta + A_U a + F_U phi_U                      - diag(i_U) K = 0
    loaded run:    Y_L beta + A_L a + F_L phi_L + Y_L,last[1:] theta - diag(i_L) K
                                                                     = -Y_L,last[m] M

with Y Pinocchio's joint-torque regressor (10 standard parameters per body, shared by both
runs), A the rotor armature (qdd_j, shared), F each run's friction (viscous qd_j, Coulomb
qd_j / sqrt(qd_j^2 + w^2)) and offset (1) per joint, theta the load's first moments and
rotational inertia about the last joint's origin (9, Pinocchio's toDynamicParameters order
after the mass) and M its known mass. Only the base columns of the known part enter
(pivoted QR, identification.regression.oracle.base_columns): the bodies' parameters need
not be identifiable, the gains are when the load moves every joint's torque.

Each joint's rows are weighted by 1 / its residual's std (first pass: 1 / std of its
current). The currents' noise sits in the gains' columns (errors in variables) and only the
load's part of the torque ties their scale, so least squares shrinks every gain, by 14-48 %
at 5 % noise (UR5, Panda). Two weighted least-squares passes are therefore followed by
instrumental-variable passes, the instruments the currents the previous pass predicts
(correlated with the currents, not with their noise): within ~1 % (docs/data.md, 'Motor
currents').
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.errors import IdentificationError
from identification.library.kinematic import COULOMB_WIDTH
from identification.regression.oracle import base_columns

ITERATIONS = 3  # weighted passes (the weights from the previous pass's residual)
BASE_ROWS = 300  # instants of each run the base columns are found on
UNIDENTIFIED = 0.2  # a gain whose standard error exceeds this fraction of it is not identified


@dataclass(frozen=True)
class DriveGainFit:
    """Gains (dof,) N m/A with their standard errors, the load's 10 parameters (mass first,
    in the last joint's frame; zero where not identifiable), each joint's residual std (N m)
    and the number of unknowns solved for (base columns and gains)."""

    gains: np.ndarray
    gain_std: np.ndarray
    load: np.ndarray
    sigma: np.ndarray
    columns: int


def _friction(qd: np.ndarray) -> np.ndarray:
    """(n, dof, 3 dof): viscous, Coulomb and offset columns of every joint."""
    n, dof = qd.shape
    out = np.zeros((n, dof, 3 * dof))
    j = np.arange(dof)
    out[:, j, j] = qd
    out[:, j, dof + j] = qd / np.sqrt(qd**2 + COULOMB_WIDTH**2)
    out[:, j, 2 * dof + j] = 1.0
    return out


def _diag(x: np.ndarray) -> np.ndarray:
    """(n, dof, dof) with x (n, dof) on each sample's diagonal."""
    out = np.zeros(x.shape + (x.shape[1],))
    j = np.arange(x.shape[1])
    out[:, j, j] = x
    return out


def _check(runs, mass: float) -> int:
    if not np.isfinite(mass) or mass <= 0:
        raise IdentificationError(f"the load's mass must be a positive number of kg, got {mass:g}")
    dof = runs[0][1].shape[1]
    shapes = [(r[0].shape[1], *(x.shape[1] for x in r[1:])) for r in runs]
    if any(d != dof for shape in shapes for d in shape):
        raise IdentificationError("the unloaded and loaded runs differ in their joints: "
                                  f"{shapes[0][0]} and {shapes[1][0]}")
    if runs[0][0].shape[2] != runs[1][0].shape[2] or runs[0][0].shape[2] < 10:
        raise IdentificationError("the runs' regressors differ in their parameters")
    return dof


def identify_drive_gains(unloaded, loaded, mass: float, instrumental: bool = True,
                         rtol: float = 1e-8, body: int = 0) -> DriveGainFit:
    """The drive gains of every joint from two runs, each (Y, qd, qdd, current): Y (n, dof, p)
    the joint-torque regressor, 10 columns per body, qd, qdd (n, dof), current (n, dof) in A;
    mass: the load's (kg) on the loaded run's body moved by joint `body` (1..dof; 0: the
    last); instrumental False: weighted least squares only (biased by the currents' noise,
    kept to measure it). IdentificationError when a gain is not identified by these runs."""
    dof = _check((unloaded, loaded), float(mass))
    p = unloaded[0].shape[2]
    end = p - 10 * (dof - body if body else 0)  # just past the load's body's columns
    blocks, rhs = [], []
    for run, (Y, qd, qdd, _) in enumerate((unloaded, loaded)):
        n = len(qd)
        per_run = np.zeros((n, dof, 2 * 3 * dof))
        per_run[:, :, run * 3 * dof:(run + 1) * 3 * dof] = _friction(qd)
        load = Y[:, :, end - 9:end] if run == 1 else np.zeros((n, dof, 9))
        blocks.append(np.concatenate([Y, _diag(qdd), per_run, load], axis=2))
        rhs.append(-mass * Y[:, :, end - 10] if run == 1 else np.zeros((n, dof)))
    known, target = np.concatenate(blocks), np.concatenate(rhs)  # (N, dof, k), (N, dof)
    current = np.concatenate([unloaded[3], loaded[3]])
    scale = current.std(axis=0)
    if np.any(scale == 0):
        raise IdentificationError(f"joint {int(np.argmin(scale)) + 1}'s current never changes: "
                                  "its gain cannot be identified")
    # the base columns are structural: found on a few hundred instants of each run
    rows = np.concatenate([np.linspace(0, len(unloaded[1]) - 1, BASE_ROWS).astype(int),
                           len(unloaded[1]) + np.linspace(0, len(loaded[1]) - 1, BASE_ROWS).astype(int)])
    base = base_columns(known[rows], rtol)
    normal = _Normal(known[:, :, base], current, target)
    sigma, sol = scale, None
    for step in range(2 + ITERATIONS):  # two weighted least-squares passes, then IV passes
        # IV: the instruments are the currents the last pass predicts (correlated with the
        # currents, not with their noise)
        instrument = current if step < 2 or not instrumental else normal.predicted(sol)
        sol, cov = normal.solve(instrument, 1.0 / sigma)
        sigma = np.maximum(normal.residual_std(sol), 1e-12 * scale)
        _positive(sol[-dof:])
    gains, std = sol[-dof:], np.sqrt(np.diag(cov)[-dof:])
    load_at = p + dof + 6 * dof
    load = np.zeros(10)
    load[0] = mass
    for i, c in enumerate(base):
        if load_at <= c < load_at + 9:
            load[1 + c - load_at] = sol[i]
    lost = np.flatnonzero(std > UNIDENTIFIED * gains)
    if len(lost):
        raise IdentificationError(
            "the drive gains of joint(s) " + ", ".join(str(j + 1) for j in lost) + " are not "
            f"identified by these runs (standard error over {UNIDENTIFIED:.0%} of the gain): the "
            "load must change every joint's torque (excite more, or put it off the last axis)")
    return DriveGainFit(gains, std, load, sigma, len(base) + dof)


def _positive(gains: np.ndarray) -> None:
    if np.any(gains <= 0):
        bad = int(np.argmin(gains)) + 1
        raise IdentificationError(f"joint {bad}'s identified gain is {gains[bad - 1]:.3g} N m/A, "
                                  "not positive: the currents' sign or the load's mass is wrong, "
                                  "or the runs do not excite that joint")


class _Normal:
    """The normal equations of known x - diag(current) K = target, kept per joint: joint j's
    rows are weighted alike and its gain's column is non-zero on its rows only, so each pass
    (new weights, new instruments) costs O(N k) instead of O(N k^2)."""

    def __init__(self, known: np.ndarray, current: np.ndarray, target: np.ndarray):
        self.known, self.current, self.target = known, current, target
        self.dof, self.kb = current.shape[1], known.shape[2]
        cols = [np.ascontiguousarray(known[:, j, :]) for j in range(self.dof)]
        self.cols = cols
        self.gram = np.stack([c.T @ c for c in cols])  # (dof, kb, kb)
        self.cross_t = np.stack([c.T @ target[:, j] for j, c in enumerate(cols)])
        self.cross_i = np.stack([c.T @ current[:, j] for j, c in enumerate(cols)])

    def predicted(self, sol: np.ndarray) -> np.ndarray:
        """(N, dof) the currents sol predicts: (known x - target) / K."""
        return (self.known @ sol[:self.kb] - self.target) / sol[self.kb:]

    def residual_std(self, sol: np.ndarray) -> np.ndarray:
        """(dof,) std over the samples of each joint's residual (N m)."""
        resid = self.target - self.known @ sol[:self.kb] + self.current * sol[self.kb:]
        return resid.std(axis=0)

    def _blocks(self, left: np.ndarray, right: np.ndarray, w2: np.ndarray) -> np.ndarray:
        """sum_j w_j^2 L_j' R_j with L_j = [known_j, -left_j e_j'] (R_j alike with right)."""
        kb, dof = self.kb, self.dof
        out = np.zeros((kb + dof, kb + dof))
        out[:kb, :kb] = np.tensordot(w2, self.gram, axes=1)
        for j, c in enumerate(self.cols):
            out[:kb, kb + j] = -w2[j] * (self.cross_i[j] if right is self.current else c.T @ right[:, j])
            out[kb + j, :kb] = -w2[j] * (self.cross_i[j] if left is self.current else c.T @ left[:, j])
            out[kb + j, kb + j] = w2[j] * left[:, j] @ right[:, j]
        return out

    def solve(self, instrument: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The instrumental-variable solution (instrument = current: weighted least squares),
        rows of joint j weighted by w_j, and its covariance."""
        w2 = w**2
        za = self._blocks(instrument, self.current, w2)
        zz = self._blocks(instrument, instrument, w2)
        zb = np.concatenate([np.tensordot(w2, self.cross_t, axes=1),
                             -w2 * np.einsum("nj,nj->j", instrument, self.target)])
        d = 1.0 / np.sqrt(np.maximum(np.diag(self._blocks(self.current, self.current, w2)),
                                     1e-300))
        x = d * np.linalg.lstsq(za * np.outer(d, d), d * zb, rcond=None)[0]
        resid = (self.target - self.known @ x[:self.kb] + self.current * x[self.kb:]) * w
        dof_left = max(resid.size - len(x), 1)
        inv = np.linalg.pinv(za * np.outer(d, d))
        cov = (inv @ (zz * np.outer(d, d)) @ inv.T) * np.outer(d, d) * float(np.sum(resid**2)) / dof_left
        return x, cov
