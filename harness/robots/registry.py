"""Registry of robots: load one by name into MuJoCo and Pinocchio.

The embedded default is the paper's 3-DOF Lynxmotion arm (models/lynxmotion).
Robots that ship with `example-robot-data` are loaded into both engines from
the package's URDF, with visual and collision meshes dropped so MuJoCo need not
resolve `package://` paths (inertias come from the URDF <inertial> elements).
"""

from __future__ import annotations

import os
import sys
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cache
from importlib import metadata
from math import pi
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

    name: str  # a registered name, or the path of the robot's file
    urdf: Path | None
    mjcf: Path | None = None  # robot-only MJCF; None: MuJoCo compiles the URDF
    scene: Path | None = None  # MJCF with floor, light, obstacle
    source: str = ""
    # the bench's planning motion: start and goal (rad, one per joint) and the body whose
    # link the obstacle crosses; None: derived from the joint limits
    motion: tuple[tuple[float, ...], tuple[float, ...], str] | None = None
    # identification libraries `identify` offers for it, the first its default ("kinematic":
    # the base atoms generated from its kinematics, for any arm)
    libraries: tuple[str, ...] = ("kinematic",)
    solver: str = "ipopt"  # the planner's NLP solver (planning.penalty.backends)
    # a published library (harness.robots.extras) its data report the conditioning of and
    # its excitation design keeps well conditioned; None: its kinematics' base atoms, reported
    excitation_library: str | None = None
    # reproductions the bench's sections run for this robot beside their common work
    # (harness.robots.extras: "paper", the paper's Tables III-IV and planning scenario)
    extras: tuple[str, ...] = ()
    logs: tuple[str, ...] = ()  # measured logs of this robot shipped under data/


@cache
def erd_robots_dir() -> Path:
    """The robots folder installed by the example-robot-data wheel."""
    dist = metadata.distribution("example-robot-data")
    path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    if not path.is_dir():
        raise UserError(f"example-robot-data robots not found at {path}")
    return path


def _erd(name: str, relpath: str, motion=None, **fields) -> Robot:
    return Robot(name=name, urdf=erd_robots_dir() / relpath, source="example-robot-data",
                 motion=motion, **fields)


ROBOTS = {
    "lynxmotion": lambda: Robot(
        name="lynxmotion",
        urdf=MODELS / "lynxmotion" / "lynxmotion.urdf",
        mjcf=MODELS / "lynxmotion" / "lynxmotion.xml",
        scene=MODELS / "lynxmotion" / "scene.xml",
        source="paper (see models/lynxmotion/README.md)",
        # the paper's 3-DOF arm: its prior-knowledge library; fatrop, faster than IPOPT on
        # its compiled NLP (docs/realtime.md, 'Nominal clock')
        # the paper scenario's start and goal; the obstacle crosses the forearm
        motion=((pi / 2, pi / 5, -pi / 4), (-pi / 2, 2 * pi / 5, -pi / 3), "link3"),
        libraries=("prior", "kinematic", "prior-general", "paper"), solver="fatrop",
        excitation_library="paper", extras=("paper",),
    ),
    "double_pendulum": lambda: _erd(
        "double_pendulum", "double_pendulum_description/urdf/double_pendulum.urdf"
    ),
    "ur5": lambda: _erd("ur5", "ur_description/urdf/ur5_robot.urdf",
                        ((1.2, -1.0, 1.2, -1.5, -1.5, 0.0), (-1.2, -1.4, 1.6, -1.0, -1.5, 0.5),
                         "forearm_link")),
    "panda": lambda: _erd("panda", "panda_description/urdf/panda.urdf",  # fingers held fixed
                          ((1.0, 0.5, 0.0, -2.4, 0.0, 2.8, 0.8),
                           (-1.0, -0.3, 0.0, -1.5, 0.0, 1.6, 0.8), "panda_link4"),
                          logs=("panda_gaz2019",)),
}

DEFAULT_ROBOT = "lynxmotion"
FLANGES = ("tool0", "panda_link8", "ee_link", "end_effector")  # first one a model has


def flange_frame(model: pin.Model) -> str | None:
    """The flange frame of the arm's Pinocchio model, or None (last joint's origin)."""
    names = {f.name for f in model.frames}
    return next((f for f in FLANGES if f in names), None)


def get_robot(name: str) -> Robot:
    """The registered robot called name."""
    if name not in ROBOTS:
        raise UserError(f"unknown robot '{name}' (known: {', '.join(sorted(ROBOTS))})")
    return ROBOTS[name]()


def robot_entry(name_or_path: str | Path) -> Robot:
    """The registry entry of a registered robot, or an entry with the defaults for the URDF or
    MJCF file at name_or_path (UserError if it is neither)."""
    if str(name_or_path) in ROBOTS:
        return get_robot(str(name_or_path))
    path = Path(name_or_path)
    if not path.is_file():
        get_robot(str(name_or_path)) if path.suffix == "" else None  # unknown-robot error
        raise UserError(f"robot file not found: {path}")
    urdf = path.suffix.lower() == ".urdf"
    return Robot(name=str(path), urdf=path if urdf else None, mjcf=None if urdf else path,
                 source=str(path))


