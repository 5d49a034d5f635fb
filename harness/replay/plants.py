"""What `replay --plant` simulates: the robot's own scene, another URDF or MJCF of it, or
the dynamics an identified MODEL.json believes (its standard parameters on the robot's
bodies), with the feed-forward that plant's model computes."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import mujoco

from harness.errors import UserError
from harness.io import read_json
from harness.robots.baseline import PinocchioModel
from harness.robots.inertials import PARAMETERS_KEY, model_standard_parameters, set_standard_parameters
from harness.robots.registry import load_mujoco, load_pinocchio
from harness.robots.scene import build_scene, replay_scene
from harness.robots.torque_models import load_torque_model
from identification.torque_model import TorqueModel
from planning.formulation.kinematics import ArmGeometry


@dataclass(frozen=True)
class ReplayPlant:
    """The MuJoCo plant, the feed-forward model and how REPLAY.json names them."""

    model: mujoco.MjModel
    feedforward: TorqueModel
    label: str
    feedforward_label: str


def replay_plant(plant: str | None, robot: str, radii: tuple[float, ...] = (),
                 geometry: ArmGeometry | None = None) -> ReplayPlant:
    """The plant `replay --plant` names (None: the robot's replay scene), where a scene is
    built the link capsules of geometry (the plan's), else of these radii (m) on the
    joint-origin segments; UserError in one line when it cannot be one."""
    if plant is None:
        return ReplayPlant(replay_scene(robot, tuple(radii), geometry),
                           PinocchioModel(load_pinocchio(robot)), robot, "pinocchio")
    path = Path(plant)
    if not path.is_file():
        raise UserError(f"plant file not found: {path}")
    if path.suffix.lower() == ".json":
        return _identified(path, robot, radii, geometry)
    if path.suffix.lower() == ".urdf":
        return ReplayPlant(build_scene(str(path), radii, geometry).compile(),
                           PinocchioModel(load_pinocchio(path)), str(path), f"pinocchio {path}")
    model = load_mujoco(path, scene=True)
    if model.nu:  # an MJCF scene with its own motors (and obstacle), simulated as it is
        return ReplayPlant(model, PinocchioModel(load_pinocchio(robot)), str(path), "pinocchio")
    return ReplayPlant(build_scene(str(path), radii, geometry).compile(),
                       PinocchioModel(load_pinocchio(path)), str(path), f"pinocchio {path}")


def _identified(path: Path, robot: str, radii: tuple[float, ...],
                geometry: ArmGeometry | None) -> ReplayPlant:
    """The robot's scene with the bodies a MODEL.json identified, its own torque the
    feed-forward."""
    payload = read_json(path, "model")
    parameters = model_standard_parameters(payload)
    if parameters is None:
        raise UserError(f"model {path} has no per-body inertial parameters to simulate ('"
                        f"{PARAMETERS_KEY}' or a consistent fit's metrics.physical): a model in "
                        "the robot's base atoms has no bodies; identify with --prior nominal|flat "
                        "or pass a URDF or MJCF with the identified inertials as --plant")
    model = set_standard_parameters(build_scene(robot, radii, geometry).compile(), parameters)
    return ReplayPlant(model, load_torque_model(str(path), robot), str(path), str(path))
