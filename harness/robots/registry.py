"""Registry of robots: load one by name into MuJoCo and Pinocchio.

The embedded default is the paper's 3-DOF Lynxmotion arm (models/lynxmotion).
Robots that ship with `example-robot-data` are loaded into both engines from
the package's URDF, with visual and collision meshes dropped so MuJoCo need not
resolve `package://` paths (inertias come from the URDF <inertial> elements).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from importlib import metadata
from pathlib import Path

import mujoco
import pinocchio as pin

from harness.errors import UserError
from harness.robots.urdf import arm_urdf, strip_geometry
from identification.library.chain import ChainError, KinematicChain
from models import MODELS


@dataclass(frozen=True)
class Robot:
    """A robot known to the harness by name."""

    name: str
    urdf: Path
    mjcf: Path | None = None  # robot-only MJCF; None: MuJoCo compiles the URDF
    scene: Path | None = None  # MJCF with floor, light, obstacle
    source: str = ""


@cache
def erd_robots_dir() -> Path:
    """The robots folder installed by the example-robot-data wheel."""
    dist = metadata.distribution("example-robot-data")
    path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    if not path.is_dir():
        raise UserError(f"example-robot-data robots not found at {path}")
    return path


def _erd(name: str, relpath: str) -> Robot:
    return Robot(name=name, urdf=erd_robots_dir() / relpath, source="example-robot-data")


ROBOTS = {
    "lynxmotion": lambda: Robot(
        name="lynxmotion",
        urdf=MODELS / "lynxmotion" / "lynxmotion.urdf",
        mjcf=MODELS / "lynxmotion" / "lynxmotion.xml",
        scene=MODELS / "lynxmotion" / "scene.xml",
        source="paper (see models/lynxmotion/README.md)",
    ),
    "double_pendulum": lambda: _erd(
        "double_pendulum", "double_pendulum_description/urdf/double_pendulum.urdf"
    ),
    "ur5": lambda: _erd("ur5", "ur_description/urdf/ur5_robot.urdf"),
    "panda": lambda: _erd("panda", "panda_description/urdf/panda.urdf"),  # fingers held fixed
}

DEFAULT_ROBOT = "lynxmotion"


def get_robot(name: str) -> Robot:
    """The registered robot called name."""
    if name not in ROBOTS:
        raise UserError(f"unknown robot '{name}' (known: {', '.join(sorted(ROBOTS))})")
    return ROBOTS[name]()


def _arm_urdf_file(path: Path) -> str:
    """arm_urdf of a URDF file; UserError if it is not text."""
    try:
        text = path.read_text()
    except UnicodeDecodeError:
        raise UserError(f"invalid URDF {path}: not a text file") from None
    return arm_urdf(text, str(path))


def load_mujoco(name_or_path: str | Path, scene: bool = False) -> mujoco.MjModel:
    """A MuJoCo model from a registered robot name or any MJCF or URDF file path."""
    path = Path(name_or_path)
    if str(name_or_path) not in ROBOTS:
        if path.suffix.lower() not in (".xml", ".mjcf") and not path.exists():
            get_robot(str(name_or_path))  # raises the unknown-robot error
        if not path.is_file():
            raise UserError(f"plant file not found: {path}")
        # as a registered URDF: arm joints only (arm_urdf's own error stays as it is), no meshes
        urdf = _arm_urdf_file(path) if path.suffix.lower() == ".urdf" else None
        try:
            if urdf is not None:
                return mujoco.MjModel.from_xml_string(strip_geometry(urdf))
            return mujoco.MjModel.from_xml_path(str(path))
        except ValueError as exc:
            detail = " ".join(str(exc).split()) or "parse error"
            kind = "URDF" if path.suffix.lower() == ".urdf" else "MJCF"
            raise UserError(f"invalid {kind} {path}: {detail}") from None
    robot = get_robot(str(name_or_path))
    if robot.mjcf is not None:
        target = robot.scene if scene and robot.scene else robot.mjcf
        return mujoco.MjModel.from_xml_path(str(target))
    return mujoco.MjModel.from_xml_string(strip_geometry(arm_urdf(robot.urdf.read_text(),
                                                                  robot.name)))


def load_pinocchio(name_or_path: str | Path) -> pin.Model:
    """The Pinocchio model of a registered robot (from its URDF) or of a URDF or MJCF path;
    non-arm joints held fixed as in load_mujoco."""
    if str(name_or_path) in ROBOTS:
        urdf = get_robot(str(name_or_path)).urdf
        return pin.buildModelFromXML(arm_urdf(urdf.read_text(), str(name_or_path)))
    path = Path(name_or_path)
    if not path.is_file():
        get_robot(str(name_or_path)) if path.suffix == "" else None  # unknown-robot error
        raise UserError(f"robot file not found: {path}")
    urdf = _arm_urdf_file(path) if path.suffix.lower() == ".urdf" else None
    try:
        if urdf is not None:
            return pin.buildModelFromXML(urdf)
        return pin.buildModelFromMJCF(str(path))
    except (ValueError, RuntimeError) as exc:
        detail = " ".join(str(exc).split()) or "parse error"
        raise UserError(f"Pinocchio cannot read {path}: {detail}") from None


def check_open_chain(model: mujoco.MjModel, name_or_path: str | Path) -> None:
    """UserError if MJCF <equality> constraints close a loop (only open chains are supported)."""
    if model.neq > 0:
        raise UserError(f"robot {name_or_path}: equality constraints close the chain: "
                        "only open serial chains are supported")


def load_chain(name_or_path: str | Path) -> KinematicChain:
    """The robot's kinematic chain (identification.library.chain); UserError unless it is a
    fixed-base serial chain of revolute joints."""
    model = load_pinocchio(name_or_path)
    name = str(name_or_path) if str(name_or_path) in ROBOTS else Path(name_or_path).stem
    if str(name_or_path) not in ROBOTS and Path(name_or_path).suffix.lower() != ".urdf":
        check_open_chain(load_mujoco(name_or_path), name_or_path)
    try:
        chain = KinematicChain.from_pinocchio(model, name)
    except ChainError as exc:
        raise UserError(f"robot {name_or_path}: {exc}") from None
    branches = [j for j, p in enumerate(chain.parents) if p != j - 1]
    if branches:
        raise UserError(f"robot {name_or_path}: joint {branches[0] + 1} does not follow joint "
                        f"{branches[0]}: not a serial chain")
    return chain
