"""`torquebench identify`: sparse torque model from a dataset .npz -> MODEL.json."""

from __future__ import annotations

import sys
import warnings

from harness.data.runs import join, load_runs, split_files
from harness.io import write_json
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import DEFAULT_ROBOT, data_robot, load_pinocchio, robot_entry
from harness.robots.torque_models import library_named, robot_record
from identification.consistent import identify_consistent
from identification.errors import IdentificationError
from identification.identify import identify
from identification.library.kinematic import KinematicLibrary

LIBRARIES = ("auto", "kinematic", "prior", "prior-general", "paper", "generic")
METHODS = ("auto", "coupled", "per-joint", "jointwise")
PRIORS = ("auto", "nominal", "flat", "none")


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
                   help="robot name or URDF/MJCF path (default: the robot the data record, else "
                   f"{DEFAULT_ROBOT})")
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
    p.add_argument("--prior", choices=PRIORS, default="auto",
                   help="nominal: a physically consistent fit (every body's pseudo-inertia "
                   "positive semidefinite, friction >= 0, each joint's friction law chosen by "
                   "data) pulled toward the --robot's URDF/MJCF inertias as far as validation "
                   "inside the training data allows; flat: the same fit without the pull; none: "
                   "the sparse fit (the fast path, consistency not imposed); auto: nominal on "
                   "measured logs (`ingest`ed), none on data `generate` made (where the URDF is "
                   "the truth)")
    p.set_defaults(func=run)



def choose_library(name: str, dof: int, robot: str = DEFAULT_ROBOT):
    """The library called name ('auto': the first the robot's registry entry offers)."""
    if name == "auto":
        name = robot_entry(robot).libraries[0]
    return library_named(name, robot, dof)


def choose_prior(name: str, meta: dict, library) -> str:
    """The prior `--prior` names ('auto': nominal on a measured log, else none); the consistent
    fits need a robot's atoms (the kinematic library)."""
    if name == "auto":
        name = "nominal" if meta.get("mode") == "measured log" else "none"
        if not isinstance(library, KinematicLibrary):
            return "none"
    if name != "none" and not isinstance(library, KinematicLibrary):
        raise IdentificationError(f"--prior {name} fits the robot's atoms: use --library kinematic "
                                  f"(not {library.name})")
    return name


def fit(data: dict, library, holdout: float, prior: str, robot: str, method: str):
    """The Identification `prior` asks for (see --prior)."""
    if prior == "none":
        return identify(data["q"], data["qd"], data["qdd"], data["tau"], library, holdout,
                        data.get("tau_clean"), method=None if method == "auto" else method)
    nominal = PinocchioModel(load_pinocchio(robot)).atom_parameters() if prior == "nominal" else None
    return identify_consistent(data["q"], data["qd"], data["qdd"], data["tau"], library, nominal,
                               holdout, data.get("tau_clean"))


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
    library = choose_library("kinematic" if args.library == "auto" and args.prior in
                             ("nominal", "flat") else args.library, dof, robot)
    prior = choose_prior(args.prior, meta, library)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(data, library, holdout, prior, robot, args.method)
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
    if result.physical:
        p = result.physical
        print(f"prior {p['prior']} (weight {p['lambda']:g}); every body physically consistent: "
              f"{'yes' if p['consistent'] else 'NO'}")
    else:
        print("physical consistency not imposed (sparse fit; --prior nominal or flat imposes it)")
    rel = ", ".join(f"{x:.3e}" for x in result.heldout_rel_rmse)
    print(f"wrote {args.out}: held-out relative RMS error per joint [{rel}]")
    return 0
