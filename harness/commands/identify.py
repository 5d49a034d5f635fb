"""`torquebench identify`: sparse torque model from a dataset .npz -> MODEL.json."""

from __future__ import annotations

import argparse
import sys
import warnings

from harness.commands import SUMMARY, add_chain_option, chain_option
from harness.data.runs import join, load_runs, split_files
from harness.identify.drive_gains import current_or_torque, describe, gain_runs
from harness.identify.fits import RIGID_BODY, arm_identification
from harness.identify.readings import describe as describe_readings
from harness.identify.refine import REFINEMENTS, refine_command
from harness.identify.refine import SECONDS as REFINE_SECONDS
from harness.io import write_json
from harness.robots.registry import DEFAULT_ROBOT
from harness.robots.resolve import resolve_arm
from identification.choice import LIBRARIES, METHODS, PRIORS
from identification.errors import IdentificationError
from identification.identify import identify
from identification.metrics import error_figures, error_words
from identification.model import model_payload
from identification.parameter_intervals import PARAMETER_BLOCKS
from identification.physical import PRIOR_METRICS


def register(sub) -> None:
    p = sub.add_parser("identify", help=SUMMARY["identify"])
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
    add_chain_option(p)
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
    p.add_argument("--plausible", action=argparse.BooleanOptionalAction, default=True,
                   help="with a consistent fit (--prior nominal|flat): each body's mass inside "
                   "an ellipsoid bounding its link (the smallest holding its collision, else "
                   "visual, geometry in the URDF; else about the segment to its child joint; "
                   "grown to hold the nominal body); MODEL.json's bodies say whether each is "
                   "plausible (default: on; --no-plausible: consistent only)")
    p.add_argument("--prior-metric", choices=PRIOR_METRICS, default="ridge",
                   help="with --prior nominal: how a body's distance from its nominal is "
                   "measured: ridge (its parameters' squared deviation, in the body's scale; "
                   "the default) or entropic (the LogDet divergence of its pseudo-inertia: "
                   "what the data leave open stays a scaled copy of the nominal body, never a "
                   "degenerate one; docs/identification.md, 'Prior metric')")
    p.add_argument("--rigid-body", action=argparse.BooleanOptionalAction, default=RIGID_BODY,
                   help="with the coupled fit on a feature library (the Lynxmotion's prior "
                   "library): hold the kept atoms' coefficients to the directions a rigid body "
                   "of the robot's kinematics also gives, unless an F-test rejects it (MODEL.json "
                   "metrics.rigid_body says which; docs/identification.md, 'Over many draws'); "
                   f"default: {'on' if RIGID_BODY else 'off'}")
    p.add_argument("--loaded", default=None, metavar="L.npz[,L2.npz]",
                   help="for logs of motor currents with unknown drive gains (ingest "
                   "--gains-unknown): runs carrying a load of known mass near the chain's end; "
                   "the gains are identified with the dynamics from --data (the unloaded runs) "
                   "and these, reported per joint with a 95 %% interval (MODEL.json drive_gains, "
                   "N m/A) and used: the model is fitted on --data's gain x current (needs "
                   "--load-mass)")
    p.add_argument("--load-mass", type=float, default=None, metavar="KG",
                   help="with --loaded: the load's mass (kg), which fixes the gains' scale")
    p.add_argument("--load-body", default=None, metavar="LINK",
                   help="with --loaded: the link the load is fixed to (default: chosen by the "
                        "data among the bodies the last three joints move, by held-out "
                        "validation; MODEL.json drive_gains.load.body_choice)")
    p.add_argument("--intervals", action=argparse.BooleanOptionalAction, default=True,
                   help="each identified parameter printed with its 95 %% interval, the fit "
                   f"redone without each of {PARAMETER_BLOCKS} contiguous time blocks of every run (a "
                   "delete-one-block jackknife: it holds on a coloured residual; MODEL.json "
                   "parameter_intervals; a consistent fit's bodies: the readings the data "
                   f"determine); --no-intervals: one fit, no interval ({PARAMETER_BLOCKS} fits "
                   "fewer)")
    p.add_argument("--refine", choices=REFINEMENTS, default="none",
                   help="rollout: the consistent fit's exported MJCF refined by rollouts "
                        "against the fitted part's q and qd (mujoco.sysid's optimizer, the "
                        "sysid extra; every body kept physically consistent), written to "
                        "--refine-out, MODEL.json 'refined' says what it did")
    p.add_argument("--refine-seconds", type=float, default=REFINE_SECONDS, metavar="S",
                   help=f"with --refine rollout: its wall-time budget (default {REFINE_SECONDS:g})")
    p.add_argument("--refine-out", default=None, metavar="MODEL.xml",
                   help="with --refine rollout: the refined MJCF (default: --out with the "
                        "suffix .refined.xml)")
    p.set_defaults(func=run)


