"""`torquebench robots`: the registered robots and the URDFs example-robot-data installs.

Each is a `--robot` value: a registered name, or any URDF's path (example-robot-data 6 has
no Python module to find them: they are under its cmeel prefix, the folder printed here).
Every one listed is loaded as an Arm (both engines, its chain checked, about 0.01 s a file):
those that load are listed as usable with their joint count, the others apart with the
reason a command would give (a whole robot's arm: --chain BASE_LINK:TIP_LINK).
"""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

from harness.commands import SUMMARY
from harness.errors import UserError
from harness.robots.registry import DEFAULT_ROBOT, ROBOTS, erd_robots_dir, get_robot


def register(sub) -> None:
    p = sub.add_parser("robots", help=SUMMARY["robots"],
                       description="The registered robots (--robot NAME) and the URDF files "
                       "example-robot-data installs, with their paths (--robot PATH), each "
                       "loaded to check that a command takes it.")
    p.add_argument("--registered", action="store_true",
                   help="only the registered robots, not example-robot-data's URDFs")
    p.set_defaults(func=run)


def check(robot: str | Path) -> tuple[int | None, str]:
    """(joint count, "") when robot loads as an Arm in both engines, else (None, the reason:
    the command's error line without the file's path); notes printed while loading are
    dropped (a command on the robot prints them)."""
    from harness.robots.arm import Arm

    try:
        with contextlib.redirect_stderr(io.StringIO()):
            arm = Arm.of(robot)
            arm.mujoco  # noqa: B018 - MuJoCo's compile, beside Pinocchio's chain
            return arm.dof, ""
    except UserError as exc:
        return None, re.sub(rf"^.*?{re.escape(str(robot))}:\s*", "", str(exc))


def registered_lines() -> list[str]:
    """One line per registered robot: its name, its file, where it comes from, and its joint
    count (or why it does not load)."""
    lines = []
    for name in ROBOTS:
        robot = get_robot(name)
        default = " (default)" if name == DEFAULT_ROBOT else ""
        dof, reason = check(name)
        state = f"{dof} joints" if dof else f"NOT USABLE: {reason}"
        lines.append(f"  {name}{default}: {robot.urdf or robot.mjcf} [{robot.source}]; {state}")
    return lines


def erd_lines() -> list[str]:
    """example-robot-data's folder and its URDFs' paths, sorted: the usable ones with their
    joint count, then the others with the reason."""
    try:
        folder = erd_robots_dir()
    except UserError as exc:
        return [f"example-robot-data: {exc}"]
    files = sorted(folder.rglob("*.urdf"))
    checked = [(path, *check(path)) for path in files]
    usable = [f"  {path}: {dof} joints" for path, dof, _ in checked if dof]
    refused = [f"  {path}: {reason}" for path, dof, reason in checked if not dof]
    return [f"example-robot-data's URDFs ({len(files)}, under {folder}; pass a path as "
            f"--robot PATH), each loaded as an arm; usable ({len(usable)}):", *usable, "",
            f"not usable as they are ({len(refused)}; a whole robot's arm: --robot PATH "
            "--chain BASE_LINK:TIP_LINK):", *refused]


def run(args) -> int:
    lines = ["registered robots (--robot NAME):", *registered_lines()]
    if not args.registered:
        lines += ["", *erd_lines()]
    print("\n".join(lines))
    return 0