def identified_robot(recorded: dict, robot: str | None, path) -> str:
    """The robot a model file at path is used with: robot (default: the one its record
    {"name", "hash"} names), checked against the record's kinematics hash. UserError when no
    such robot can be found, IdentificationError when its kinematics differ."""
    from identification.errors import IdentificationError

    robot = robot or recorded.get("name")
    if not robot or (robot not in ROBOTS and not Path(robot).is_file()):
        raise UserError(f"model {path} was identified for robot '{str(recorded.get('name')):.60}'"
                        ": pass its URDF/MJCF with --robot")
    chain = load_chain(robot)
    if recorded.get("hash") != chain.digest():
        raise IdentificationError(f"model was identified for robot '{str(recorded.get('name')):.60}' "
                                  f"(kinematics {str(recorded.get('hash')):.20}), not "
                                  f"'{chain.name}' ({chain.digest()})")
    return robot


def robot_reference(name_or_path: str | Path) -> str:
    """How data and plans record a robot: its registered name, or its file's absolute path
    (so the record still finds it from another working directory)."""
    name = str(name_or_path)
    return name if name in ROBOTS or not Path(name).is_file() else str(Path(name).resolve())


def recorded_robot(record: dict) -> str | None:
    """The robot a dataset's meta or a PLAN.json records ('robot', else 'plant'): a registered
    name or the path of its file; None when it records none. UserError when the recorded
    robot is neither registered nor an existing file (the caller's --robot then names it)."""
    robot = record.get("robot") or record.get("plant") if isinstance(record, dict) else None
    if robot is None or robot == "":
        return None
    if not isinstance(robot, str) or not (robot in ROBOTS or ("\0" not in robot
                                                              and Path(robot).is_file())):
        raise UserError(f"the data record robot {str(robot)[:60]!r}, neither a registered robot "
                        "nor an existing URDF/MJCF file: pass --robot")
    return robot


def data_robot(record: dict, given: str | None = None) -> str:
    """The robot a command works on: --robot if given, else the robot the data (or plan)
    record, else the default robot. Every command infers a data's robot here."""
    return given or recorded_robot(record) or DEFAULT_ROBOT


# What Pinocchio's bindings raise on a description they cannot map (boost.python's
# translation of std::invalid_argument, runtime_error, out_of_range, overflow_error).
PINOCCHIO_ERRORS = (ValueError, RuntimeError, IndexError, OverflowError)


@contextmanager
def native_output(lines: list[str]):
    """Collect what C/C++ parsers print on file descriptors 1 and 2 (urdfdom's parse errors,
    TinyXML's warnings) into lines instead of the user's terminal; the caller decides."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 1)
        os.dup2(tmp.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            tmp.seek(0)
            lines += [x.strip() for x in tmp.read().decode(errors="replace").splitlines()
                      if x.strip()]


def _parse(build, path: Path, problem: str):
    """build() under native_output: its printout is re-issued as one warning line on success
    and becomes the detail of the UserError on failure."""
    printed: list[str] = []
    try:
        with native_output(printed):
            model = build()
    except (mujoco.FatalError, *PINOCCHIO_ERRORS) as exc:
        detail = " ".join(str(exc).split()) or "; ".join(printed[:2]) or "parse error"
        raise UserError(f"{problem}: {detail}") from None
    # urdfdom reports an element it could not parse, and goes on without it; MuJoCo warns of a
    # NaN in the file and builds a model with it
    errors = [line for line in printed
              if line.lower().startswith("error") or "contains a 'nan'" in line.lower()]
    if errors:
        raise UserError(f"{problem}: {'; '.join(' '.join(e.split()) for e in errors[:2])}")
    if printed:
        print(f"torquebench: warning: {path}: {'; '.join(printed[:3])}", file=sys.stderr)
    return model


def load_mujoco(name_or_path: str | Path, scene: bool = False) -> mujoco.MjModel:
    """A MuJoCo model from a registered robot name or any MJCF or URDF file path."""
    path = Path(name_or_path)
    if str(name_or_path) not in ROBOTS:
        if path.suffix.lower() not in (".xml", ".mjcf") and not path.exists():
            get_robot(str(name_or_path))  # raises the unknown-robot error
        if not path.is_file():
            raise UserError(f"plant file not found: {path}")
        if path.suffix.lower() == ".urdf":  # as a registered URDF: arm joints only, no meshes
            text = strip_geometry(arm_urdf(read_text(path), str(path)))
            return _parse(lambda: mujoco.MjModel.from_xml_string(text), path, f"invalid URDF {path}")
        return _parse(lambda: mujoco.MjModel.from_xml_path(str(path)), path, f"invalid MJCF {path}")
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
    if path.suffix.lower() == ".urdf":
        text = arm_urdf(read_text(path), str(path))
        return _parse(lambda: pin.buildModelFromXML(text), path, f"Pinocchio cannot read {path}")
    return _parse(lambda: pin.buildModelFromMJCF(str(path)), path, f"Pinocchio cannot read {path}")


def read_text(path: Path) -> str:
    """A robot description's text; UserError if it is not readable UTF-8 text."""
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise UserError(f"robot file {path} is not UTF-8 text") from None
    except OSError as exc:
        raise UserError(f"cannot read robot file {path}: {exc.strerror}") from None


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