def run(args) -> int:
    if not 0.0 < args.holdout < 1.0:  # 0 would score the training data as "held out"
        raise IdentificationError(f"--holdout must be in (0, 1), got {args.holdout}")
    gains = None  # logs of currents: their drive gains, identified with a loaded run
    if args.loaded is not None or args.load_mass is not None:
        runs, _, gains = gain_runs(split_files(args.data, "--data"),
                                   None if args.loaded is None
                                   else split_files(args.loaded, "--loaded"),
                                   args.load_mass, args.robot, args.load_body)
    else:
        runs = load_runs(split_files(args.data, "--data"))
    held = {"kind": "last_fraction", "fraction": args.holdout, "of": list(runs.files)}
    holdout = args.holdout
    if args.validate is not None:
        validate_files = split_files(args.validate, "--validate")
        validate = (current_or_torque(validate_files, gains["gains"]) if gains
                    else load_runs(validate_files))
        held = {"kind": "logs", "logs": list(validate.files), "fitted_on": list(runs.files),
                "samples": validate.samples}
        holdout = validate.samples / (runs.samples + validate.samples)
        runs = join(runs, validate)
    data, meta = runs.arrays, runs.metas[0]
    dof = data["q"].shape[1]
    # every --data and --validate run checked
    arm = resolve_arm(args.robot, data=runs.records, chain=chain_option(args))
    library, regressor = arm_identification(arm, dof, args.library, args.prior, args.method,
                                            meta.get("mode") == "measured log", args.plausible,
                                            args.prior_metric, args.rigid_body)
    if args.prior_metric != "ridge" and getattr(regressor, "nominal", None) is None:
        raise IdentificationError(f"--prior-metric {args.prior_metric} measures the pull toward "
                                  "the URDF's bodies: it needs the consistent fit with a prior "
                                  "(--prior nominal)")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = identify(data["q"], data["qd"], data["qdd"], data["tau"], library, holdout,
                          data.get("tau_clean"), regressor, runs=runs.labels,
                          interval_blocks=PARAMETER_BLOCKS if args.intervals else 0)
    # every warning reaches the user, once each (a library's rank, a solver's convergence,
    # a numerical library's complaint alike)
    for line in dict.fromkeys(f"{w.category.__name__}: {w.message}" for w in caught):
        print(f"torquebench identify: warning: {' '.join(line.split())}", file=sys.stderr)
    payload = model_payload(result, arm.record, held, "tau_clean" if "tau_clean" in data else "tau")
    payload["sensor_offsets"] = result.sensor_offsets()
    if result.intervals:
        payload["parameter_intervals"] = result.intervals
    if args.refine == "rollout":
        for line in refine_command(args, payload, arm, runs, result, holdout):
            print(line)
    if gains:
        payload["drive_gains"] = gains
        for line in describe(gains):
            print(line)
    write_json(args.out, payload)
    for line in result.model.equations():
        print(line)
    if result.physical:
        p = result.physical
        plausible = ("" if "plausible" not in p else "; every body plausible (inside its link's "
                     f"ellipsoid): {'yes' if all(p['plausible']) else 'NO'}")
        print(f"prior {p['prior']} ({p['prior_metric']}, weight {p['lambda']:g}); every body "
              "physically consistent: "
              f"{'yes' if p['consistent'] else 'NO'}{plausible}")
    else:
        print("physical consistency not imposed (sparse fit; --prior nominal or flat imposes it)")
    for line in describe_readings(result.intervals):
        print(line)
    print(f"wrote {args.out}: {error_words(result.reference, 'held-out samples')} "
          f"{error_figures(result.heldout_rel_rmse)}")
    for scored in result.scored:  # a measured log: each held-out run's sensor offset
        print(f"  a held-out run's sensor offset: from {scored.source}")
    return 0
