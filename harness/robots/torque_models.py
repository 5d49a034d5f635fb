"""Resolve a `--model` argument to a TorqueModel: 'pinocchio' or a MODEL.json."""

from __future__ import annotations

from dataclasses import replace
from functools import cache
from pathlib import Path

from harness.errors import UserError
from harness.io import read_json
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import (
    DEFAULT_ROBOT,
    identified_robot,
    load_chain,
    load_pinocchio,
    robot_entry,
)
from identification.choice import choose_fit, choose_prior, library_name
from identification.errors import IdentificationError
from identification.library.kinematic import KinematicLibrary
from identification.model import model_from_dict
from identification.regression.consistent import ConsistentRegressor
from identification.torque_model import TorqueModel


@cache
def robot_library(robot: str) -> KinematicLibrary:
    """The base atoms generated from robot's kinematics (cached per robot and process)."""
    return KinematicLibrary.generate(load_chain(robot))


def robot_record(robot: str) -> dict:
    """What a MODEL.json records of the robot it was identified for: name, kinematics hash."""
    chain = load_chain(robot)
    return {"name": chain.name, "hash": chain.digest()}


def _recorded(payload: dict) -> dict | None:
    """The robot a MODEL.json records (None for files written before models recorded it)."""
    robot = payload.get("robot")
    if robot is None:
        return None
    if not isinstance(robot, dict) or not isinstance(robot.get("name"), str) or not robot["name"]:
        raise IdentificationError("'robot' must be an object with the robot's 'name' and 'hash'")
    return robot


def load_torque_model(spec: str, robot: str | None = None) -> TorqueModel:
    """'pinocchio' -> the closed-form baseline of robot; a path -> an identified model (one on
    a robot's base atoms is checked against robot, by default the robot it records).
    UserError naming the file and what is wrong with it."""
    if spec == "pinocchio":
        return PinocchioModel(load_pinocchio(robot or DEFAULT_ROBOT))
    path = Path(spec)
    if not path.is_file():
        raise UserError(f"model file not found: {path} (or use 'pinocchio')")
    payload = read_json(path, "model")
    try:
        if payload.get("kind") == "closeloop":  # closeloop --data's DIR/model.json
            from harness.closeloop.model_file import closeloop_model

            return closeloop_model(payload, robot, path, robot_library)
        recorded = _recorded(payload)
        if recorded is None:
            return model_from_dict(payload)
        robot = identified_robot(recorded, robot, path)
        return model_from_dict(payload, lambda: robot_library(robot))
    except IdentificationError as exc:
        raise UserError(f"model {path}: {exc}") from None


def library_named(name: str, robot: str, dof: int | None = None):
    """An identification library by the name `identify --library` takes, for robot:
    'kinematic' (base atoms generated from its kinematics), 'prior' / 'prior-general' (derived
    from simple structures: 3-DOF arms), 'paper' (the published 75 features, 3-DOF),
    'generic' (polynomial x trig, any dof)."""
    from harness.robots.extras import published_library
    from identification.library.generic import generic_library
    from identification.library.prior_knowledge import prior_knowledge_library

    dof = load_chain(robot).dof if dof is None else dof
    if name == "kinematic":
        library = robot_library(robot)
        if library.dof != dof:
            raise UserError(f"data have {dof} joints, robot {robot} has {library.dof}")
        return library
    if name == "generic" or dof != 3:
        return generic_library(dof)
    if name == "paper":
        return published_library(name)
    return prior_knowledge_library(3, symmetric_links=name != "prior-general")


def robot_identification(robot: str, dof: int | None = None, library: str = "auto",
                         prior: str = "none", method: str = "auto", measured: bool = False,
                         plausible: bool = True, prior_metric: str = "ridge"):
    """(library, regressor) of an identification on robot, chosen by identification.choice
    from the names `identify --library/--prior/--method` take (measured: the data are a
    measured log); the robot's inputs (its libraries, its nominal inertias) made here.
    The CLI, the sweep and the bench all identify with this (the bench's perturbed prior
    alone builds its ConsistentRegressor per draw). plausible: a consistent fit keeps each
    body inside its link's bounding ellipsoid (harness.robots.ellipsoids); prior_metric: its
    prior's distance from the nominal (identification.physical.PRIOR_METRICS)."""
    lib = library_named(library_name(library, prior, robot_entry(robot).libraries), robot, dof)
    regressor = choose_fit(lib, choose_prior(prior, measured, lib), method,
                           lambda: PinocchioModel(load_pinocchio(robot)).atom_parameters())
    if isinstance(regressor, ConsistentRegressor):
        regressor = replace(regressor, prior_metric=prior_metric)
    if plausible and isinstance(regressor, ConsistentRegressor):
        from harness.robots.ellipsoids import robot_ellipsoids

        regressor = replace(regressor, ellipsoids=robot_ellipsoids(robot))
    return lib, regressor
