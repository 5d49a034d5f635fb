"""`closeloop --data A.npz[,B.npz...] [--validate C.npz[,...]] --robot R [--declared ...]`:
the loop on runs of one robot against the model the user declared. Which robot the runs are
of is the command's (harness.robots.arm.resolve_arm on every run's meta, the declared model's
record and --robot): here the runs come with their arm.

The declared model is the robot's nominal model (`pinocchio`: its URDF/MJCF) or a
MODEL.json; with the nominal model the inertial candidate is the rigid-body correction
of the physically consistent fit pulled toward it (identification.regression.consistent): a payload,
a wrong mass or centre of mass, named as such rather than absorbed by springs and friction.
Effects are chosen by identification.closeloop.selection.runs; scores are on the --validate runs, or
without them on the last --holdout of every run (the rest trains), each scored run with its
sensor offset by the rule identify and predict use (identification.closeloop.closed.offsets: the
model's mean residual on the training runs' samples, or on its own run's trained part),
before and after alike.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from harness.data.derivatives import state_smoothing
from harness.data.runs import KEYS, Runs, load_runs, run_times, split_files
from harness.errors import UserError
from harness.robots.arm import Arm
from harness.robots.bodies import candidate_bodies, last_body
from harness.robots.closed_model import model_payload
from harness.robots.scales import robot_scales
from harness.robots.torque_models import load_torque_model, read_model
from identification.closeloop.candidates.inertial import inertial_correction
from identification.closeloop.candidates.payload import REACH
from identification.closeloop.closed.leftover import LEFT, Leftover
from identification.closeloop.closed.offsets import RULE, ScoredRun, held_out_offset
from identification.closeloop.events.detect import Events
from identification.closeloop.events.runs import (
    events_json,
    events_line,
)
from identification.closeloop.pipeline import close_the_loop
from identification.closeloop.selection.runs import RunsLoop
from identification.closeloop.verdicts.agreement import AGREE, MIN_GAIN
from identification.closeloop.verdicts.ranges import ranges_json
from identification.errors import IdentificationError
from identification.metrics import HELD_OUT, error_measure


def read_runs(data: str, validate: str | None = None) -> tuple[Runs, Runs | None]:
    """The --data runs and the --validate runs (None without), each of one joint count."""
    train = load_runs(split_files(data, "--data"))
    return train, (load_runs(split_files(validate, "--validate")) if validate else None)


def _split(runs: Runs) -> list[tuple]:
    """Each run's (q, qd, qdd, tau)."""
    cuts = np.cumsum(runs.lengths)[:-1]
    return list(zip(*(np.split(runs.arrays[k], cuts) for k in KEYS), strict=True))


@dataclass(frozen=True)
class RunsRun:
    """The loop on the runs, its scores and what it was run on."""

    robot: str
    declared: str
    train_files: list[str]
    validate_files: list[str]  # empty: the last holdout of every run scored
    holdout: float
    loop: RunsLoop
    error_before: np.ndarray
    error_after: np.ndarray
    left: Leftover
    model_json: dict
    heldout_offsets: np.ndarray  # (held runs, dof) N m, each under the closed model
    scored: list[ScoredRun]  # what each held-out run is scored on, its offset from where
    event_files: list[str]  # the runs events were looked for on: training, then validation
    found: tuple[Events, ...]  # each one's external torques (identification.closeloop.events)
    ranges: dict  # per effect, the range its coefficient was held to (per joint)
    body: str = ""  # the link --payload-body named ('' : the data chose, loop.body_choice)

    @property
    def events_line(self) -> str:
        return events_line(self.event_files, list(self.found))

    def to_json(self) -> dict:
        r, left = self.loop, self.left
        out = {"effects": [n.to_json() for n in r.named],
               "error_before": self.error_before.tolist(),
               "error_after": self.error_after.tolist(),
               "error_measure": error_measure("measured", HELD_OUT),
               "unexplained": bool(left.unexplained_joints),
               "unexplained_joints": list(left.unexplained_joints),
               "unexplained_detail": left.to_json(),
               "declared": self.declared, "robot": self.robot,
               "sensor_offsets": r.offsets.tolist(),
               "training_sensor_offsets": r.run_offsets.tolist(),
               "heldout_sensor_offsets": self.heldout_offsets.tolist(),
               "heldout_runs": [s.to_json(r.model) for s in self.scored],
               "data": {"files": self.train_files},
               "selection": {"folds": r.folds, "path": [list(p) for p in r.path],
                             "not_named": [{"joint": j, "effect": e, "validation_gain": g,
                                            "reason": why} for j, e, g, why in r.not_named],
                             "rule": f"forward selection validated leaving one {r.folds[:-1]} "
                                     f"out: named if it cuts its joint's validation error "
                                     f"power by >= {MIN_GAIN:.0%}, on no held-out run makes "
                                     "a joint it acts on worse, lies in its physical range "
                                     "(physical_ranges) and agrees between runs within "
                                     f"{AGREE:g} standard errors; a joint is unexplained when "
                                     f"its held-out residual is > {LEFT:g} noise sigma RMS "
                                     "above the noise"},
               "physical_ranges": self.ranges,
               "error_definition": "relative error ||tau_hat - tau|| / ||tau|| per joint "
                                   "against the measured torque, on " + (
                                       "the --validate runs" if self.validate_files else
                                       f"the last {self.holdout:.0%} of every run") +
                                   ", before and after alike with each scored run's "
                                   "sensor offset (a constant per joint) by the rule identify "
                                   "and predict use: " + RULE + ". heldout_runs says which, "
                                   "run by run; `predict` with model.json on a --validate "
                                   "log reproduces its figures",
               "model": "model.json", **events_json(self.event_files, list(self.found)),
               "payload_body": r.body_choice or {"chosen": self.body,
                                                 "rule": "--payload-body"}}
        if self.validate_files:
            out["heldout"] = {"files": self.validate_files, "before": out["error_before"],
                              "after": out["error_after"]}
        return out


