"""The models of the real-data section on one ingested log, each scored on its held-out part.

- nominal: Pinocchio's RNEA with the URDF's inertials (example-robot-data), no friction,
  no offset: nothing fitted (scored on the held-out part and on the whole log);
- least squares: the source README's reference model, recomputed here on the same data -
  the rigid-body base atoms plus, per joint, viscous (qd), Coulomb (the kinematic library's
  smoothed sign) and an offset, plain least squares on the training part;
- consistent: identification.physical on the training part: standard parameters pulled
  toward the URDF's (weight chosen inside the training part), every body physically
  consistent (pseudo-inertia LMI), viscous, Coulomb and offset per joint;
- identified: `identify --robot R` (the coupled sparse regression on the robot's base atoms
  with armature, viscous and Coulomb atoms), its fitted sensor offsets added.

Errors are relative RMS ||tau_hat - tau|| / ||tau|| per joint against the measured torque.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from harness.closeloop.measured import rigid_library
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import load_pinocchio
from harness.robots.torque_models import robot_library
from identification.identify import identify
from identification.library.kinematic import COULOMB_WIDTH
from identification.metrics import rel_error
from identification.physical import fit_physical


@dataclass(frozen=True)
class Scored:
    """A model's torque on every sample (n, dof) and its held-out error per joint."""

    name: str
    torque: np.ndarray
    heldout: np.ndarray
    seconds: float


def joint_friction_columns(qd: np.ndarray) -> np.ndarray:
    """(n, dof, 3 dof): viscous, Coulomb and offset columns of every joint."""
    n, dof = qd.shape
    eye = np.eye(dof)
    viscous = qd[:, :, None] * eye
    coulomb = (qd / np.sqrt(qd**2 + COULOMB_WIDTH**2))[:, :, None] * eye
    return np.concatenate([viscous, coulomb, np.broadcast_to(eye, (n, dof, dof))], axis=2)


def least_squares(robot: str, q, qd, qdd, tau, split: int) -> np.ndarray:
    """The reference model's torque (n, dof): rigid-body atoms + viscous, Coulomb and offset
    per joint, least squares on the first split samples."""
    X = np.concatenate([rigid_library(robot).evaluate(q, qd, qdd), joint_friction_columns(qd)],
                       axis=2)
    coef, *_ = np.linalg.lstsq(X[:split].reshape(-1, X.shape[2]), tau[:split].ravel(),
                               rcond=None)
    return X @ coef


def score_models(robot: str, q, qd, qdd, tau, holdout: float) -> tuple[dict[str, Scored], object]:
    """The three models on the data; also the identification (its MODEL.json payload)."""
    split = int(round(len(q) * (1 - holdout)))
    held = slice(split, None)
    out = {}

    def add(name, fn):
        start = time.process_time()
        torque = fn()
        out[name] = Scored(name, torque, rel_error(torque[held], tau[held]),
                           time.process_time() - start)

    nominal = PinocchioModel(load_pinocchio(robot))
    add("nominal", lambda: nominal.torque(q, qd, qdd))

    def consistent():  # identification.physical: the nominal as a prior, the LMI, friction
        Y = nominal.regressor(q, qd, qdd)
        fit = fit_physical(Y[:split], qd[:split], tau[:split], nominal.inertial_parameters())
        return fit.torque(Y, qd)

    add("consistent", consistent)
    add("least_squares", lambda: least_squares(robot, q, qd, qdd, tau, split))
    result = {}

    def identified():
        result["id"] = identify(q, qd, qdd, tau, robot_library(robot), holdout)
        return result["id"].model.torque(q, qd, qdd) + result["id"].model.offsets

    add("identified", identified)
    return out, result["id"]
