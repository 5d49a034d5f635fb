"""What `replay --plant` simulates: the robot's own scene, another URDF or MJCF of it, or
the dynamics an identified MODEL.json believes (its standard parameters on the robot's
bodies), with the feed-forward that plant's model computes."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from harness.errors import UserError
from harness.io import read_json
from harness.replay.friction import PlantFriction
from harness.robots.arm import Arm
from harness.robots.inertials import PARAMETERS_KEY, model_standard_parameters, set_standard_parameters
from harness.robots.scene import build_scene, replay_scene
from harness.robots.torque_models import load_torque_model
from identification.torque_model import TorqueModel
from planning.formulation.kinematics import ArmGeometry


@dataclass(frozen=True)
class ReplayPlant:
    """The MuJoCo plant, the feed-forward model and how REPLAY.json names them; friction:
    what the plant's joints feel beyond MuJoCo's own (an identified model's sigmoid or
    Stribeck law), None when nothing."""

    model: mujoco.MjModel
    feedforward: TorqueModel
    label: str
    feedforward_label: str
    friction: PlantFriction | None = None


def replay_plant(plant: str | None, arm: Arm, radii: tuple[float, ...] = (),
                 geometry: ArmGeometry | None = None) -> ReplayPlant:
    """The plant `replay --plant` names (None: the arm's replay scene), where a scene is
    built the link capsules of geometry (the plan's), else of these radii (m) on the
    joint-origin segments; UserError in one line when it cannot be one (a URDF or MJCF of
    another robot's kinematics among them: a URDF or MJCF of the robot is its own Arm,
    whose kinematics hash is the arm's)."""
    if plant is None:
        return ReplayPlant(replay_scene(arm, tuple(radii), geometry), arm.nominal,
                           arm.reference, "pinocchio")
    path = Path(plant)
    if not path.is_file():
        raise UserError(f"plant file not found: {path}")
    if path.suffix.lower() == ".json":
        return _identified(path, arm, radii, geometry)
    other = Arm.of(path)
    if path.suffix.lower() != ".urdf" and other.mujoco.nu:
        # an MJCF scene with its own motors (and obstacle), simulated as it is
        _check_scene(other.mujoco, arm, path)
        return ReplayPlant(other.mujoco, arm.nominal, str(path), "pinocchio")
    if other.record["hash"] != arm.record["hash"]:
        raise UserError(f"plant {path} is not robot {arm.label}: its kinematics "
                        f"({other.record['hash']}) are not the arm's ({arm.record['hash']})")
    return ReplayPlant(build_scene(other, radii, geometry).compile(), other.nominal, str(path),
                       f"pinocchio {path}")


def _check_scene(model: mujoco.MjModel, arm: Arm, path: Path, tolerance: float = 1e-6) -> None:
    """UserError unless the MuJoCo scene at path moves arm's joints: its hinges' anchors and
    axes are the arm's at a few angles within its limits. (A scene is checked in MuJoCo, which
    alone simulates it: Pinocchio, whose model the kinematics hash reads, does not follow a
    scene's <include>.)"""
    hinges = np.flatnonzero(model.jnt_type == mujoco.mjtJoint.mjJNT_HINGE)
    same = len(hinges) == model.njnt == arm.dof
    if same:
        geometry, data = arm.geometry, mujoco.MjData(model)
        lower, upper = (np.clip(b, -np.pi, np.pi) for b in arm.position_limits)
        for q in np.random.default_rng(0).uniform(lower, upper, (3, arm.dof)):
            data.qpos[model.jnt_qposadr[hinges]] = q
            mujoco.mj_kinematics(model, data)
            origins, rotations = (x[0] for x in geometry.joint_frames(q))
            axes = np.einsum("jik,jk->ji", rotations, np.asarray(geometry.axes, float))
            same &= bool(np.allclose(data.xanchor[hinges], origins, atol=tolerance)
                         and np.allclose(data.xaxis[hinges], axes, atol=tolerance))
    if not same:
        raise UserError(f"plant {path} is not robot {arm.label}: its {model.njnt} joints are "
                        "not the arm's")


def _identified(path: Path, arm: Arm, radii: tuple[float, ...],
                geometry: ArmGeometry | None) -> ReplayPlant:
    """The arm's scene with the bodies, armature, damping and dry friction a MODEL.json
    identified, the friction of its laws with a column of their own applied as a torque the
    joints feel (MuJoCo has no such friction), its own torque the feed-forward. Its sensor
    offsets are in neither: an offset is the run's, not a torque the motors spend."""
    payload = read_json(path, "model")
    parameters = model_standard_parameters(payload)
    if parameters is None:
        raise UserError(f"model {path} has no per-body inertial parameters to simulate ('"
                        f"{PARAMETERS_KEY}' or a consistent fit's metrics.physical): a model in "
                        "the robot's base atoms has no bodies; identify with --prior nominal|flat "
                        "or pass a URDF or MJCF with the identified inertials as --plant")
    model = set_standard_parameters(build_scene(arm, radii, geometry).compile(), parameters)
    feedforward = load_torque_model(str(path), arm)
    return ReplayPlant(model, feedforward, str(path), str(path), PlantFriction.of(feedforward))
