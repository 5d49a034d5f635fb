"""The models of the real-data section on one ingested log, each scored on its held-out part
(the peers the identification is measured against, on the same data):

- nominal: Pinocchio's RNEA with the URDF's inertials (example-robot-data), no friction,
  no offset: nothing fitted (scored on the held-out part and on the whole log);
- nominal + friction: the same plus, per joint, viscous, Coulomb and an offset fitted by
  least squares to the nominal model's residual on the training part;
- least squares: the source README's reference model, recomputed here on the same data -
  the rigid-body base atoms plus, per joint, viscous (qd), Coulomb (the kinematic library's
  smoothed sign) and an offset, plain least squares on the training part;
- least squares + LMI: `identify --prior flat` (every body physically consistent, friction
  >= 0 and its law chosen per joint, no pull toward the URDF);
- identified: `identify --robot panda`, the default on a measured log (`--prior nominal`:
  the same pulled toward the URDF's inertias as far as validation inside the training part
  allows);
- sparse: `identify --prior none` (the coupled sparse regression on the robot's base atoms
  with armature, viscous and Coulomb atoms), its fitted sensor offsets added.

Errors are relative RMS ||tau_hat - tau|| / ||tau|| per joint against the measured torque.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from harness.identify.fits import arm_identification
from harness.identify.peers import least_squares, nominal_friction
from harness.robots.arm import Arm
from identification.identify import identify
from identification.metrics import rel_error
from identification.regression.consistent import ConsistentRegressor


@dataclass(frozen=True)
class Scored:
    """A model's torque on every sample (n, dof) and its held-out error per joint."""

    name: str
    torque: np.ndarray
    heldout: np.ndarray
    seconds: float


def score_models(arm: Arm, q, qd, qdd, tau, holdout: float) -> tuple[dict[str, Scored], object]:
    """The peers on the data; also the default identification (its MODEL.json payload)."""
    split = int(round(len(q) * (1 - holdout)))
    held = slice(split, None)
    out = {}

    def add(name, fn):
        start = time.process_time()
        torque = fn()
        out[name] = Scored(name, torque, rel_error(torque[held], tau[held]),
                           time.process_time() - start)

    nominal = arm.nominal
    add("nominal", lambda: nominal.torque(q, qd, qdd))
    add("nominal_friction", lambda: nominal_friction(out["nominal"].torque, qd, tau, split))
    add("least_squares", lambda: least_squares(arm, q, qd, qdd, tau, split))
    library, result = arm.library, {}

    def fitted(name, regressor):
        def fn():
            result[name] = identify(q, qd, qdd, tau, library, holdout, regressor=regressor)
            return result[name].model.torque(q, qd, qdd) + result[name].model.offsets
        return fn

    add("least_squares_lmi", fitted("least_squares_lmi", ConsistentRegressor()))
    # what `identify --robot panda` fits on a measured log: the nominal prior, every body
    # inside its link's ellipsoid (arm_identification, the command's own choice)
    _, regressor = arm_identification(arm, q.shape[1], prior="nominal", measured=True)
    add("identified", fitted("identified", regressor))
    add("sparse", fitted("sparse", None))
    return out, result["identified"]
