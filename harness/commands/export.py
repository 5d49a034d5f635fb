"""`torquebench export`: a consistent fit's bodies as the robot's URDF or MJCF, or a table."""

from __future__ import annotations

from harness.commands import SUMMARY, add_chain_option, chain_option
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
                   "armature, damping, frictionloss; csv: body or joint, parameter, value, unit, "
                   "nominal, about (first moments and inertias about the link frame, its "
                   "joint's, not the centre of mass; a model without bodies: its terms). "
                   "URDF has no armature: the line written says what was left out")
    p.add_argument("--out", required=True, help="output file")
    p.set_defaults(func=run)


def run(args) -> int:
    model = read_model(args.model)
    if model.payload is None:
        raise UserError("export takes a MODEL.json written by `identify`, not 'pinocchio'")
    arm = resolve_arm(args.robot, model=model.recorded, chain=chain_option(args))
    torque_model(model, arm)  # a well-formed model of this arm's kinematics
    what = export_model(model.payload, arm, args.format, args.out)
    print(f"wrote {args.out}: {what}")
    return 0
