"""What an arm is identified with: the library `identify --library` names and the regressor
(sparse, coupled or physically consistent with its prior) identification.choice picks."""

from __future__ import annotations

from dataclasses import replace

from harness.robots.arm import Arm
from identification.choice import choose_fit, choose_prior, library_name
from identification.regression.consistent import ConsistentRegressor

# identify's --rigid-body default (docs/identification.md, 'Over many draws')
RIGID_BODY = False


def library_named(name: str, arm: Arm, dof: int | None = None):
    """An identification library by the name `identify --library` takes, for arm:
    'kinematic' (base atoms generated from its kinematics), 'prior' / 'prior-general' (derived
    from simple structures: 3-DOF arms), 'paper' (the published 75 features, 3-DOF),
    'generic' (polynomial x trig, any dof)."""
    from harness.robots.extras import published_library
    from identification.library.generic import generic_library
    from identification.library.prior_knowledge import prior_knowledge_library

    dof = arm.dof if dof is None else dof
    if name == "kinematic":
        arm.check_joints(dof, "the data")
        return arm.library
    if name == "generic" or dof != 3:
        return generic_library(dof)
    if name == "paper":
        return published_library(name)
    return prior_knowledge_library(3, symmetric_links=name != "prior-general")


def arm_identification(arm: Arm, dof: int | None = None, library: str = "auto",
                         prior: str = "none", method: str = "auto", measured: bool = False,
                         plausible: bool = True, prior_metric: str = "ridge",
                         rigid_body: bool = RIGID_BODY):
    """(library, regressor) of an identification on arm, chosen by identification.choice
    from the names `identify --library/--prior/--method` take (measured: the data are a
    measured log); the robot's inputs (its libraries, its nominal inertias) made here.
    The CLI, the sweep and the bench all identify with this (the bench's perturbed prior
    alone builds its ConsistentRegressor per draw). plausible: a consistent fit keeps each
    body inside its link's bounding ellipsoid (harness.robots.ellipsoids); prior_metric: its
    prior's distance from the nominal (identification.physical.PRIOR_METRICS); rigid_body:
    a coupled fit on a feature library is held to the arm's rigid-body structure, its
    kinematics' base atoms (identification.regression.structure)."""
    lib = library_named(library_name(library, prior, arm.entry.libraries), arm, dof)
    regressor = choose_fit(lib, choose_prior(prior, measured, lib), method,
                           lambda: arm.nominal.atom_parameters(),
                           (lambda: arm.library) if rigid_body else None)
    if isinstance(regressor, ConsistentRegressor):
        regressor = replace(regressor, prior_metric=prior_metric)
    if plausible and isinstance(regressor, ConsistentRegressor):
        regressor = replace(regressor, ellipsoids=arm.ellipsoids)
    return lib, regressor
