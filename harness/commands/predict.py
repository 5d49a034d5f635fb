"""`torquebench predict`: a torque model's torques at a dataset's states."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from harness.commands import SUMMARY, add_chain_option, chain_option
from harness.data.dataset import STATE_KEYS, load_arrays
from harness.errors import UserError
from harness.io import write_json, write_npz
from harness.replay.friction import PlantFriction
from harness.replay.rollout import (
    DIVERGED,
    WINDOWS,
    held_model,
    refined_model,
    roll_out,
    table,
)
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
from identification.metrics import error_figures, error_measure, error_words, rel_error
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
    p.add_argument("--rollout", nargs="?", const=",".join(f"{w:g}" for w in WINDOWS),
                   default=None, metavar="SECONDS[,...]",
                   help="also roll the model out in MuJoCo (the robot's own file for "
                   "'pinocchio', the refined MJCF a MODEL.json of `identify --refine rollout` "
                   "names, driven with its motors' bias, else the MJCF `export --format mjcf` "
                   "writes): from the log's "
                   "q, qd at the start of each window of these lengths (default "
                   f"{','.join(f'{w:g}' for w in WINDOWS)}), driven by the log's tau (less "
                   "the sensor offset added to the prediction), against the log's q and qd; "
                   "per window length and joint the RMS errors and the fraction of windows "
                   "that diverge, in --rollout-out and as a table")
    p.add_argument("--rollout-holdout", type=float, default=None, metavar="FRACTION",
                   help="--rollout's windows on the last FRACTION of the log only (the part "
                   "`identify --holdout` scores; default: the whole log)")
    p.add_argument("--rollout-out", default=None, metavar="ROLLOUT.json",
                   help="where --rollout writes (default: beside --out, NAME.rollout.json)")
    p.set_defaults(func=run)


def run(args) -> int:
    states, meta = load_arrays(args.data, STATE_KEYS, optional=("tau", "tau_clean", "t"))
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
        samples = f"samples {start}-{len(tau) - 1} (after the log's first rest)" if start else (
            "all samples")
        scored["error_measure"] = np.array(json.dumps(error_measure("measured", samples)))
    if args.offset_from_rest:
        scored["rest_samples"] = np.array(start)
    if args.rollout is None and args.rollout_holdout is not None:
        raise UserError("--rollout-holdout chooses --rollout's windows: give --rollout too")
    rollout = None if args.rollout is None else _rollout(args, read, arm, model, states, meta,
                                                          offset if measured else None)
    write_npz(args.out, tau=tau, offset=np.broadcast_to(offset, (len(tau), model.dof)),
              offset_from=np.array(source if measured else "none (tau_clean: no sensor)"),
              **scored)
    print(f"wrote {args.out}: tau {tau.shape}" + (
        f", the sensor offset from {source} included" if measured else ""))
    if "rel_error" in scored:
        print(f"{error_words('measured', json.loads(str(scored['error_measure']))['samples'])}: "
              f"{error_figures(scored['rel_error'])}")
    if rollout is not None:
        path, payload, figures = rollout
        write_json(path, payload)
        print(f"wrote {path}: rollout of {payload['model']}\n{table(figures)}")
    return 0


def _rollout(args, read, arm, model, states: dict, meta: dict, offset) -> tuple:
    """(path, ROLLOUT.json payload, figures) of --rollout; UserError before anything is
    written for a log or model it cannot roll out."""
    seconds = parse_windows(args.rollout)
    missing = [k for k in ("t", "tau") if k not in states]
    if missing:
        raise UserError(f"{args.data}: --rollout needs the log's {' and '.join(missing)}")
    approximated: list[str] = []
    refined = refined_model(read.payload, args.model)
    if refined is None:
        held, words = held_model(read.payload, arm, approximated)
    else:  # the refined MJCF is the model: its motors' bias holds its sensor offset
        held, bias, words = refined
        offset = -bias
    tau = states["tau"] - (0.0 if offset is None else offset)
    done = roll_out(held, states["t"], states["q"], states["qd"], tau, seconds,
                    args.rollout_holdout)
    figures = done.figures
    friction = PlantFriction.of(model)
    path = args.rollout_out or str(Path(args.out).with_suffix("")) + ".rollout.json"
    payload = {"model": f"{args.model}: {words}", "robot": arm.reference, "data": args.data,
               "seed": meta.get("seed"), "samples": len(states["q"]), "from_sample": done.start,
               "log_step_s": done.log_step, "timestep_s": done.timestep,
               "torque": "the log's tau, linear between samples, as qfrc_applied (actuators off)",
               "offset_removed": None if offset is None else np.broadcast_to(
                   offset, (model.dof,)).tolist(),
               "not_in_mujoco": list(friction.described) if friction else [],
               "approximated_in_mujoco": approximated,
               "diverged_when": f"non-finite, unstable, or a joint over {DIVERGED:.4g} rad off",
               "windows": [f.to_json() for f in figures],
               "units": {"seconds": "s", "q_rms": "rad", "qd_rms": "rad/s"}}
    return path, payload, figures


def parse_windows(text: str) -> list[float]:
    """--rollout's window lengths (s); UserError unless positive numbers."""
    try:
        seconds = [float(x) for x in text.split(",")]
    except ValueError:
        raise UserError(f"--rollout takes window lengths in seconds, e.g. 0.1,0.5,1; got "
                        f"'{text}'") from None
    if not all(np.isfinite(s) and s > 0 for s in seconds):
        raise UserError(f"--rollout windows must be positive seconds, got '{text}'")
    return seconds


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
