"""The `torquebench` command line (also `python -m harness`).

Each subcommand lives in harness/commands/<name>.py with `register(subparsers)`
adding its parser and setting `func(args) -> int`. User errors print one line
and exit 2; no output file is left behind.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

# MuJoCo picks its GL backend at import: headless EGL unless the user chose one.
if sys.platform.startswith("linux"):
    os.environ.setdefault("MUJOCO_GL", "egl")
# The matrices here are small (thousands x tens): threaded BLAS only adds contention,
# measured 10-100x slower on a loaded 2-core machine. Set before numpy is imported.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from harness import interrupt  # noqa: E402 - after the environment set-up above
from harness.commands import SUMMARY  # noqa: E402
from harness.errors import UserError  # noqa: E402

COMMANDS = ["generate", "ingest", "identify", "predict", "plan", "replay", "closeloop", "bench",
            "study", "sweep", "excite", "export", "robots"]


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("torquebench")
    except PackageNotFoundError:  # run from a checkout that was never installed
        return "unknown (not installed)"


def _command(argv: list[str]) -> str | None:
    """The subcommand argv names (its first word that is one), or None."""
    return next((a for a in argv if a in COMMANDS), None)


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The command line's parser. Only the command argv names is imported (its libraries take
    seconds); the others are listed by their one-line help (harness.commands.SUMMARY), so that
    `--help`, `--version` and a mistyped command answer at once. argv None: every command's
    parser (documentation, tests)."""
    parser = argparse.ArgumentParser(
        prog="torquebench",
        description="Data-driven torque identification and energy-optimal planning, benchmarked "
        "against Pinocchio and replayed in MuJoCo.",
    )
    parser.add_argument("--version", action="version", version=f"torquebench {_version()}")
    sub = parser.add_subparsers(dest="command", required=True)
    wanted = COMMANDS if argv is None else [_command(argv)]
    for name in COMMANDS:  # every command module exists: a missing one is a broken install
        if name in wanted:
            importlib.import_module(f"harness.commands.{name}").register(sub)
        else:
            sub.add_parser(name, help=SUMMARY[name])
    return parser


def _user_errors() -> tuple[type[BaseException], ...]:
    """The errors that mean bad input, not a bug: one line, exit 2."""
    from identification.errors import IdentificationError
    from planning.errors import PlanningError

    return UserError, FileNotFoundError, IdentificationError, PlanningError


DIR_OUTPUTS = ("bench", "study", "closeloop", "sweep")  # commands whose --out is a folder


def _check_output(args) -> None:
    """Fail before the work, not after it, when --out cannot be the file asked for."""
    out = getattr(args, "out", None)
    if out and args.command not in DIR_OUTPUTS and os.path.isdir(out):
        raise UserError(f"output path {out} is a directory, expected a file name")
    if out and args.command in DIR_OUTPUTS and os.path.isfile(out):
        raise UserError(f"output folder {out} is an existing file")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        args = build_parser(argv).parse_args(argv)
    except KeyboardInterrupt:  # while the command's libraries were imported: nothing begun
        print("torquebench: interrupted", file=sys.stderr)
        return 130
    interrupt.install()
    try:
        _check_output(args)
        return int(args.func(args) or 0)
    except _user_errors() as exc:
        message = " ".join(str(exc).split())  # one line, whatever the library wrote
        print(f"torquebench {args.command}: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # result files are written atomically: none is left half-written
        print(f"torquebench {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
