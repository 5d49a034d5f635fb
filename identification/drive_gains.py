"""Joint drive gains identified with the dynamics, from unloaded and loaded runs.

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

Several unloaded and loaded runs enter one system (each run its friction and offset, the
load's parameters shared by the loaded runs). The white-noise standard errors understate a
real log's spread (its residual is coloured by what the model lacks), so each
gain's 95 % interval comes from a delete-one-block jackknife over every run
(identification.intervals); the deleted blocks' currents, predicted by the fits without them,
give a held-out error that chooses the body the load rides on (harness.identify.drive_gains).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.errors import IdentificationError
from identification.intervals import half_width, time_blocks
from identification.library.kinematic import COULOMB_WIDTH
from identification.regression.gain_normal import GainNormal, gram
from identification.regression.oracle import base_columns

ITERATIONS = 3  # weighted passes (the weights from the previous pass's residual)
BASE_ROWS = 300  # instants of each run the base columns are found on
UNIDENTIFIED = 0.2  # a gain whose standard error exceeds this fraction of it is not identified
# the jackknife's blocks per run: fewer and longer than the loop's (identification.intervals
# BLOCKS = 8), since a term the model lacks colours the gains' residual over longer times;
# on 10 development draws of the study's coupled UR5 (seed 100, none scored), 3-4 blocks per
# run covered the true gains in 8-10 of 10 per joint, 8 in 7-9, 16 in 7-10
GAIN_BLOCKS = 4

Run = tuple  # (Y (n, dof, p), qd (n, dof), qdd (n, dof), current (n, dof))


@dataclass(frozen=True)
class DriveGainFit:
    """Gains (dof,) N m/A with their white-noise standard errors and their 95 % intervals
    (half-widths, identification.intervals: a delete-one-block jackknife over every run;
    NaN when not computed), the load's 10 parameters (mass first, in its body's joint frame;
    zero where not identifiable), each joint's residual std (N m), the number of unknowns
    solved for (base columns and gains) and the held-out error: the power of the deleted
    blocks' currents as the fits without them predict them, each joint in units of its
    current's std (inf when a fold's fit failed; NaN when not computed)."""

    gains: np.ndarray
    gain_std: np.ndarray
    load: np.ndarray
    sigma: np.ndarray
    columns: int
    interval: np.ndarray
    heldout: float


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


def _as_runs(runs) -> list:
    """One run (a tuple of 4 arrays) or a list of runs, as a list of runs."""
    return [runs] if isinstance(runs[0], np.ndarray) else list(runs)


def _check(unloaded: list, loaded: list, mass: float) -> int:
    if not np.isfinite(mass) or mass <= 0:
        raise IdentificationError(f"the load's mass must be a positive number of kg, got {mass:g}")
    if not unloaded or not loaded:
        raise IdentificationError("the drive gains need an unloaded and a loaded run")
    runs = unloaded + loaded
    dof = runs[0][1].shape[1]
    shapes = [(r[0].shape[1], *(x.shape[1] for x in r[1:])) for r in runs]
    if any(d != dof for shape in shapes for d in shape):
        raise IdentificationError("the unloaded and loaded runs differ in their joints: "
                                  + ", ".join(str(s[0]) for s in shapes))
    params = {r[0].shape[2] for r in runs}
    if len(params) != 1 or min(params) < 10:
        raise IdentificationError("the runs' regressors differ in their parameters")
    return dof


class _System:
    """known x - diag(current) K = target over every run's samples: the base columns of
    [Y, armature, each run's friction and offset, the load's 9 parameters on the loaded runs],
    the target -M Y_mass on the loaded runs; runs: each run's sample indices."""

    def __init__(self, unloaded: list, loaded: list, mass: float, body: int, rtol: float):
        dof = _check(unloaded, loaded, mass)
        every = unloaded + loaded
        p = every[0][0].shape[2]
        end = p - 10 * (dof - body if body else 0)  # just past the load's body's columns
        friction = 3 * dof * len(every)
        blocks, rhs, runs, at = [], [], [], 0
        for r, (Y, qd, qdd, _) in enumerate(every):
            n = len(qd)
            per_run = np.zeros((n, dof, friction))
            per_run[:, :, 3 * dof * r:3 * dof * (r + 1)] = _friction(qd)
            is_loaded = r >= len(unloaded)
            load = Y[:, :, end - 9:end] if is_loaded else np.zeros((n, dof, 9))
            blocks.append(np.concatenate([Y, _diag(qdd), per_run, load], axis=2))
            rhs.append(-mass * Y[:, :, end - 10] if is_loaded else np.zeros((n, dof)))
            runs.append(np.arange(at, at + n))
            at += n
        known = np.concatenate(blocks)  # (N, dof, k)
        self.target = np.concatenate(rhs)  # (N, dof)
        self.current = np.concatenate([r[3] for r in every])
        self.scale = self.current.std(axis=0)
        if np.any(self.scale == 0):
            raise IdentificationError(f"joint {int(np.argmin(self.scale)) + 1}'s current never "
                                      "changes: its gain cannot be identified")
        # the base columns are structural: found on a few hundred instants of each run
        rows = np.concatenate([r[np.linspace(0, len(r) - 1, BASE_ROWS).astype(int)]
                               for r in runs])
        self.base = base_columns(known[rows], rtol)
        self.known = known[:, :, self.base]
        self.runs, self.dof, self.mass = runs, dof, mass
        self.load_at = p + dof + friction  # the load's first column before the base selection

    def solve(self, rows: np.ndarray, instrumental: bool, gram: np.ndarray | None = None,
              covariance: bool = True) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """(solution: base coefficients then gains, its covariance, each joint's residual
        std) on the samples rows (gram: their per-joint known' known, when at hand): two
        weighted least-squares passes, then instrumental-variable passes; the covariance (of
        the last pass) when asked for. IdentificationError when a gain comes out
        non-positive."""
        normal = GainNormal(self.known[rows], self.current[rows], self.target[rows], gram)
        scale = self.current[rows].std(axis=0)
        sigma, sol = scale, None
        for step in range(2 + ITERATIONS):
            # IV: the instruments are the currents the last pass predicts (correlated with
            # the currents, not with their noise)
            instrument = (normal.current if step < 2 or not instrumental
                          else normal.predicted(sol))
            last = step == 1 + ITERATIONS
            sol, cov = normal.solve(instrument, 1.0 / sigma, covariance and last)
            sigma = np.maximum(normal.residual_std(sol), 1e-12 * scale)
            _positive(sol[-self.dof:])
        return sol, cov, sigma

    def predicted(self, sol: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """(len(rows), dof) the currents sol predicts at the samples rows."""
        kb = self.known.shape[2]
        return (self.known[rows] @ sol[:kb] - self.target[rows]) / sol[kb:]

    def load(self, sol: np.ndarray) -> np.ndarray:
        """The load's 10 parameters: the known mass, then the identifiable part of the 9."""
        load = np.zeros(10)
        load[0] = self.mass
        for i, c in enumerate(self.base):
            if self.load_at <= c < self.load_at + 9:
                load[1 + c - self.load_at] = sol[i]
        return load


def identify_drive_gains(unloaded, loaded, mass: float, instrumental: bool = True,
                         rtol: float = 1e-8, body: int = 0, blocks: int = GAIN_BLOCKS) -> DriveGainFit:
    """The drive gains of every joint from unloaded and loaded runs, each (Y, qd, qdd,
    current) or a list of such runs: Y (n, dof, p) the joint-torque regressor, 10 columns per
    body, qd, qdd (n, dof), current (n, dof) in A; mass: the load's (kg), the same on every
    loaded run, on the body moved by joint `body` (1..dof; 0: the last); instrumental False:
    weighted least squares only (biased by the currents' noise, kept to measure it); blocks:
    the jackknife's contiguous blocks per run (0: no interval, no held-out error).
    IdentificationError when a gain is not identified by these runs."""
    system = _System(_as_runs(unloaded), _as_runs(loaded), float(mass), body, rtol)
    every, whole = np.arange(len(system.current)), gram(system.known)
    sol, cov, sigma = system.solve(every, instrumental, whole)
    dof = system.dof
    gains, std = sol[-dof:], np.sqrt(np.diag(cov)[-dof:])
    lost = np.flatnonzero(std > UNIDENTIFIED * gains)
    if len(lost):
        raise IdentificationError(
            "the drive gains of joint(s) " + ", ".join(str(j + 1) for j in lost) + " are not "
            f"identified by these runs (standard error over {UNIDENTIFIED:.0%} of the gain): the "
            "load must change every joint's torque (excite more, or put it off the last axis)")
    interval, heldout = np.full(dof, np.nan), float("nan")
    if blocks:
        thetas, heldout = [], 0.0
        for block in time_blocks(system.runs, blocks):
            try:
                fold = system.solve(np.setdiff1d(every, block, assume_unique=True), instrumental,
                                    whole - gram(system.known[block]), covariance=False)[0]
            except (IdentificationError, np.linalg.LinAlgError):
                thetas.append(np.full(dof, np.nan))
                heldout = float("inf")
                continue
            thetas.append(fold[-dof:])
            miss = (system.predicted(fold, block) - system.current[block]) / system.scale
            heldout += float(np.sum(miss**2))
        interval = half_width(np.array(thetas))
    return DriveGainFit(gains, std, system.load(sol), sigma, len(system.base) + dof,
                        interval, heldout)


def _positive(gains: np.ndarray) -> None:
    if np.any(gains <= 0):
        bad = int(np.argmin(gains)) + 1
        raise IdentificationError(f"joint {bad}'s identified gain is {gains[bad - 1]:.3g} N m/A, "
                                  "not positive: the currents' sign or the load's mass is wrong, "
                                  "or the runs do not excite that joint")
