"""`torquebench excite`: the excitation a user records on the robot, designed for identification."""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

from harness.commands import SUMMARY, add_chain_option, chain_option
from harness.data.excitation_file import write_trajectory
from harness.data.excite import DEFAULT_ACCELERATION, ITERATIONS, design_for, floor_below_home
from harness.data.generate import CONDITION_MEANING, CONDITION_WORDS
from harness.errors import UserError
from harness.robots.resolve import resolve_arm
from identification.excitation.criteria import CRITERIA


def register(sub) -> None:
    p = sub.add_parser("excite", help=SUMMARY["excite"])
    p.add_argument("--robot", "--plant", dest="robot", default="lynxmotion",
                   help="robot name (lynxmotion, double_pendulum, ur5, panda) or URDF/MJCF path")
    add_chain_option(p)
    p.add_argument("--duration", type=float, required=True, help="period of the excitation (s)")
    p.add_argument("--rate", type=float, required=True, help="sample rate of the file (Hz)")
    p.add_argument("--accel-limit", dest="accel_limit", type=float, default=DEFAULT_ACCELERATION,
                   help=f"joint acceleration limit (rad/s^2, default {DEFAULT_ACCELERATION:g})")
    p.add_argument("--harmonics", type=int, default=None,
                   help="harmonics per joint (default: the highest near 1 Hz, 5 to 20)")
    p.add_argument("--seed", type=int, default=0, help="seed of the random starting candidates")
    p.add_argument("--iterations", type=int, default=ITERATIONS,
                   help=f"optimizer (SLSQP) iterations at most (default {ITERATIONS})")
    p.add_argument("--criterion", choices=sorted(CRITERIA), default="information",
                   help="information (the default): the largest log det of the regressor's Gram "
                   "(D-optimal: large motions count); condition: the smallest condition number "
                   "of the column-normalized regressor (blind to scale: its designs move "
                   "little; how the two compare: docs/identification.md, "
                   "'identification.excitation.criteria')")
    p.add_argument("--floor", type=_height, default=0.0,
                   help="height (m, in the robot's base frame) of the floor every moving link "
                   "stays above, or 'none' for an arm not standing on one (a humanoid's; "
                   "default 0: the base's plane)")
    p.add_argument("--out", required=True, help="output TRAJ.csv: t,q1..qn,qd1..qdn,qdd1..qddn")
    p.set_defaults(func=run)


def run(args) -> int:
    _check_writable(Path(args.out))
    if args.iterations < 0:
        raise UserError(f"--iterations must be >= 0, got {args.iterations}")
    arm = resolve_arm(args.robot, chain=chain_option(args))
    lowest = floor_below_home(arm, args.floor)
    if lowest is not None:
        print(f"note: at q = 0 the arm reaches z = {lowest:.3g} m, below the floor at "
              f"{args.floor:g} m that the excitation will keep every moving link above: give "
              "--floor HEIGHT (or --floor none) if the robot does not stand on it", file=sys.stderr)
    designed = design_for(arm, args.duration, args.rate, args.accel_limit, args.seed,
                          args.iterations, args.harmonics, args.criterion, args.floor,
                          Progress())
    write_trajectory(args.out, designed.trajectory)
    design = designed.design
    if design.stuck and args.iterations > 0:
        print(f"note: the optimizer did not improve on its random start (SLSQP: "
              f"{design.message or 'no result'}): the file is that start; try another --seed",
              file=sys.stderr)
    elif not design.converged and args.iterations > 0:
        print(f"note: the design is {design.convergence()}: more --iterations may improve it",
              file=sys.stderr)
    n = len(designed.trajectory.t)
    print(f"wrote {args.out}: {n} samples at {args.rate:g} Hz over {args.duration:g} s, at rest at "
          f"both ends; {CONDITION_WORDS} {designed.condition:.3g} (generate's default "
          f"excitation's {designed.default_condition:.3g}; {CONDITION_MEANING})")
    return 0


class Progress:
    """One line on stderr at most every EVERY_S seconds of the design: a long design (a
    6-joint arm at 20 s took ten minutes on a 2-core machine) is not silent."""

    EVERY_S = 30.0

    def __init__(self):
        self.began = self.said = time.perf_counter()

    def __call__(self, iteration: int, iterations: int) -> None:
        now = time.perf_counter()
        if now - self.said >= self.EVERY_S:
            self.said = now
            print(f"excite: designing, optimizer iteration {iteration} of at most {iterations}, "
                  f"{now - self.began:.0f} s so far", file=sys.stderr, flush=True)


def _height(text: str) -> float | None:
    """--floor's value: a height (m) or None for 'none'."""
    if text.strip().lower() == "none":
        return None
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a height (m) or 'none', got {text!r}") from None


def _check_writable(out: Path) -> None:
    """Fail before the design, not after it, when --out cannot be written."""
    folder = out.parent if str(out.parent) else Path(".")
    existing = next((p for p in (folder, *folder.parents) if p.exists()), Path("."))
    if not existing.is_dir() or not os.access(existing, os.W_OK):
        raise UserError(f"cannot write {out}: {existing} is not a writable folder")
