"""`torquebench identify`: sparse torque model from a dataset .npz -> MODEL.json."""

from __future__ import annotations

import sys
import warnings

from harness.data.runs import join, load_runs, split_files
from harness.io import write_json
from harness.robots.registry import DEFAULT_ROBOT, ROBOTS, robot_entry
from harness.robots.torque_models import library_named, robot_record
from identification.errors import IdentificationError
from identification.identify import identify

LIBRARIES = ("auto", "kinematic", "prior", "prior-general", "paper", "generic")
METHODS = ("auto", "coupled", "per-joint", "jointwise")


def register(sub) -> None:
    p = sub.add_parser("identify", help="identify a sparse torque model from data")
    p.add_argument("--data", required=True,
                   help="dataset .npz with q, qd, qdd, tau [, tau_clean], or several runs of the "
                   "same robot: A.npz,B.npz (each with its own derivative estimate)")
    p.add_argument("--validate", default=None,
                   help="FILE.npz[,...]: score on these logs, never used in fitting (then "
                   "--data is fitted whole and --holdout is not used)")
    p.add_argument("--out", required=True, help="output MODEL.json")
    p.add_argument("--holdout", type=float, default=0.25,
                   help="last fraction of samples (time order, over the --data runs in the "
                   "order given) held out for scoring, in (0, 1)")
    p.add_argument("--robot", default=None,
                   help="robot name or URDF/MJCF path (default: the robot the data were generated "
                   f"on if registered, else {DEFAULT_ROBOT})")
    p.add_argument("--library", choices=LIBRARIES, default="auto",
                   help="kinematic: base atoms generated from the robot's kinematics (any arm); "
                   "prior: derived from simple structures (3-DOF arm, symmetric links); "
                   "prior-general: the same without the symmetric-link assumption; paper: the published "
                   "75 features; generic: polynomial x trig (any dof); auto: the first library "
                   "the robot's registry entry offers (prior on the paper's Lynxmotion, kinematic "
                   "on any other robot)")
    p.add_argument("--method", choices=METHODS, default="auto",
                   help="coupled: one Lagrangian, atoms shared by all joints (needs the prior "
                   "library); per-joint: the paper's regression of each joint alone; jointwise: "
                   "atoms on the joints whose torque passes a Lagrangian F-test, features "
                   "elsewhere; auto: coupled when the library allows it")
    p.set_defaults(func=run)



def data_robot(meta: dict, given: str | None) -> str:
    """--robot if given, else the registered robot the data were generated on, else the default."""
    if given:
        return given
    plant = str(meta.get("plant", ""))
    return plant if plant in ROBOTS else DEFAULT_ROBOT


def choose_library(name: str, dof: int, robot: str = DEFAULT_ROBOT):
    """The library called name ('auto': the first the robot's registry entry offers)."""
    if name == "auto":
        name = robot_entry(robot).libraries[0]
    return library_named(name, robot, dof)


def run(args) -> int:
    if not 0.0 < args.holdout < 1.0:  # 0 would score the training data as "held out"
        raise IdentificationError(f"--holdout must be in (0, 1), got {args.holdout}")
    runs = load_runs(split_files(args.data, "--data"))
    held = {"kind": "last_fraction", "fraction": args.holdout, "of": list(runs.files)}
    holdout = args.holdout
    if args.validate is not None:
        validate = load_runs(split_files(args.validate, "--validate"))
        held = {"kind": "logs", "logs": list(validate.files), "fitted_on": list(runs.files),
                "samples": validate.samples}
        holdout = validate.samples / (runs.samples + validate.samples)
        runs = join(runs, validate)
    data, meta = runs.arrays, runs.metas[0]
    dof = data["q"].shape[1]
    robot = data_robot(meta, args.robot)
    library = choose_library(args.library, dof, robot)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = identify(data["q"], data["qd"], data["qdd"], data["tau"], library,
                          holdout, data.get("tau_clean"),
                          method=None if args.method == "auto" else args.method)
    # every warning reaches the user, once each (a library's rank, a solver's convergence,
    # a numerical library's complaint alike)
    for line in dict.fromkeys(f"{w.category.__name__}: {w.message}" for w in caught):
        print(f"torquebench identify: warning: {' '.join(line.split())}", file=sys.stderr)
    payload = {"robot": robot_record(robot), **result.model.to_dict(),
               "metrics": {**result.metrics(), "heldout": held,
                           "scored_against": "tau_clean" if "tau_clean" in data else "tau"}}
    if result.lagrangian():
        payload["lagrangian"] = result.lagrangian()
    write_json(args.out, payload)
    for line in result.model.equations():
        print(line)
    rel = ", ".join(f"{x:.3e}" for x in result.heldout_rel_rmse)
    print(f"wrote {args.out}: held-out relative RMS error per joint [{rel}]")
    return 0
