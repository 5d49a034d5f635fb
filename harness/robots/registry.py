"""Registry of robots: load one by name into MuJoCo and Pinocchio.

The embedded default is the paper's 3-DOF Lynxmotion arm (models/lynxmotion).
Robots that ship with `example-robot-data` are loaded into both engines from
the package's URDF, with visual and collision meshes dropped so MuJoCo need not
resolve `package://` paths (inertias come from the URDF <inertial> elements).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache
from importlib import metadata
from pathlib import Path

import mujoco
import pinocchio as pin

from harness.errors import UserError
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
}

DEFAULT_ROBOT = "lynxmotion"


def get_robot(name: str) -> Robot:
    """The registered robot called name."""
    if name not in ROBOTS:
        raise UserError(f"unknown robot '{name}' (known: {', '.join(sorted(ROBOTS))})")
    return ROBOTS[name]()


def _strip_geometry(urdf_text: str) -> str:
    """Drop <visual> and <collision> blocks and tell MuJoCo to keep every body."""
    text = re.sub(r"<visual\b.*?</visual>", "", urdf_text, flags=re.S)
    text = re.sub(r"<collision\b.*?</collision>", "", text, flags=re.S)
    # ROS writes lower = upper = 0 for "no limit"; MuJoCo would warn and ignore it.
    text = re.sub(r'lower="0"\s+upper="0"', "", text)
    compiler = (
        '<mujoco><compiler angle="radian" discardvisual="true" fusestatic="false" '
        'inertiafromgeom="false" autolimits="true"/></mujoco>'
    )
    return re.sub(r"(<robot\b[^>]*>)", r"\1" + compiler, text, count=1)


def load_mujoco(name_or_path: str | Path, scene: bool = False) -> mujoco.MjModel:
    """A MuJoCo model from a registered robot name or any MJCF or URDF file path."""
    path = Path(name_or_path)
    if str(name_or_path) not in ROBOTS:
        if path.suffix.lower() not in (".xml", ".mjcf") and not path.exists():
            get_robot(str(name_or_path))  # raises the unknown-robot error
        if not path.is_file():
            raise UserError(f"plant file not found: {path}")
        try:
            if path.suffix.lower() == ".urdf":  # as a registered URDF: meshes dropped, ROS limits fixed
                return mujoco.MjModel.from_xml_string(_strip_geometry(path.read_text()))
            return mujoco.MjModel.from_xml_path(str(path))
        except ValueError as exc:
            detail = " ".join(str(exc).split()) or "parse error"
            kind = "URDF" if path.suffix.lower() == ".urdf" else "MJCF"
            raise UserError(f"invalid {kind} {path}: {detail}") from None
    robot = get_robot(str(name_or_path))
    if robot.mjcf is not None:
        target = robot.scene if scene and robot.scene else robot.mjcf
        return mujoco.MjModel.from_xml_path(str(target))
    return mujoco.MjModel.from_xml_string(_strip_geometry(robot.urdf.read_text()))


def load_pinocchio(name: str) -> pin.Model:
    """The Pinocchio model of a registered robot, built from its URDF."""
    return pin.buildModelFromUrdf(str(get_robot(name).urdf))
