"""Closing the loop on a plant: measured data, declared model, traced effects, scores.

Measured data come from `generate(mode="measured")` with zero sensor bias by
default: a constant torque-sensor bias cannot be told apart from a constant
offset torque without a zero-torque calibration (taring the sensor at rest is
what one does on a real arm), so with a bias the `offset` effect is named.
Errors are held-out relative RMS errors against the clean measured torque
`tau_clean` (the actuator force without sensor noise) on the last `holdout`
fraction of the samples.

Declared models: `pinocchio` (the closed-form baseline, fixed), `identified`
(the sparse prior-knowledge-library model fitted on the same training part; its
kept terms are refitted jointly with the effects, identification.closeloop.selection.plant_identified)
or a MODEL.json (fixed). closeloop.json carries the contract's keys for the
chosen one and, under `declared_models`, the effects and errors for both
built-in declared models.

Reference errors, for scoring only (they read the plant's MJCF, which the
estimation never does):
- `truth_error_measured`: declared model plus the true effects at the plant's own
  coefficients (Coulomb at MuJoCo's own friction shape, `friction_shape`), evaluated
  on the estimated states, relative RMS against the *measured* held-out torque: what
  the noise allows on the same data. The acceptance bar: the extended model's
  `error_after_measured` within 1.5x of it (harness.closeloop.acceptance).
- `truth_error`: the same model against the clean torque (what state estimation
  alone allows), and `noise_floor`: the true effect set refitted on the training
  part, against the clean torque. Information only: the noise floor equals the
  error after whenever the right effects are named (same fit), and any fitted
  coefficient costs about sqrt(k / n) noise sigmas against the clean torque, which
  the true coefficients do not pay.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import mujoco
import numpy as np

from harness.closeloop.arm_plants import arm_variant_xml
from harness.closeloop.plants import Variant, true_effects
from harness.data.dataset import Dataset
from harness.data.derivatives import state_smoothing
from harness.data.generate import generate
from harness.errors import UserError
from harness.robots.arm import Arm
from harness.robots.bodies import PayloadTorque, last_body
from harness.robots.registry import flange_frame
from harness.robots.scales import robot_scales
from harness.robots.torque_models import load_torque_model
from identification.closeloop import pipeline
from identification.closeloop.candidates.effects import Effect, EffectTerm
from identification.closeloop.closed.truth import score_truth
from identification.closeloop.events.detect import Events
from identification.closeloop.events.runs import events_json
from identification.closeloop.pipeline import close_the_plant
from identification.closeloop.selection.plant import CloseLoopResult, is_unexplained
from identification.library.base import Library
from identification.library.prior_knowledge import prior_knowledge_library
from identification.metrics import REFERENCES, error_measure
from identification.torque_model import TorqueModel

DECLARED_MODELS = ("pinocchio", "identified")  # both reported in closeloop.json


@dataclass(frozen=True)
class CloseLoopRun:
    """A closed loop on one plant, with the references it is scored against."""

    plant: str
    declared: str
    data: Dataset
    result: CloseLoopResult
    truth: tuple[EffectTerm, ...]  # effects the plant carries beyond the declared model
    outside_dictionary: bool  # the plant carries an effect the dictionary cannot name
    noise_floor: np.ndarray | None  # (dof,) oracle refit error; None if outside dictionary
    truth_error: np.ndarray | None  # (dof,) true-coefficient error vs the clean torque
    truth_error_measured: np.ndarray | None  # (dof,) same vs the measured torque (the bar)
    absorbed: tuple[str, ...] = ()  # labels of true effects the declared model's terms span
    others: tuple[CloseLoopRun, ...] = ()  # the same data with the other declared models
    events: Events | None = None  # external torques found on the data (left out of `data`)

    @property
    def expected(self) -> tuple[EffectTerm, ...]:
        """The true effects the loop can name: those the declared model does not carry."""
        return tuple(t for t in self.truth if Effect(t.effect, t.joint).label not in self.absorbed)

    def summary(self) -> dict:
        """Effects, errors and references of this declared model."""
        r = self.result
        ref = {k: None if v is None else v.tolist() for k, v in
               (("noise_floor", self.noise_floor), ("truth_error", self.truth_error),
                ("truth_error_measured", self.truth_error_measured))}
        return {"effects": [t.to_json() for t in r.terms], "error_before": r.error_before.tolist(),
                "error_after": r.error_after.tolist(), "unexplained": bool(r.unexplained),
                "error_before_measured": r.error_before_measured.tolist(),
                "error_after_measured": r.error_after_measured.tolist(), **ref,
                "candidates": [c.to_json() for c in r.candidates],
                "fallback_joints": list(r.fallback),
                "plant_effects_absorbed": list(self.absorbed)}

    def to_json(self) -> dict:
        r = self.result
        return {
            **self.summary(),
            "unexplained_joints": [d.joint for d in r.diagnostics_after if is_unexplained([d])],
            "declared": self.declared,
            "declared_models": {run.declared: run.summary() for run in (self, *self.others)},
            "plant": self.plant,
            "error_measure": error_measure("clean", "the last 25 % of the samples (time "
                                           "order); *_measured: against " + REFERENCES["measured"]),
            "error_definition": "held-out relative RMS ||tau_hat - tau_clean|| / ||tau_clean|| "
                                "per joint on the last 25 % of samples (time order); *_measured: "
                                "the same against the measured (noisy) torque tau",
            "plant_effects": [t.to_json() for t in self.truth],
            "plant_outside_dictionary": self.outside_dictionary,
            "selection": {"bic_path": [list(p) for p in r.selection.bic_path],
                          "sizes_in_noise_sigma": r.selection.sizes},
            "diagnostics": {"before": [d.to_json() for d in r.diagnostics_before],
                            "after": [d.to_json() for d in r.diagnostics_after]},
            "data": {k: self.data.meta[k] for k in ("samples", "noise", "bias", "seed", "mode")},
            **(events_json([self.plant], [self.events]) if self.events is not None else {}),
        }


def declared_model(spec: str, arm: Arm) -> TorqueModel | Library:
    """'pinocchio' or a MODEL.json path: a fixed torque model of arm; 'identified': the
    library the loop identifies its declared model with (identification.closeloop.selection.plant_identified;
    the Lynxmotion's prior-knowledge library)."""
    if spec == "identified":
        if "prior" not in arm.entry.libraries:
            raise UserError(f"--declared identified is built on a prior-knowledge library, which "
                            f"{arm.label} does not declare; use 'pinocchio' or a MODEL.json")
        return prior_knowledge_library(3)
    return load_torque_model(spec, arm)


def check_plant(plant: Arm, arm: Arm) -> None:
    """UserError, one line, unless plant can be a variant of arm: the same number of joints,
    each of the same type, axis and place (the kinematics hash, Arm.record)."""
    dof = plant.mujoco.nv  # MuJoCo's count first: a file Pinocchio cannot read is refused too
    if dof != arm.dof:
        raise UserError(f"plant {plant.label} has {dof} joints; the declared {arm.label} "
                        f"model has {arm.dof}: not a variant of this robot")
    differ = arm.first_difference(plant)
    if differ is not None:
        where = f"joint {differ}" if differ else "its kinematics"
        raise UserError(f"plant {plant.label}: {where} differs from {arm.label}'s in type, axis "
                        "or position: not a variant of this robot")


def effects_reference(arm: Arm) -> mujoco.MjModel:
    """What a plant's true effects are read against: the arm as its plants are written
    (harness.closeloop.arm_plants; MjSpec.to_xml keeps 6 significant digits, so masses rounded
    alike are not read as a payload)."""
    return mujoco.MjModel.from_xml_string(arm_variant_xml(arm, Variant(name="declared")))


def _loop(spec: str, data: Dataset, split: int, payload: PayloadTorque, truth, outside: bool,
          holdout: float, arm: Arm) -> CloseLoopRun:
    declared = declared_model(spec, arm)
    if declared.dof != data.q.shape[1]:
        raise UserError(f"declared model {spec} has {declared.dof} joints, the plant "
                        f"{data.q.shape[1]}")
    run = (data.q, data.qd, data.qdd, data.tau, data.tau_clean)
    result = close_the_plant(declared, run, holdout, payload, lambda r: robot_scales(arm, r))
    identified = isinstance(declared, Library)
    model = result.model.declared if identified else declared  # identified: the terms of the
    # last re-identification
    if outside:
        return CloseLoopRun(str(data.meta["plant"]), spec, data, result, truth, outside,
                            None, None, None)
    s = score_truth(model, data.q, data.qd, data.qdd, data.tau, data.tau_clean, truth,
                    result.split, payload, identified)
    return CloseLoopRun(str(data.meta["plant"]), spec, data, result, truth, outside,
                        s.noise_floor, s.truth_error, s.truth_error_measured, s.absorbed)


def leave_out_events(data: Dataset, arm: Arm, declared: str) -> tuple[Dataset, Events]:
    """The data without the external torques found on them (the loop's first step,
    identification.closeloop.pipeline.leave_out_events) with the declared model (the arm's
    nominal one when the declared is identified), and those events."""
    model = arm.nominal if declared in DECLARED_MODELS else load_torque_model(declared, arm)
    names = list(data.truth)
    run = (data.q, data.qd, data.qdd, data.tau, data.tau_clean, data.t,
           *(data.truth[n] for n in names))
    (kept,), (found,) = pipeline.leave_out_events(model, [run], [data.t], last_body(arm),
                                                  robot_scales(arm, [run[:4]]),
                                                  smoothing=[state_smoothing(data.meta)])
    if np.all(found.kept):
        return data, found
    q, qd, qdd, tau, tau_clean, t, *truth = kept
    return replace(data, t=t, q=q, qd=qd, qdd=qdd, tau=tau, tau_clean=tau_clean,
                   truth=dict(zip(names, truth, strict=True))), found


def run_closeloop(plant: Arm, arm: Arm, samples: int = 4000, noise: float = 0.05,
                  seed: int = 0, bias: float = 0.0, holdout: float = 0.25,
                  declared: str = "pinocchio", compare: bool = False,
                  pushes=()) -> CloseLoopRun:
    """Generate measured data on plant (a variant of arm: check_plant; pushes: external
    forces on its links, harness.data.pushes), leave out the external torques found on them,
    close the loop on arm's declared model, score it; compare: also close it with the arm's
    other built-in declared models (CloseLoopRun.others)."""
    check_plant(plant, arm)
    data = generate(plant, samples, noise, seed, "measured", bias, robot=arm, pushes=pushes)
    data, found = leave_out_events(data, arm, declared)
    samples = len(data.q)
    split = int(round(samples * (1.0 - holdout)))
    payload = PayloadTorque(arm.pinocchio, flange_frame(arm.pinocchio) or "")
    truth, outside = true_effects(plant.mujoco, effects_reference(arm))
    run = replace(_loop(declared, data, split, payload, truth, outside, holdout, arm),
                  events=found)
    if not compare:
        return run
    specs = DECLARED_MODELS if "prior" in arm.entry.libraries else ("pinocchio",)
    others = tuple(_loop(spec, data, split, payload, truth, outside, holdout, arm)
                   for spec in specs if spec != declared)
    return replace(run, others=others)
