"""Closing the loop on a plant: measured data, declared model, traced effects, scores.

Measured data come from `generate(mode="measured")` with zero sensor bias by
default: a constant torque-sensor bias cannot be told apart from a constant
offset torque without a zero-torque calibration (taring the sensor at rest is
what one does on a real arm), so with a bias the `offset` effect is named.
Errors are held-out relative RMS errors against the clean measured torque
`tau_clean` (the actuator force without sensor noise) on the last `holdout`
fraction of the samples.

Reference errors, for scoring only (they read the plant's MJCF, which the
estimation never does):
- `noise_floor`: the oracle - declared model plus the plant's *true* effect set,
  coefficients fitted on the same training data the same way; this is what the
  torque-sensor noise allows.
- `truth_error`: declared model plus the true effects at the plant's own
  coefficients (Coulomb at MuJoCo's own friction shape, `friction_shape`),
  evaluated on the estimated states; what state estimation alone allows. It is
  below `noise_floor` by the sensor noise's share of a least-squares fit on
  finite data (about sigma / sqrt(n) on each coefficient), so it is reported
  beside the floor and each acceptance row says which of the two it meets.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.closeloop_payload import PayloadTorque
from harness.closeloop_plants import true_effects
from harness.datagen import Dataset, generate
from harness.robots import DEFAULT_ROBOT, load_pinocchio
from harness.torque_models import load_torque_model
from identification import TorqueModel
from identification.closeloop import CloseLoopResult, close_loop, is_unexplained, rel_error
from identification.closeloop_model import ExtendedModel
from identification.effects import Effect, EffectTerm, build_dictionary
from identification.effects_selection import refine_coulomb, refit
from identification.residual import noise_sigma


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
    truth_error: np.ndarray | None  # (dof,) true-coefficient error

    def to_json(self) -> dict:
        r = self.result
        return {
            "effects": [t.to_json() for t in r.terms],
            "error_before": r.error_before.tolist(),
            "error_after": r.error_after.tolist(),
            "unexplained": bool(r.unexplained),
            "unexplained_joints": [d.joint for d in r.diagnostics_after if is_unexplained([d])],
            "declared": self.declared,
            "plant": self.plant,
            "error_definition": "held-out relative RMS ||tau_hat - tau_clean|| / ||tau_clean|| "
                                "per joint on the last 25 % of samples (time order)",
            "noise_floor": None if self.noise_floor is None else self.noise_floor.tolist(),
            "truth_error": None if self.truth_error is None else self.truth_error.tolist(),
            "plant_effects": [t.to_json() for t in self.truth],
            "plant_outside_dictionary": self.outside_dictionary,
            "selection": {"bic_path": [list(p) for p in r.selection.bic_path],
                          "sizes_in_noise_sigma": r.selection.sizes},
            "diagnostics": {"before": [d.to_json() for d in r.diagnostics_before],
                            "after": [d.to_json() for d in r.diagnostics_after]},
            "data": {k: self.data.meta[k] for k in ("samples", "noise", "bias", "seed", "mode")},
        }


def declared_model(spec: str, data: Dataset, split: int) -> TorqueModel:
    """'pinocchio', 'identified' (sparse model fitted on the training part of data) or a
    MODEL.json path."""
    if spec != "identified":
        return load_torque_model(spec, DEFAULT_ROBOT)
    from identification import identify, prior_knowledge_library

    result = identify(data.q[:split], data.qd[:split], data.qdd[:split], data.tau[:split],
                      prior_knowledge_library(3), holdout=0.0)
    return result.model


def oracle(declared: TorqueModel, data: Dataset, truth: tuple[EffectTerm, ...], split: int,
           payload: PayloadTorque) -> tuple[np.ndarray, np.ndarray]:
    """Held-out errors of the true effect set refitted (noise floor) and at true values."""
    tr = slice(0, split)
    residual = data.tau[tr] - declared.torque(data.q[tr], data.qd[tr], data.qdd[tr])
    dictionary = build_dictionary(data.q[tr], data.qd[tr], data.qdd[tr], payload)
    sigma = noise_sigma(residual)
    chosen = [Effect(t.effect, t.joint) for t in truth]
    fitted = refine_coulomb(residual, dictionary, sigma, refit(residual, dictionary, sigma, chosen),
                            data.q[tr], data.qd[tr], data.qdd[tr])
    exact = truth
    held = slice(split, None)
    errors = []
    for terms in (fitted, exact):
        model = ExtendedModel(declared, terms, payload)
        errors.append(rel_error(model.torque(data.q[held], data.qd[held], data.qdd[held]),
                                data.tau_clean[held]))
    return errors[0], errors[1]


def run_closeloop(plant: str | Path, samples: int = 4000, noise: float = 0.05, seed: int = 0,
                  bias: float = 0.0, holdout: float = 0.25, declared: str = "pinocchio",
                  ) -> CloseLoopRun:
    """Generate measured data on plant, close the loop on the declared model, score it."""
    data = generate(str(plant), samples, noise, seed, "measured", bias)
    split = int(round(samples * (1.0 - holdout)))
    model = declared_model(declared, data, split)
    payload = PayloadTorque(load_pinocchio(DEFAULT_ROBOT))
    result = close_loop(model, data.q, data.qd, data.qdd, data.tau, data.tau_clean, holdout,
                        payload, payload.symbolic)
    from harness.plant import load_plant

    truth, outside = true_effects(load_plant(plant).model)
    floor = exact = None
    if not outside:
        floor, exact = oracle(model, data, truth, result.split, payload)
    return CloseLoopRun(str(plant), declared, data, result, truth, outside, floor, exact)
