"""Resolve a `--model` argument to a TorqueModel: 'pinocchio' or a MODEL.json."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

from harness.errors import UserError
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import DEFAULT_ROBOT, ROBOTS, load_chain, load_pinocchio
from identification.errors import IdentificationError
from identification.kinematic_model import LIBRARY, KinematicModel
from identification.library.kinematic import KinematicLibrary
from identification.torque_model import TorqueModel


@cache
def robot_library(robot: str) -> KinematicLibrary:
    """The base atoms generated from robot's kinematics (cached per robot and process)."""
    return KinematicLibrary.generate(load_chain(robot))


def robot_record(robot: str) -> dict:
    """What a MODEL.json records of the robot it was identified for: name, kinematics hash."""
    chain = load_chain(robot)
    return {"name": chain.name, "hash": chain.digest()}


def _recorded(path: Path) -> tuple[dict, dict | None]:
    """The MODEL.json payload and the robot it records (None for older files)."""
    try:
        payload = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise UserError(f"cannot read model {path}: {exc}") from None
    robot = payload.get("robot") if isinstance(payload, dict) else None
    return payload, robot if isinstance(robot, dict) and robot.get("name") else None


def load_torque_model(spec: str, robot: str | None = None) -> TorqueModel:
    """'pinocchio' -> the closed-form baseline of robot; a path -> an identified model (one on
    a robot's base atoms is checked against robot, by default the robot it records)."""
    if spec == "pinocchio":
        return PinocchioModel(load_pinocchio(robot or DEFAULT_ROBOT))
    path = Path(spec)
    if not path.is_file():
        raise UserError(f"model file not found: {path} (or use 'pinocchio')")
    from identification.model import load_model

    payload, recorded = _recorded(path)
    if recorded is None:
        return load_model(path)
    robot = robot or str(recorded["name"])
    if robot not in ROBOTS and not Path(robot).is_file():
        raise UserError(f"model {path} was identified for robot '{recorded['name']}': pass its "
                        "URDF/MJCF with --robot")
    try:
        if payload.get("library") == LIBRARY:
            return KinematicModel.from_dict(payload, robot_library(robot))
        chain = load_chain(robot)
        if recorded.get("hash") != chain.digest():
            raise IdentificationError(f"model was identified for robot '{recorded['name']}' "
                                      f"(kinematics {recorded.get('hash')}), not '{chain.name}' "
                                      f"({chain.digest()})")
    except IdentificationError as exc:
        raise UserError(f"model {path}: {exc}") from None
    return load_model(path)
