"""`torquebench predict`: a torque model's torques at a dataset's states."""

from __future__ import annotations

import numpy as np

from harness.commands import SUMMARY, add_chain_option, chain_option
from harness.data.dataset import STATE_KEYS, load_arrays
from harness.errors import UserError
from harness.io import write_npz
from harness.robots.registry import DEFAULT_ROBOT
from harness.robots.resolve import resolve_arm
from harness.robots.torque_models import read_model, torque_model
from identification.closeloop.closed.offsets import (
    MIN_REST,
    RECORDED,
    REST_SPEED,
    first_rest,
    held_out_offset,
    residual_offset,
)
from identification.metrics import rel_error
from identification.model import sensor_offsets


def register(sub) -> None:
    p = sub.add_parser("predict", help=SUMMARY["predict"])
    p.add_argument("--model", required=True, help="MODEL.json or 'pinocchio'")
    p.add_argument("--data", required=True, help="dataset .npz with q, qd, qdd")
    p.add_argument("--robot", default=None,
                   help="robot name or URDF/MJCF path (default: a MODEL.json's own, else the "
                   f"robot the data record, else {DEFAULT_ROBOT}); a MODEL.json identified "
                   "for another robot, or data of another, is an error")
    add_chain_option(p)
    p.add_argument("--out", required=True,
                   help="output .npz: tau, the model's torque at the data's states; on a "
                   "measured log (no tau_clean: ingested or sensed), the torque its sensor would "
                   "read, the sensor offset a run the model was not trained on is scored with "
                   "included (the model file's sensor_offsets.new_run, the rule identify and "
                   "closeloop score held-out runs by; else the model's fitted offset, zeros for "
                   "a model that fits none); the offset also as 'offset' and where it came from "
                   "as 'offset_from'; with a torque in the data, also 'rel_error', its per-joint "
                   "relative error ||tau_hat - tau|| / ||tau||")
    p.add_argument("--offset-from-rest", action="store_true",
                   help="the sensor offset of this log taken from its first rest (the samples "
                   "before any joint moves faster than 0.01 rad/s, at least 10: the model's "
                   "mean residual there) instead of the model file's, and rel_error "
                   "scored on the samples after the rest, as `closeloop` scores a --validate "
                   "log; needs the data's tau")
    p.set_defaults(func=run)


def run(args) -> int:
    states, meta = load_arrays(args.data, STATE_KEYS, optional=("tau", "tau_clean"))
    read = read_model(args.model)
    arm = resolve_arm(args.robot, model=read.recorded, data=[(args.data, meta)], chain=chain_option(args))
    model = torque_model(read, arm)
    if states["q"].shape[1] != model.dof:
        raise UserError(f"data has {states['q'].shape[1]} joints, model has {model.dof}")
    tau = model.torque(states["q"], states["qd"], states["qdd"])
    measured = "tau_clean" not in states or args.offset_from_rest  # a log reads the offset
    if args.offset_from_rest:
        offset, start = _offset_from_rest(args.data, states, model)
        source = f"the log's first rest ({start} samples, not scored)"
    else:  # the rule held-out runs are scored by (identification.closeloop.closed.offsets)
        offset = held_out_offset(model, new_run_offset(read.payload, model))
        start, source = 0, RECORDED
    if measured:
        tau = tau + offset
    scored = {}
    if "tau" in states:  # what the sensor read: against the torque the model says it reads
        scored["rel_error"] = rel_error(tau[start:], states["tau"][start:])
    if args.offset_from_rest:
        scored["rest_samples"] = np.array(start)
    write_npz(args.out, tau=tau, offset=np.broadcast_to(offset, (len(tau), model.dof)),
              offset_from=np.array(source if measured else "none (tau_clean: no sensor)"),
              **scored)
    print(f"wrote {args.out}: tau {tau.shape}" + (
        f", the sensor offset from {source} included" if measured else ""))
    if "rel_error" in scored:
        errors = ", ".join(f"{e:.4g}" for e in scored["rel_error"])
        where = f" after its first rest (samples {start}-{len(tau) - 1})" if start else ""
        print(f"relative error against the data's tau{where}, per joint: [{errors}]")
    return 0


def new_run_offset(payload, model) -> np.ndarray:
    """(dof,) N m: the offset the model file records for a run it was not trained on
    (sensor_offsets.new_run, written by identify and closeloop), else the model's fitted
    offset (zeros for a model without: 'pinocchio')."""
    offsets = payload.get("sensor_offsets") if isinstance(payload, dict) else None
    if offsets is not None and not isinstance(offsets, dict):
        raise UserError(f"the model's sensor_offsets must be an object with new_run, got "
                        f"{str(offsets):.60}")
    recorded = None if offsets is None else offsets.get("new_run")
    if recorded is None:
        return sensor_offsets(model)
    try:
        offset = np.asarray(recorded, float).reshape(model.dof)
    except (TypeError, ValueError):
        raise UserError(f"the model's sensor_offsets.new_run must be {model.dof} numbers, got "
                        f"{str(recorded):.60}") from None
    if not np.all(np.isfinite(offset)):
        raise UserError("the model's sensor_offsets.new_run must be finite")
    return offset


def _offset_from_rest(path: str, states: dict, model) -> tuple[np.ndarray, int]:
    """The log's offset from its first rest (identification.closeloop.closed.offsets) and the rest's
    length in samples."""
    if "tau" not in states:
        raise UserError(f"{path}: --offset-from-rest needs the log's torque (tau)")
    rest = first_rest(states["qd"])
    if not rest:
        raise UserError(f"{path}: no rest at its start (every joint below {REST_SPEED:g} rad/s "
                        f"for at least {MIN_REST} samples) to take the sensor offset from")
    calibration = tuple(states[k][:rest] for k in ("q", "qd", "qdd", "tau"))
    return residual_offset(model, calibration), rest
