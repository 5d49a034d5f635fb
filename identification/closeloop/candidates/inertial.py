"""The rigid-body correction candidate of the measured loop (`inertial`): what the physically
consistent fit pulled toward the robot's nominal model (identification.regression.consistent)
adds to it, so a payload, a wrong mass or a wrong centre of mass is named as such rather than
absorbed by springs and friction."""

from __future__ import annotations

import numpy as np

from identification.identify import identify
from identification.kinematic_model import KinematicModel
from identification.library.kinematic import JOINT_ATOMS, KinematicLibrary
from identification.regression.consistent import ConsistentRegressor


def inertial_correction(library: KinematicLibrary, nominal: np.ndarray, ellipsoids,
                        runs: list[tuple]) -> KinematicModel:
    """The consistent fit's rigid body on runs [(q, qd, qdd, tau)] pulled toward the nominal
    atom parameters, minus the nominal rigid body: the torque to add to the nominal model (its
    joint atoms left out); each run with its own sensor offset, each body inside its link's
    ellipsoid (ellipsoids: the robot's, identification.regression.consistent)."""
    q, qd, qdd, tau = (np.concatenate([r[i] for r in runs]) for i in range(4))
    labels = np.repeat(np.arange(len(runs)), [len(r[0]) for r in runs])  # an offset per run
    regressor = ConsistentRegressor(nominal, ellipsoids=ellipsoids)
    fit = identify(q, qd, qdd, tau, library, 0.0, regressor=regressor, runs=labels).model
    delta = fit.coefficients - library.fold @ nominal
    joint_atoms = tuple(name for name, _ in JOINT_ATOMS)
    delta[[k for k, n in enumerate(library.names) if n.startswith(joint_atoms)]] = 0.0
    return KinematicModel(library, delta, np.zeros(library.dof), "consistent")
