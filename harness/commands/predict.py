"""`torquebench predict`: a torque model's torques at a dataset's states."""

from __future__ import annotations

from harness.data.dataset import load_arrays
from harness.errors import UserError
from harness.io import write_npz
from harness.robots.registry import DEFAULT_ROBOT
from harness.robots.torque_models import load_torque_model


def register(sub) -> None:
    p = sub.add_parser("predict", help="torques of a model (MODEL.json or 'pinocchio') on data")
    p.add_argument("--model", required=True, help="MODEL.json or 'pinocchio'")
    p.add_argument("--data", required=True, help="dataset .npz with q, qd, qdd")
    p.add_argument("--robot", default=None,
                   help=f"robot name or URDF/MJCF path: the pinocchio baseline's (default "
                   f"{DEFAULT_ROBOT}); a MODEL.json's by default the robot it records")
    p.add_argument("--out", required=True, help="output .npz with key tau")
    p.set_defaults(func=run)


def run(args) -> int:
    states, _ = load_arrays(args.data)
    model = load_torque_model(args.model, args.robot)
    if states["q"].shape[1] != model.dof:
        raise UserError(f"data has {states['q'].shape[1]} joints, model has {model.dof}")
    tau = model.torque(states["q"], states["qd"], states["qdd"])
    write_npz(args.out, tau=tau)
    print(f"wrote {args.out}: tau {tau.shape}")
    return 0
