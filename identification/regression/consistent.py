"""The physically consistent fit on a robot's atoms, with or without a prior.

The fit is identification.physical's (every body's pseudo-inertia positive semidefinite,
armature and friction non-negative, each joint's friction law chosen by data); with a
nominal model it is pulled toward it as far as validation inside the training data allows
("nominal"), without one it is least squares under those constraints ("flat"). The result
is a KinematicModel like the sparse fit's: the candidate atoms' coefficients folded into
the robot's base atoms (KinematicLibrary.fold), plus each joint's friction-law column, so
predict, plan and replay read it the same way; `TorqueFit.physical` says which prior,
which weight, which laws, and whether every body is consistent.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from identification.ellipsoids import Ellipsoid, holding, inside
from identification.errors import IdentificationError
from identification.kinematic_model import KinematicModel
from identification.library.base import conditioning
from identification.library.kinematic import KinematicLibrary
from identification.physical import CONSISTENT_TOL, LAMBDAS, fit_physical, pseudo_inertia
from identification.regression.torque import TorqueFit

PRIORS = ("nominal", "flat")
FLAT = 1e-8  # without a prior: a vanishing pull toward zero, so that what the data leave
# open has one solution (the solver's accuracy on a singular least squares)


def model_of(library: KinematicLibrary, fit) -> KinematicModel:
    """The KinematicModel of a PhysicalFit (its coefficients folded into the base atoms)."""
    coefficients = library.fold @ fit.params
    coefficients[np.abs(coefficients) < 1e-15] = 0.0
    return KinematicModel(library, coefficients, fit.offsets.copy(), "consistent", fit.laws,
                          fit.law_coefficients.copy())


@dataclass(frozen=True, eq=False)
class ConsistentRegressor:
    """nominal: the robot's nominal coefficients of every candidate atom (13 per joint,
    PinocchioModel.atom_parameters) - the prior; None fits without one (least squares under
    the LMI). choose_friction False keeps viscous-Coulomb on every joint. ellipsoids: per
    body the Ellipsoid bounding its link (or None): each body's mass held inside it
    (plausible), the ellipsoid first grown to hold the nominal body (identification.ellipsoids.
    holding); None: consistent only. prior_metric: how the prior measures a body's distance
    from the nominal (identification.physical.PRIOR_METRICS)."""

    nominal: np.ndarray | None = None
    choose_friction: bool = True
    ellipsoids: tuple[Ellipsoid | None, ...] | None = None
    prior_metric: str = "ridge"  # identification.physical.PRIOR_METRICS
    lambdas: tuple[float, ...] | None = None  # the prior weights tried (None: LAMBDAS)
    per_run_offsets = True  # fit(runs=...) gives each run its own sensor offset

    def min_samples(self, library: KinematicLibrary) -> int:
        if self.nominal is not None and np.shape(self.nominal) != (13 * library.dof,):
            raise IdentificationError(f"the nominal model has {np.size(self.nominal)} coefficients, "
                                      f"the robot's atoms need {13 * library.dof}")
        return len(library) // library.dof + 1

    def parameters(self, library: KinematicLibrary) -> int:
        return 13 * library.dof

    def fit(self, library: KinematicLibrary, q, qd, qdd, tau, runs=None) -> TorqueFit:
        dof, nominal = library.dof, self.nominal
        atoms = library.evaluate_every(q, qd, qdd)
        cond = conditioning(atoms[:, :, list(library.columns)].reshape(-1, len(library)),
                            library.names)
        bounds = self.bounds(dof)
        fit = fit_physical(atoms, qd, tau, np.zeros(13 * dof) if nominal is None else nominal,
                           lambdas=(FLAT,) if nominal is None else (self.lambdas or LAMBDAS),
                           choose_friction=self.choose_friction, runs=runs,
                           bounds=None if bounds is None else [b and b.matrix for b in bounds],
                           metric=self.prior_metric)
        physical = {"prior": "flat" if nominal is None else "nominal", "lambda": fit.lam,
                    "prior_metric": self.prior_metric,
                    "solver": fit.validation["solver"],
                    "consistent": fit.consistent,
                    "min_pseudo_eigenvalues": fit.min_eigenvalues.tolist(),
                    "friction": [law.describe() for law in fit.laws],
                    "standard_parameters": fit.params[:10 * dof].tolist(),
                    "joint_parameters": {k: fit.params[(10 + i) * dof:(11 + i) * dof].tolist()
                                         for i, k in enumerate(("armature", "viscous", "coulomb"))},
                    "validation": fit.validation,
                    "nominal": None if nominal is None else np.asarray(nominal, float).tolist()}
        if bounds is not None:
            physical["ellipsoids"] = [b and b.to_dict() for b in bounds]
            physical["plausible"] = [b is None or inside(np.array(pseudo_inertia(
                fit.params[10 * k:10 * k + 10])), b) >= -CONSISTENT_TOL for k, b in enumerate(bounds)]
        if not fit.consistent:  # the solver's tolerance: never returned silently
            worst = float(fit.min_eigenvalues.min())
            warnings.warn(f"identified bodies are not physically consistent: smallest "
                          f"pseudo-inertia eigenvalue {worst:.3g} < -{CONSISTENT_TOL:g}",
                          RuntimeWarning, stacklevel=2)
        return TorqueFit(model_of(library, fit), cond, "consistent", physical=physical)

    def bounds(self, dof: int) -> tuple[Ellipsoid | None, ...] | None:
        """Each body's ellipsoid, grown to hold its nominal body (the prior stays feasible)."""
        if self.ellipsoids is None:
            return None
        if len(self.ellipsoids) != dof:
            raise IdentificationError(f"{len(self.ellipsoids)} bounding ellipsoids for {dof} bodies")
        if self.nominal is None:
            return tuple(self.ellipsoids)
        nominal = np.asarray(self.nominal, float)
        return tuple(e and holding(e, np.array(pseudo_inertia(nominal[10 * k:10 * k + 10])))
                     for k, e in enumerate(self.ellipsoids))
