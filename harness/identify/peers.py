"""The peers an identification is measured against on the same data, beside the nominal model:
least squares on the robot's rigid-body base atoms plus, per joint, viscous, Coulomb and an
offset (the reference of Gaz et al.'s log, recomputed), and the nominal model plus the same
friction fitted to its residual."""

from __future__ import annotations

import numpy as np

from harness.closeloop.one_log import rigid_library
from harness.robots.arm import Arm
from identification.library.kinematic import COULOMB_WIDTH


def joint_friction_columns(qd: np.ndarray) -> np.ndarray:
    """(n, dof, 3 dof): viscous, Coulomb and offset columns of every joint."""
    n, dof = qd.shape
    eye = np.eye(dof)
    viscous = qd[:, :, None] * eye
    coulomb = (qd / np.sqrt(qd**2 + COULOMB_WIDTH**2))[:, :, None] * eye
    return np.concatenate([viscous, coulomb, np.broadcast_to(eye, (n, dof, dof))], axis=2)


def least_squares(arm: Arm, q, qd, qdd, tau, split: int) -> np.ndarray:
    """The reference model's torque (n, dof): rigid-body atoms + viscous, Coulomb and offset
    per joint, least squares on the first split samples."""
    X = np.concatenate([rigid_library(arm).evaluate(q, qd, qdd), joint_friction_columns(qd)],
                       axis=2)
    coef, *_ = np.linalg.lstsq(X[:split].reshape(-1, X.shape[2]), tau[:split].ravel(),
                               rcond=None)
    return X @ coef


def nominal_friction(nominal: np.ndarray, qd, tau, split: int) -> np.ndarray:
    """The nominal torque (n, dof) plus viscous, Coulomb and offset per joint fitted to its
    residual on the first split samples."""
    X = joint_friction_columns(qd)
    coef, *_ = np.linalg.lstsq(X[:split].reshape(-1, X.shape[2]),
                               (tau - nominal)[:split].ravel(), rcond=None)
    return nominal + X @ coef
