"""identification.choice: the CLI's names mapped to a library, a prior and a regressor, for
every caller alike (the CLI, the sweep and the bench)."""

from __future__ import annotations

import numpy as np
import pytest

from harness.identify.fits import arm_identification
from harness.paper.identification.published_library import paper_library
from harness.robots.arm import Arm
from identification.choice import choose_fit, choose_prior, choose_regressor, library_name
from identification.errors import IdentificationError
from identification.library.prior_knowledge import prior_knowledge_library
from identification.regression.consistent import ConsistentRegressor
from identification.regression.torque import (
    BaseAtomRegressor,
    CoupledRegressor,
    JointwiseRegressor,
    PerJointRegressor,
)


def test_auto_library_is_kinematic_for_a_consistent_prior_else_the_robots_first():
    assert library_name("auto", "nominal", ("prior", "kinematic")) == "kinematic"
    assert library_name("auto", "flat", ("prior",)) == "kinematic"
    assert library_name("auto", "none", ("prior", "kinematic")) == "prior"
    assert library_name("paper", "nominal", ("prior",)) == "paper"


def test_the_regressor_follows_the_library_and_method():
    atoms = prior_knowledge_library(3)
    assert isinstance(choose_regressor(atoms), CoupledRegressor)
    assert isinstance(choose_regressor(atoms, "jointwise"), JointwiseRegressor)
    assert isinstance(choose_regressor(paper_library()), PerJointRegressor)
    assert isinstance(choose_regressor(Arm.of("lynxmotion").library, "per-joint"),
                      BaseAtomRegressor)
    with pytest.raises(IdentificationError, match="method must be"):
        choose_regressor(atoms, "joint")
    with pytest.raises(IdentificationError, match="no Lagrangian atoms"):
        choose_regressor(paper_library(), "coupled").min_samples(paper_library())


def test_the_prior_by_data_kind_and_library():
    kinematic, features = Arm.of("lynxmotion").library, prior_knowledge_library(3)
    assert choose_prior("auto", True, kinematic) == "nominal"
    assert choose_prior("auto", False, kinematic) == "none"
    assert choose_prior("auto", True, features) == "none"
    with pytest.raises(IdentificationError, match="--prior flat fits the robot's atoms"):
        choose_prior("flat", False, features)


def test_the_nominal_is_computed_only_for_the_nominal_prior():
    kinematic = Arm.of("lynxmotion").library

    def never():
        raise AssertionError("nominal computed")

    assert isinstance(choose_fit(kinematic, "none", "auto", never), BaseAtomRegressor)
    flat = choose_fit(kinematic, "flat", "auto", never)
    assert isinstance(flat, ConsistentRegressor) and flat.nominal is None
    nominal = choose_fit(kinematic, "nominal", "auto", lambda: np.ones(39))
    assert np.array_equal(nominal.nominal, np.ones(39))


def test_robot_identification_passes_the_robots_inputs_in():
    library, regressor = arm_identification(Arm.of("lynxmotion"))
    assert library.name.startswith("prior") and isinstance(regressor, CoupledRegressor)
    library, regressor = arm_identification(Arm.of("lynxmotion"), prior="nominal")
    assert library is Arm.of("lynxmotion").library and isinstance(regressor, ConsistentRegressor)
    assert regressor.nominal.shape == (39,)
