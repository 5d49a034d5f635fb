"""`torquebench ingest`: a measured log (CSV, or a ROS 2 bag of JointState) into the dataset
contract (.npz)."""

from __future__ import annotations

from harness.commands import SUMMARY, add_chain_option, chain_option
from harness.data.bag import is_bag
from harness.data.dataset import check_arrays
from harness.data.ingest import ingest
from harness.errors import UserError
from harness.io import write_npz
from harness.robots.resolve import resolve_arm


def register(sub) -> None:
    p = sub.add_parser("ingest", help=SUMMARY["ingest"],
                       description="Header 't, q1..qn, [qd1..qn], [qdd1..qn], tau1..taun' (s, rad, "
                       "rad/s, rad/s^2, N m; irregular time stamps allowed; .csv.gz read "
                       "compressed). Resampled to the median step; missing qd/qdd estimated by "
                       "Savitzky-Golay differentiation with a window chosen from the data "
                       "(written in meta).")
    p.add_argument("--csv", default=None, help="the log (CSV, or gzipped CSV)")
    p.add_argument("--bag", default=None, metavar="DIR_OR_FILE",
                   help="instead of --csv: a ROS 2 recording (rosbag2, MCAP or SQLite 3: its "
                   "folder, or a storage file in it) of sensor_msgs/JointState (position, "
                   "velocity, effort), the joints taken by the robot file's names")
    p.add_argument("--topic", default=None,
                   help="with --bag: the JointState topic (default: the recording's only one)")
    p.add_argument("--robot", required=True, help="registered robot or URDF/MJCF path")
    add_chain_option(p)
    p.add_argument("--out", required=True, help="output dataset .npz")
    p.add_argument("--rate", type=float, default=None,
                   help="output rate in Hz (every k-th resampled sample, after the "
                   "derivatives; default: the log's median step)")
    p.add_argument("--window", type=int, default=None,
                   help="Savitzky-Golay window (odd, samples of the resampled grid) instead of "
                   "the one chosen from the data")
    p.add_argument("--current-gains", default=None, metavar="K1,...,Kn",
                   help="the effort columns (tau1..taun, or i1..in) are motor currents (A): "
                   "torque = gain x current, gains in N m/A per joint (recorded in meta)")
    p.add_argument("--gains-unknown", action="store_true",
                   help="the effort columns are motor currents (A) whose drive gains are "
                   "unknown: kept as currents (key 'current', no torque in the dataset); "
                   "`identify --data THIS.npz --loaded LOADED.npz --load-mass KG` identifies "
                   "the gains from this run and one carrying a load of known mass")
    p.set_defaults(func=run)


def run(args) -> int:
    if (args.csv is None) == (args.bag is None):
        raise UserError("give exactly one of --csv LOG.csv and --bag ROSBAG2")
    if args.topic is not None and args.bag is None:
        raise UserError("--topic applies to --bag")
    source = args.csv if args.bag is None else args.bag
    if args.csv is not None and is_bag(args.csv):
        raise UserError(f"--csv {args.csv} is a folder or a rosbag2 file: give it as --bag")
    arm = resolve_arm(args.robot, chain=chain_option(args))
    dof = arm.dof
    gains = None
    if args.current_gains is not None:
        try:
            gains = [float(k) for k in args.current_gains.split(",")]
        except ValueError:
            raise UserError(f"--current-gains must be numbers K1,...,Kn (N m/A), got "
                            f"'{args.current_gains}'") from None
    data = ingest(source, arm, args.rate, args.window, gains, args.gains_unknown, args.topic)
    # what the estimated derivatives reach must pass the dataset loader (a jump in q: a spike)
    check_arrays(f"{source} (estimated derivatives)", data.arrays)
    write_npz(args.out, **data.npz())
    meta, d = data.meta, data.meta["derivatives"]
    how = ("qd, qdd as logged" if not d["estimated"] else
           f"{', '.join(d['estimated'])} from {d['source']} by Savitzky-Golay (order "
           f"{d['polyorder']}, window {d['window_samples']} samples = {d['window_s']:.3g} s, "
           + (f"signal band up to {max(d['band_edge_hz']):.3g} Hz)" if "band_edge_hz" in d
              else "given)"))
    print(f"wrote {args.out}: {meta['samples']} samples of {dof} joints at "
          f"{meta['resampling']['rate_out_hz']:.6g} Hz from {meta['raw_samples']} logged "
          f"(steps {meta['raw_step_s']['min'] * 1e3:.3g}-{meta['raw_step_s']['max'] * 1e3:.3g} ms); "
          f"{how}" + ("; effort: motor currents (A), gains unknown" if args.gains_unknown else ""))
    return 0
