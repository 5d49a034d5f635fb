"""Registry of robots: what the harness knows of a robot by name (its files, its bench motion,
its libraries, its planner's solver). A robot is resolved and loaded once per command by
harness.robots.arm (Arm); this module only names the files.

The embedded default is the paper's 3-DOF Lynxmotion arm (models/lynxmotion).
Robots that ship with `example-robot-data` are loaded from the package's URDF.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from importlib import metadata
from math import pi
from pathlib import Path

import pinocchio as pin

from harness.errors import UserError
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
    # `plan`'s obstacle path when none is given: its centre at t = 0 and at the end (m); None:
    # the paper scenario's, with a notice that it is not placed for this robot
    obstacle: tuple[tuple[float, ...], tuple[float, ...]] | None = None
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
    # the arm between two links of a whole robot's URDF (base link, tip link), every other
    # joint held fixed (harness.robots.subchain); None: the file's arm joints
    chain: tuple[str, str] | None = None
    hold: tuple[tuple[str, float], ...] = ()  # positions stated for held joints (--hold)


CHAIN_MARK = "#"  # an Arm's reference of a chain: FILE#BASE_LINK:TIP_LINK[@JOINT=POSITION,...]


def split_reference(reference: str) -> tuple[str, str | None]:
    """(robot name or file, chain 'BASE:TIP' or None) of an Arm's reference."""
    if CHAIN_MARK in reference and reference not in ROBOTS and not Path(reference).is_file():
        robot, chain = reference.rsplit(CHAIN_MARK, 1)
        return robot, chain
    return reference, None


def reference_name(reference: str, form: str, stem: bool) -> str:
    """A short name of an Arm's reference: the registered name, else its file's name (stem:
    without the suffix); a chain's put into form ("{name}", "{chain}")."""
    robot, chain = split_reference(reference)
    name = robot if robot in ROBOTS else (Path(robot).stem if stem else Path(robot).name)
    return name if chain is None else form.format(name=name, chain=chain)


def chain_reference(robot: str, chain: str | None) -> str:
    """The reference of robot's arm between the links chain names (robot itself if None)."""
    return robot if not chain else f"{robot}{CHAIN_MARK}{chain}"


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
        obstacle=((0.15, 0.40, 0.22), (0.18, -0.35, 0.28)),
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
        raise UserError(f"unknown robot '{name}' (known: {', '.join(sorted(ROBOTS))}; or a URDF/MJCF "
                        "file's path: `torquebench robots` lists example-robot-data's)")
    return ROBOTS[name]()


def robot_entry(name_or_path: str | Path) -> Robot:
    """The registry entry of a registered robot, or an entry with the defaults for the URDF or
    MJCF file at name_or_path (UserError if it is neither); a reference with a chain
    (chain_reference) gives the entry of that chain of the robot's URDF."""
    robot, chain = split_reference(str(name_or_path))
    if chain is not None:
        from harness.robots.subchain import parse_chain, parse_hold

        entry, links = robot_entry(robot), parse_chain(chain)
        if entry.urdf is None:
            raise UserError(f"--chain needs the robot's URDF: {entry.mjcf} is an MJCF")
        return Robot(name=str(name_or_path), urdf=entry.urdf, source=entry.source, chain=links,
                     hold=parse_hold(chain))
    if str(name_or_path) in ROBOTS:
        return get_robot(str(name_or_path))
    path = Path(name_or_path)
    if not path.is_file():
        get_robot(str(name_or_path)) if path.suffix == "" else None  # unknown-robot error
        raise UserError(f"robot file not found: {path}")
    urdf = path.suffix.lower() == ".urdf"
    if path.suffix.lower() not in (".urdf", ".xml", ".mjcf") and not _looks_like_xml(path):
        raise UserError(f"--robot takes a registered name or a robot file (URDF or MJCF, XML): "
                        f"{path} is not XML" + (f" (a {path.suffix} file)" if path.suffix else ""))
    return Robot(name=str(path), urdf=path if urdf else None, mjcf=None if urdf else path,
                 source=str(path))


def _looks_like_xml(path: Path) -> bool:
    """Whether the file at path opens as XML does (its first character, past white space and a
    byte-order mark, is '<')."""
    with open(path, "rb") as f:
        head = f.read(512).lstrip(b"\xef\xbb\xbf \t\r\n")
    return head.startswith(b"<")


def robot_reference(name_or_path: str | Path) -> str:
    """How data and plans record a robot: its registered name, or its file's absolute path
    (so the record still finds it from another working directory)."""
    name = str(name_or_path)
    return name if name in ROBOTS or not Path(name).is_file() else str(Path(name).resolve())
