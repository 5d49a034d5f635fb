"""`torquebench generate`: torque data from a MuJoCo plant."""

from __future__ import annotations

import sys

from harness.commands import SUMMARY, add_chain_option, chain_option
from harness.data.excitation_file import read_trajectory
from harness.data.generate import CONDITION_MEANING, CONDITION_WORDS, generate
from harness.io import write_npz
from harness.robots.resolve import resolve_arm
from identification.metrics import error_figures, error_words

SAMPLES = 4000  # without --excitation


def register(sub) -> None:
    p = sub.add_parser("generate", help=SUMMARY["generate"])
    p.add_argument("--plant", "--robot", dest="plant", default="lynxmotion",
                   help="robot name (lynxmotion, double_pendulum, ur5, panda) or URDF/MJCF path")
    add_chain_option(p)
    p.add_argument("--samples", type=int, default=None,
                   help="samples (default 4000, or every row of --excitation)")
    p.add_argument("--noise", type=float, default=0.05, help="torque noise std / torque std")
    p.add_argument("--bias", type=float, default=0.2, help="noise mean in units of its std")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the noise, the sensor bias and the default excitation (default 0)")
    p.add_argument("--mode", choices=["inverse", "measured"], default="inverse",
                   help="inverse: MuJoCo inverse dynamics along the excitation (the default); "
                   "measured: MuJoCo tracks it, encoders and torque sensors read, derivatives "
                   "estimated as from a real log")
    p.add_argument("--excitation", default=None, metavar="TRAJ.csv",
                   help="generate along this excitation (from `torquebench excite`; measured mode "
                   "tracks it from t = 0, as a robot would record it)")
    p.add_argument("--out", required=True, help="output .npz")
    p.set_defaults(func=run)


def run(args) -> int:
    arm = resolve_arm(args.plant, chain=chain_option(args))
    excitation = None
    if args.excitation is not None:
        excitation = read_trajectory(args.excitation, arm.dof)
    samples = args.samples if args.samples is not None else (
        SAMPLES if excitation is None else len(excitation.t))
    ds = generate(arm, samples, args.noise, args.seed, args.mode, args.bias,
                  excitation=excitation)
    write_npz(args.out, **ds.arrays())
    meta = ds.meta
    line = (f"wrote {args.out}: {samples} samples, mode {args.mode}, "
            f"noise {args.noise:g}, {_library(meta)}; {CONDITION_WORDS} "
            f"{meta['condition_number']:.3g} ({CONDITION_MEANING})")
    print(line)
    if args.mode == "measured":
        print(f"  the estimated states' {error_words('states', 'all samples')}: "
              f"qd {error_figures(meta['qd_rel_rmse'])}, qdd {error_figures(meta['qdd_rel_rmse'])}, "
              f"the torque from them {error_figures(meta.get('tau_from_states_rel_rmse', []))} "
              "(MuJoCo's qdd jitters step to step: the estimate is smoother than it)",
              file=sys.stdout)
    return 0


def _library(meta: dict) -> str:
    return (f"{meta['library']} library rank {meta['library_rank']}/{meta['library_size']} "
            f"(its columns' condition {meta['library_condition']:.3g} on this motion)")

