"""`torquebench predict`: a torque model's torques at a dataset's states."""

from __future__ import annotations

import numpy as np

from harness.data.dataset import STATE_KEYS, load_arrays
from harness.errors import UserError
from harness.io import write_npz
from harness.robots.registry import DEFAULT_ROBOT
from harness.robots.torque_models import load_torque_model
from identification.identify import sensor_offsets


def register(sub) -> None:
    p = sub.add_parser("predict", help="torques of a model (MODEL.json or 'pinocchio') on data")
    p.add_argument("--model", required=True, help="MODEL.json or 'pinocchio'")
    p.add_argument("--data", required=True, help="dataset .npz with q, qd, qdd")
    p.add_argument("--robot", default=None,
                   help=f"robot name or URDF/MJCF path: the pinocchio baseline's (default "
                   f"{DEFAULT_ROBOT}); a MODEL.json's by default the robot it records")
    p.add_argument("--out", required=True,
                   help="output .npz: tau, the model's torque at the data's states; on a "
                   "measured log (no tau_clean: ingested or sensed), the torque its sensor would "
                   "read, the model's fitted sensor offset included; the offset also as 'offset' "
                   "(zeros for a model that fits none)")
    p.set_defaults(func=run)


def run(args) -> int:
    states, _ = load_arrays(args.data, STATE_KEYS, optional=("tau_clean",))
    model = load_torque_model(args.model, args.robot)
    if states["q"].shape[1] != model.dof:
        raise UserError(f"data has {states['q'].shape[1]} joints, model has {model.dof}")
    tau = model.torque(states["q"], states["qd"], states["qdd"])
    offset = sensor_offsets(model)
    measured = "tau_clean" not in states  # a log's sensor reads the offset too
    if measured:
        tau = tau + offset
    write_npz(args.out, tau=tau, offset=np.broadcast_to(offset, (len(tau), model.dof)))
    print(f"wrote {args.out}: tau {tau.shape}"
          + (", the fitted sensor offset included (measured log)" if measured else ""))
    return 0
