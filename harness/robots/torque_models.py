"""Resolve a `--model` argument to a TorqueModel: 'pinocchio' or a MODEL.json."""

from __future__ import annotations

from pathlib import Path

from harness.errors import UserError
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import DEFAULT_ROBOT, load_pinocchio
from identification.torque_model import TorqueModel


def load_torque_model(spec: str, robot: str = DEFAULT_ROBOT) -> TorqueModel:
    """'pinocchio' -> the closed-form baseline of robot; a path -> an identified model."""
    if spec == "pinocchio":
        return PinocchioModel(load_pinocchio(robot))
    path = Path(spec)
    if not path.is_file():
        raise UserError(f"model file not found: {path} (or use 'pinocchio')")
    from identification.model import load_model  # provided by the identification package

    return load_model(path)
