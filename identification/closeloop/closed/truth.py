"""Scoring a closed loop against the effects a plant truly carries (known only in simulation).

The estimation never sees the truth; these references tell how close it came:
- the noise floor: the true effect set refitted on the training part (what the
  data allow when the right effects are named);
- the true effects at their true coefficients, against the clean and against the
  measured held-out torque (what the noise allows on the same data);
- the true effects the declared model's own terms span exactly (absorbed: an
  identified model may carry them already, so the loop cannot name them).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.closeloop.candidates.effects import Effect, EffectDictionary, EffectTerm
from identification.closeloop.closed.extended import ExtendedModel
from identification.closeloop.selection.bic import refine_coulomb, refit
from identification.closeloop.selection.plant import projected_dictionary
from identification.closeloop.selection.plant_identified import KeptSpan, refit_kept
from identification.closeloop.selection.residual import noise_sigma
from identification.metrics import rel_error
from identification.torque_model import TorqueModel


@dataclass(frozen=True)
class TruthScores:
    """Held-out per-joint relative errors of the true effect set, and what was absorbed."""

    noise_floor: np.ndarray  # true effect set refitted, vs the clean torque
    truth_error: np.ndarray  # true coefficients, vs the clean torque
    truth_error_measured: np.ndarray  # true coefficients, vs the measured torque
    absorbed: tuple[str, ...]  # labels of true effects the declared model's terms span


def _refit_truth(states, dictionary: EffectDictionary, residual, truth, project):
    """The true effect set's coefficients (and Coulomb shapes) fitted on the training part."""
    sigma = noise_sigma(residual)
    chosen = [Effect(t.effect, t.joint) for t in truth]
    return refine_coulomb(residual, dictionary, sigma, refit(residual, dictionary, sigma, chosen),
                          *states, project)


def score_truth(declared: TorqueModel, q, qd, qdd, tau, tau_clean,
                truth: tuple[EffectTerm, ...], split: int, payload=None,
                joint_refit: bool = False) -> TruthScores:
    """References of the true effect set on the data split at `split` (train | held out).

    joint_refit: the declared model is identified; its kept terms are refitted with the
    effects (as close_loop_identified does); an effect they span exactly is absorbed."""
    tr, held = slice(0, split), slice(split, None)
    states = (q[tr], qd[tr], qdd[tr])
    project = KeptSpan.of(declared, *states).project if joint_refit else None
    residual = project(tau[tr]) if project is not None else tau[tr] - declared.torque(*states)
    dictionary = projected_dictionary(*states, payload, project=project)
    absorbed = tuple(e.label for i, e in enumerate(dictionary.effects)
                     if not np.any(dictionary.columns[:, :, i])
                     and any(Effect(t.effect, t.joint) == e for t in truth))
    visible = tuple(t for t in truth if Effect(t.effect, t.joint).label not in absorbed)
    fitted = _refit_truth(states, dictionary, residual, visible, project)
    predicted = []
    for terms in (fitted, truth):
        base = refit_kept(declared, terms, *states, tau[tr], payload) if joint_refit else declared
        predicted.append(ExtendedModel(base, terms, payload).torque(q[held], qd[held], qdd[held]))
    return TruthScores(rel_error(predicted[0], tau_clean[held]),
                       rel_error(predicted[1], tau_clean[held]),
                       rel_error(predicted[1], tau[held]), absorbed)
