"""`torquebench excite`: the excitation a user records on the robot, designed for identification."""

from __future__ import annotations

import os
from pathlib import Path

from harness.data.excitation_file import write_trajectory
from harness.data.excite import DEFAULT_ACCELERATION, ITERATIONS, design_for
from harness.errors import UserError
from identification.excitation.criteria import CRITERIA


def register(sub) -> None:
    p = sub.add_parser("excite", help="design a rest-to-rest excitation for identification (CSV)")
    p.add_argument("--robot", "--plant", dest="robot", default="lynxmotion",
                   help="robot name (lynxmotion, double_pendulum, ur5, panda) or URDF/MJCF path")
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
                   "(D-optimal: large motions count; on generated Lynxmotion, UR5, Panda "
                   "and xArm7 data 0.2-0.7x the default excitation's error at the same "
                   "sensor noise); condition: the smallest condition number of the "
                   "column-normalized regressor (blind to scale: its designs move little and "
                   "generalize 1.2-6x worse; docs/identification.md, "
                   "'identification.excitation.criteria')")
    p.add_argument("--out", required=True, help="output TRAJ.csv: t,q1..qn,qd1..qdn,qdd1..qddn")
    p.set_defaults(func=run)


def run(args) -> int:
    _check_writable(Path(args.out))
    if args.iterations < 0:
        raise UserError(f"--iterations must be >= 0, got {args.iterations}")
    designed = design_for(args.robot, args.duration, args.rate, args.accel_limit, args.seed,
                          args.iterations, args.harmonics, args.criterion)
    write_trajectory(args.out, designed.trajectory)
    n = len(designed.trajectory.t)
    print(f"wrote {args.out}: {n} samples at {args.rate:g} Hz over {args.duration:g} s, at rest at "
          f"both ends; condition number {designed.condition:.3g} (generate's default excitation "
          f"{designed.default_condition:.3g}; the identification's atoms and offsets, columns "
          "normalized)")
    return 0


def _check_writable(out: Path) -> None:
    """Fail before the design, not after it, when --out cannot be written."""
    folder = out.parent if str(out.parent) else Path(".")
    existing = next((p for p in (folder, *folder.parents) if p.exists()), Path("."))
    if not existing.is_dir() or not os.access(existing, os.W_OK):
        raise UserError(f"cannot write {out}: {existing} is not a writable folder")
