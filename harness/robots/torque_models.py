"""A `--model` argument ('pinocchio' or a MODEL.json) read, and made a TorqueModel on an Arm."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from harness.errors import UserError
from harness.io import read_json
from harness.robots.arm import Arm
from harness.robots.resolve import resolve_arm
from identification.errors import IdentificationError
from identification.model import model_from_dict
from identification.torque_model import TorqueModel


@dataclass(frozen=True)
class ModelFile:
    """A `--model` argument read: 'pinocchio', or a MODEL.json's path and content. Its robot
    record is what resolve_arm checks the arm against (`model=ModelFile.recorded`)."""

    spec: str
    payload: dict | None = None

    @property
    def recorded(self) -> tuple[str, dict] | None:
        """(file, robot record {"name", "hash"}) for resolve_arm; None: 'pinocchio', or a file
        written before models recorded their robot."""
        robot = None if self.payload is None else self.payload.get("robot")
        if robot is None:
            return None
        if not isinstance(robot, dict) or not isinstance(robot.get("name"), str) \
                or not robot["name"]:
            raise UserError(f"model {self.spec}: 'robot' must be an object with the robot's "
                            "'name' and 'hash'")
        return self.spec, robot


def read_model(spec: str) -> ModelFile:
    """'pinocchio', or the MODEL.json at spec read (UserError naming a missing or bad file)."""
    if spec == "pinocchio":
        return ModelFile(spec)
    path = Path(spec)
    if not path.is_file():
        raise UserError(f"model file not found: {path} (or use 'pinocchio')")
    return ModelFile(spec, read_json(path, "model"))


def torque_model(model: ModelFile, arm: Arm) -> TorqueModel:
    """The TorqueModel of a read `--model` on arm: the closed-form baseline, or an identified
    model (one on the arm's base atoms is checked against its kinematics). UserError naming
    the file and what is wrong with it."""
    if model.payload is None:
        return arm.nominal
    payload = model.payload
    try:
        if payload.get("kind") == "closeloop":  # closeloop --data's DIR/model.json
            from harness.robots.closed_model import closeloop_model

            return closeloop_model(payload, arm, Path(model.spec))
        if model.recorded is None:
            model = model_from_dict(payload)
        else:
            model = model_from_dict(payload, lambda: arm.library)
    except IdentificationError as exc:
        raise UserError(f"model {model.spec}: {exc}") from None
    arm.check_joints(model.dof, "the model")
    return model


def load_torque_model(spec: str, arm: Arm) -> TorqueModel:
    """torque_model of spec on an arm already resolved (the model's robot checked)."""
    model = read_model(spec)
    if model.recorded is not None:
        resolve_arm(arm.reference, model=model.recorded)
    return torque_model(model, arm)
