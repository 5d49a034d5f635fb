"""One cell of a sweep: generate its data, identify by its method, score on a fresh trajectory.

A cell names its robot by a string (a Ray worker builds its Arm, `Arm.of`, once per process).
The data are `generate(arm, samples, noise, seed)` (MuJoCo inverse dynamics along the seed's
excitation, non-zero-mean torque noise from the seed); every sample trains. The score is the
relative RMS error per joint of the identified torque on a fresh noise-free trajectory
(`generate(arm, FRESH_SAMPLES, 0, FRESH_SEED)`, the same for every cell of a robot) against
its clean torque, as in the bench's arm section.

Methods, each reused from identification/ with the library `torquebench identify` picks by
default (the paper's prior-knowledge library on the Lynxmotion, the base atoms generated from
the kinematics on any other arm):
- coupled: the coupled sparse regression (identify's default method);
- per-joint: the paper's sparse regression of each joint's torque alone, on its columns;
- stlsq, ssr: pysindy's STLSQ and SSR per joint on the same columns, tuned on the same
  validation blocks (identification.regression.peers);
- oracle: two-step WLS on Pinocchio's base regressor plus per-joint viscous and armature
  columns (harness.identify.scoring.oracle_design).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache

import numpy as np
from scipy.linalg import LinAlgWarning
from threadpoolctl import threadpool_limits

from harness.data.generate import generate
from harness.errors import UserError
from harness.identify.fits import arm_identification
from harness.identify.scoring import oracle_design
from harness.robots.arm import Arm
from harness.sweep.grid import Cell
from identification.errors import IdentificationError, LibraryRankWarning
from identification.identify import identify
from identification.metrics import rel_error
from identification.regression.oracle import BaseParameterRegression
from identification.regression.peers import PeerRegression
from identification.regression.sparse import SparseRegression

FRESH_SAMPLES, FRESH_SEED = 4000, 1_000_000  # the scoring trajectory; cell seeds are 0..N-1

Predictor = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class CellResult:
    """A finished cell: per-joint relative errors and its times (s)."""

    cell: Cell
    errors: tuple[float, ...]  # relative RMS error per joint on the fresh trajectory
    seconds: float  # identification (the method's fit), wall
    cell_seconds: float  # the whole cell (data, fit, score), wall
    cpu_seconds: float  # the whole cell, CPU time of the process that ran it

    @property
    def median(self) -> float:
        return float(np.median(self.errors))


@dataclass(frozen=True)
class CellFailure:
    """A cell that could not run for a reason a user can fix (too few samples, ...)."""

    cell: Cell
    message: str


@cache
def identification(arm: Arm):
    """(library, regressor) `torquebench identify` uses on arm's generated data by default
    (cached per process)."""
    return arm_identification(arm)


def library(arm: Arm):
    """The library `torquebench identify` uses on arm by default."""
    return identification(arm)[0]


@cache
def fresh(arm: Arm):
    """The noise-free trajectory every cell of arm is scored on."""
    return generate(arm, FRESH_SAMPLES, 0.0, FRESH_SEED, "inverse")


def _coupled(arm: Arm, d) -> Predictor:
    lib, regressor = identification(arm)
    return identify(d.q, d.qd, d.qdd, d.tau, lib, 0.0, regressor=regressor).model.torque


def _oracle(arm: Arm, d) -> Predictor:
    base = arm.nominal
    fit = BaseParameterRegression().fit(oracle_design(base, d.q, d.qd, d.qdd), d.tau)
    return lambda q, qd, qdd: fit.predict(oracle_design(base, q, qd, qdd))


def _per_joint(make: Callable) -> Callable[[Arm, object], Predictor]:
    def fit(arm: Arm, d) -> Predictor:
        lib = library(arm)
        fits = [make().fit(x, d.tau[:, j]) for j, x in enumerate(lib.joint_designs(d.q, d.qd, d.qdd))]

        def predict(q, qd, qdd):
            return np.column_stack([f.predict(x) for f, x in zip(fits, lib.joint_designs(q, qd, qdd),
                                                                  strict=True)])
        return predict
    return fit


FITS = {"coupled": _coupled, "oracle": _oracle, "per-joint": _per_joint(SparseRegression),
        "stlsq": _per_joint(lambda: PeerRegression("STLSQ")),
        "ssr": _per_joint(lambda: PeerRegression("SSR"))}


def run_cell(cell: Cell, reference: str | None = None) -> CellResult | CellFailure:
    """Run one cell on one BLAS thread, on the arm Arm.of(reference) (default: cell.robot; a
    string: what crosses to a Ray worker); a user-fixable error comes back as a CellFailure."""
    start, cpu = time.perf_counter(), time.process_time()
    try:
        arm = Arm.of(reference or cell.robot)
        with threadpool_limits(limits=1, user_api="blas"), warnings.catch_warnings():
            # few samples may leave the library rank-deficient, or STLSQ's subsets ill-conditioned:
            # the error measured on the fresh trajectory says what it cost
            warnings.simplefilter("ignore", LibraryRankWarning)
            warnings.simplefilter("ignore", LinAlgWarning)
            data = generate(arm, cell.samples, cell.noise, cell.seed, "inverse")
            tic = time.perf_counter()
            predict = FITS[cell.method](arm, data)
            seconds = time.perf_counter() - tic
            truth = fresh(arm)
            errors = rel_error(predict(truth.q, truth.qd, truth.qdd), truth.tau_clean)
    except (IdentificationError, UserError) as exc:
        return CellFailure(cell, str(exc))
    return CellResult(cell, tuple(float(e) for e in errors), seconds, time.perf_counter() - start,
                      time.process_time() - cpu)
