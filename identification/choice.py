"""Which library, prior and regressor an identification uses, by the names the CLI takes.

The robot-specific inputs (the libraries a robot offers, its kinematic library, its nominal
inertial parameters, whether the data are a measured log) come in from the caller; the
decisions are made here, once, for the CLI, the sweep and the bench alike.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from identification.errors import IdentificationError
from identification.library.kinematic import KinematicLibrary
from identification.regression.consistent import ConsistentRegressor
from identification.regression.sparse import SparseRegression
from identification.regression.torque import (
    BaseAtomRegressor,
    CoupledRegressor,
    JointwiseRegressor,
    PerJointRegressor,
    TorqueRegressor,
)

LIBRARIES = ("auto", "kinematic", "prior", "prior-general", "paper", "generic")
METHODS = ("auto", "coupled", "per-joint", "jointwise")
PRIORS = ("auto", "nominal", "flat", "none")
CONSISTENT = ("nominal", "flat")  # the priors of the physically consistent fit
FEATURE_REGRESSORS = {"coupled": CoupledRegressor, "per-joint": PerJointRegressor,
                      "jointwise": JointwiseRegressor}


def choose_regressor(library, method: str | None = None,
                     selector: SparseRegression | None = None,
                     structure: KinematicLibrary | None = None) -> TorqueRegressor:
    """The sparse regressor for library: on a robot's base atoms the coupled one (method is
    not used there); on a feature library `method` ("coupled", "per-joint", "jointwise";
    None: coupled when the library has Lagrangian atoms, else per-joint). structure: the
    robot's base atoms the coupled fit on a feature library is held to (None: free)."""
    if isinstance(library, KinematicLibrary):
        return BaseAtomRegressor(selector)
    method = method or ("coupled" if library.atoms else "per-joint")
    if method not in FEATURE_REGRESSORS:
        raise IdentificationError(f"method must be 'coupled', 'per-joint' or 'jointwise', got {method!r}")
    if method == "coupled":
        return CoupledRegressor(selector, structure)
    return FEATURE_REGRESSORS[method](selector)


def library_name(requested: str, prior: str, offered: Sequence[str]) -> str:
    """The library `--library requested` names; 'auto': the kinematic one when a consistent
    prior is asked, else the first the robot offers."""
    if requested != "auto":
        return requested
    return "kinematic" if prior in CONSISTENT else offered[0]


def choose_prior(requested: str, measured: bool, library) -> str:
    """The prior `--prior requested` names; 'auto': nominal on a measured log, else none (and
    none on a library without a robot's atoms). The consistent fits need a robot's atoms."""
    kinematic = isinstance(library, KinematicLibrary)
    if requested == "auto":
        requested = "nominal" if measured and kinematic else "none"
    if requested != "none" and not kinematic:
        raise IdentificationError(f"--prior {requested} fits the robot's atoms: use --library "
                                  f"kinematic (not {library.name})")
    return requested


def choose_fit(library, prior: str, method: str, nominal: Callable[[], np.ndarray],
               structure: Callable[[], KinematicLibrary] | None = None) -> TorqueRegressor:
    """The regressor for a chosen prior: 'none' the sparse fit by `method` ('auto': the
    library's default; structure(): the robot's base atoms a coupled fit on a feature library
    is held to, None: free), 'nominal' the consistent fit toward nominal() (the robot's
    nominal atom parameters, computed only then), 'flat' the consistent fit without a prior."""
    if prior == "none":
        held = structure() if structure is not None and not isinstance(library,
                                                                        KinematicLibrary) else None
        return choose_regressor(library, None if method == "auto" else method, structure=held)
    return ConsistentRegressor(nominal() if prior == "nominal" else None)
