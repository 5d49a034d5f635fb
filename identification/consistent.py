"""Identify a physically consistent model on a robot's atoms, with or without a prior.

The fit is identification.physical's (every body's pseudo-inertia positive semidefinite,
armature and friction non-negative, each joint's friction law chosen by data); with a
nominal model it is pulled toward it as far as validation inside the training data allows
("nominal"), without one it is least squares under those constraints ("flat"). The result
is a KinematicModel like the sparse fit's: the candidate atoms' coefficients folded into
the robot's base atoms (KinematicLibrary.fold), plus each joint's friction-law column, so
predict, plan and replay read it the same way; `Identification.physical` says which prior,
which weight, which laws, and whether every body is consistent.
"""

from __future__ import annotations

import time
import warnings

import numpy as np
from threadpoolctl import threadpool_limits

from identification.errors import IdentificationError
from identification.identify import Identification, heldout_errors, split_training
from identification.kinematic_model import KinematicModel
from identification.library.base import conditioning
from identification.library.kinematic import KinematicLibrary
from identification.physical import CONSISTENT_TOL, LAMBDAS, fit_physical

PRIORS = ("nominal", "flat")
FLAT = 1e-8  # without a prior: a vanishing pull toward zero, so that what the data leave
# open has one solution (the solver's accuracy on a singular least squares)


def model_of(library: KinematicLibrary, fit) -> KinematicModel:
    """The KinematicModel of a PhysicalFit (its coefficients folded into the base atoms)."""
    coefficients = library.fold @ fit.params
    coefficients[np.abs(coefficients) < 1e-15] = 0.0
    return KinematicModel(library, coefficients, fit.offsets.copy(), "consistent", fit.laws,
                          fit.law_coefficients.copy())


def identify_consistent(q, qd, qdd, tau, library: KinematicLibrary, nominal: np.ndarray | None,
                        holdout: float = 0.25, tau_clean=None,
                        choose_friction: bool = True) -> Identification:
    """Fit on the first 1 - holdout of the samples, score on the rest (as `identify`).

    nominal: the robot's nominal coefficients of every candidate atom (PinocchioModel.
    atom_parameters) - the prior; None fits without one (least squares under the LMI)."""
    dof = library.dof
    if nominal is not None and np.shape(nominal) != (13 * dof,):
        raise IdentificationError(f"the nominal model has {np.size(nominal)} coefficients, "
                                  f"the robot's atoms need {13 * dof}")
    q, qd, qdd, tau, n_train = split_training(q, qd, qdd, tau, dof, library.name, holdout,
                                              len(library) // dof + 1)
    with threadpool_limits(limits=1, user_api="blas"):
        start = time.perf_counter()
        atoms = library.evaluate_every(q[:n_train], qd[:n_train], qdd[:n_train])
        cond = conditioning(atoms[:, :, list(library.columns)].reshape(-1, len(library)),
                            library.names)
        fit = fit_physical(atoms, qd[:n_train], tau[:n_train],
                           np.zeros(13 * dof) if nominal is None else nominal,
                           lambdas=(FLAT,) if nominal is None else LAMBDAS, choose_friction=choose_friction)
        seconds = time.perf_counter() - start
    model = model_of(library, fit)
    physical = {"prior": "flat" if nominal is None else "nominal", "lambda": fit.lam,
                "consistent": fit.consistent,
                "min_pseudo_eigenvalues": fit.min_eigenvalues.tolist(),
                "friction": [law.describe() for law in fit.laws],
                "standard_parameters": fit.params[:10 * dof].tolist(),
                "joint_parameters": {k: fit.params[(10 + i) * dof:(11 + i) * dof].tolist()
                                     for i, k in enumerate(("armature", "viscous", "coulomb"))},
                "validation": fit.validation}
    if not fit.consistent:  # the solver's tolerance: never returned silently
        worst = float(fit.min_eigenvalues.min())
        warnings.warn(f"identified bodies are not physically consistent: smallest pseudo-inertia "
                      f"eigenvalue {worst:.3g} < -{CONSISTENT_TOL:g}", RuntimeWarning, stacklevel=2)
    rel, mse = heldout_errors(model, q, qd, qdd, tau, tau_clean, n_train)
    return Identification(model, rel, mse, cond, seconds, (), "consistent", None, physical)