def _times(runs: Runs) -> tuple[np.ndarray, ...]:
    """Each run's time stamps, checked (harness.data.runs.run_times): its `t`, else its
    samples at the rate its meta records."""
    times = runs.times or (None,) * len(runs.lengths)
    return tuple(run_times(f, {"q": np.empty((n, 0)), "t": t}, m) for f, n, t, m in zip(
        runs.files, runs.lengths, times, runs.metas, strict=True))


def _declared(declared: str, arm: Arm, dof: int):
    """(the declared torque model, what model.json records of it)."""
    if declared == "pinocchio":
        return arm.nominal, "pinocchio"
    model, spec = load_torque_model(declared, arm), read_model(declared).payload
    if model.dof != dof:
        raise UserError(f"--declared {declared} has {model.dof} joints, robot {arm.label} {dof}")
    return model, spec


def run_runs(data: Runs, arm: Arm, declared: str = "pinocchio", validate: Runs | None = None,
             holdout: float = 0.25, reach: float = REACH, body: str | None = None,
             detect: bool = True) -> RunsRun:
    """Close the loop (identification.closeloop.pipeline) on the runs data (read_runs) of arm,
    scored on the validate runs or the last holdout of every run; a payload on the last body
    (payload.last_body; the link `body` when given) is a candidate, its centre of mass within
    reach m of its joint; detect=False: no external torque looked for (as before events were:
    the study of pushes measures what that costs)."""
    runs, dof = _split(data), arm.dof
    carrier = (last_body(arm, body),) if body else candidate_bodies(arm)
    if runs[0][0].shape[1] != dof:
        raise UserError(f"data have {runs[0][0].shape[1]} joints, robot {arm.label} has {dof}")
    model, spec = _declared(declared, arm, dof)
    held = None if validate is None else _split(validate)
    if held is not None and held[0][0].shape[1] != dof:
        raise UserError(f"--validate logs have {held[0][0].shape[1]} joints, robot "
                        f"{arm.label} has {dof}")
    try:
        out = close_the_loop(
            model, runs, _times(data), held, None if validate is None else _times(validate),
            holdout, carrier if len(carrier) > 1 else carrier[0],
            lambda r: robot_scales(arm, r),
            (lambda train: inertial_correction(arm.library, arm.nominal.atom_parameters(),
                                                 arm.ellipsoids, train)) if declared == "pinocchio" else None,
            reach, detect, [state_smoothing(m) for m in data.metas],
            None if validate is None else [state_smoothing(m) for m in validate.metas])
    except IdentificationError as exc:
        raise UserError(f"{','.join(data.files)}: {exc}") from None
    loop = out.loop
    payload = model_payload(arm, spec, out.inertial, loop.terms, loop.run_offsets,
                            out.heldout_offsets, held_out_offset(loop.model, out.train))
    name = "the robot's nominal model (URDF/MJCF)" if declared == "pinocchio" else declared
    files = list(data.files) + ([] if validate is None else list(validate.files))
    return RunsRun(arm.reference, name, list(data.files),
                   [] if validate is None else list(validate.files), holdout, loop,
                   out.error_before, out.error_after, out.left, payload, out.heldout_offsets,
                   out.scored, files, out.found, ranges_json(robot_scales(arm, out.train)),
                   body or "")
