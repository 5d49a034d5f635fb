"""`torquebench robots`: the registered robots and the URDFs example-robot-data installs.

Each is a `--robot` value: a registered name, or any URDF's path (example-robot-data 6 has
no Python module to find them: they are under its cmeel prefix, the folder printed here).
Nothing is parsed: a URDF listed is not known to be an arm the harness takes (a fixed-base
serial chain of revolute joints) until a command loads it.
"""

from __future__ import annotations

from harness.commands import SUMMARY
from harness.errors import UserError
from harness.robots.registry import DEFAULT_ROBOT, ROBOTS, erd_robots_dir, get_robot


def register(sub) -> None:
    p = sub.add_parser("robots", help=SUMMARY["robots"],
                       description="The registered robots (--robot NAME) and the URDF files "
                       "example-robot-data installs, with their paths (--robot PATH).")
    p.add_argument("--registered", action="store_true",
                   help="only the registered robots, not example-robot-data's URDFs")
    p.set_defaults(func=run)


def registered_lines() -> list[str]:
    """One line per registered robot: its name, its file and where it comes from."""
    lines = []
    for name in ROBOTS:
        robot = get_robot(name)
        default = " (default)" if name == DEFAULT_ROBOT else ""
        lines.append(f"  {name}{default}: {robot.urdf or robot.mjcf} [{robot.source}]")
    return lines


def erd_lines() -> list[str]:
    """example-robot-data's folder and its URDFs' paths, sorted."""
    try:
        folder = erd_robots_dir()
    except UserError as exc:
        return [f"example-robot-data: {exc}"]
    files = sorted(folder.rglob("*.urdf"))
    return [f"example-robot-data's URDFs ({len(files)}, under {folder}; pass a path as "
            "--robot PATH):", *(f"  {path}" for path in files)]


def run(args) -> int:
    lines = ["registered robots (--robot NAME):", *registered_lines()]
    if not args.registered:
        lines += ["", *erd_lines()]
    print("\n".join(lines))
    return 0
