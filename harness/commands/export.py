"""`torquebench export`: a consistent fit's bodies as the robot's URDF or MJCF, or a table."""

from __future__ import annotations

import sys

from harness.commands import SUMMARY, add_chain_option, chain_option
from harness.commands.predict import new_run_offset
from harness.data.dataset import STATE_KEYS, load_arrays
from harness.errors import UserError
from harness.robots.export import FORMATS, export_model
from harness.robots.registry import DEFAULT_ROBOT
from harness.robots.resolve import resolve_arm
from harness.robots.torque_models import read_model, torque_model


def register(sub) -> None:
    p = sub.add_parser("export", help=SUMMARY["export"])
    p.add_argument("--model", required=True, help="MODEL.json written by `identify`")
    p.add_argument("--robot", default=None,
                   help=f"robot name or URDF/MJCF path (default: the MODEL.json's, else "
                   f"{DEFAULT_ROBOT})")
    add_chain_option(p)
    p.add_argument("--format", choices=FORMATS, required=True,
                   help="urdf: the robot's URDF with each body's <inertial> and each joint's "
                   "<dynamics damping friction>; mjcf: MuJoCo's model with the inertials, "
                   "armature, the model's friction as frictionloss (its smoothing set) + "
                   "damping, a motor per joint whose bias holds the sensor offset (what was "
                   "approximated: a comment in the file and stderr); csv: body or joint, "
                   "parameter, value, unit, nominal, about (first moments and inertias "
                   "about the link frame, its joint's, not the centre of mass; a model "
                   "without bodies: its terms). URDF has no armature: the line written says "
                   "what was left out")
    p.add_argument("--data", default=None, metavar="LOG.npz",
                   help="mjcf: also measure what the file's approximation of the model's "
                   "friction costs on this log's states: per joint, the torque RMS gap of the "
                   "file's inverse dynamics (mj_inverse) against the model's torque")
    p.add_argument("--out", required=True, help="output file")
    p.set_defaults(func=run)


def run(args) -> int:
    model = read_model(args.model)
    if model.payload is None:
        raise UserError("export takes a MODEL.json written by `identify`, not 'pinocchio'")
    arm = resolve_arm(args.robot, model=model.recorded, chain=chain_option(args))
    torque = torque_model(model, arm)  # a well-formed model of this arm's kinematics
    offset = new_run_offset(model.payload, torque)
    log = None
    if args.data is not None:
        if args.format != "mjcf":
            raise UserError("--data measures an mjcf export's approximation: give --format mjcf")
        states, _ = load_arrays(args.data, STATE_KEYS)
        if states["q"].shape[1] != torque.dof:
            raise UserError(f"data has {states['q'].shape[1]} joints, model has {torque.dof}")
        sensor = torque.torque(states["q"], states["qd"], states["qdd"]) + offset
        log = (states["q"], states["qd"], states["qdd"], sensor)
    report: list[str] = []
    what = export_model(model.payload, arm, args.format, args.out, offset, log, report)
    for line in report:
        print(f"torquebench: export: {line}", file=sys.stderr)
    print(f"wrote {args.out}: {what}")
    return 0
