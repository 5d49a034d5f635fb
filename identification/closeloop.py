"""Close the loop on measured data: residual -> missing effect -> add it -> error before/after.

1. Residual of the declared model on the training part (first 1 - holdout of the
   samples in time order) and its diagnostics (identification.residual).
2. Tracing: forward selection with BIC over the effect dictionary
   (identification.effects_selection), all joints at once.
3. Adding: the declared model extended with the selected effects, whose
   coefficients are the weighted least-squares fit on the training residual.
4. Errors: held-out relative RMS error ||tau_hat - tau_clean|| / ||tau_clean||
   per joint on the last `holdout` fraction, before and after.

`unexplained` is set when, after the refit, some joint's residual still carries
structure (a non-white residual, Ljung-Box p < UNEXPLAINED_P, whose part above
the white-noise level exceeds UNEXPLAINED_SIZE noise sigmas) that no candidate
explains: the method then says so instead of forcing a name.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.closeloop_model import ExtendedModel
from identification.effects import EffectTerm, PayloadTorque, build_dictionary
from identification.effects_selection import Selection, refine_coulomb, select_effects
from identification.errors import IdentificationError
from identification.residual import JointDiagnostics, diagnose, noise_sigma
from identification.torque_model import TorqueModel, as_states

UNEXPLAINED_P = 1e-3
UNEXPLAINED_SIZE = 0.25  # structure left, in noise sigmas (0.25 sigma = 3 % extra residual power)
MIN_TRAIN = 200


@dataclass(frozen=True)
class CloseLoopResult:
    """Outcome of one closed loop; torques in N m, errors relative (1 = 100 %)."""

    terms: tuple[EffectTerm, ...]
    selection: Selection
    error_before: np.ndarray  # (dof,) held-out rel RMS error of the declared model
    error_after: np.ndarray  # (dof,) same for the extended model
    diagnostics_before: tuple[JointDiagnostics, ...]
    diagnostics_after: tuple[JointDiagnostics, ...]
    unexplained: bool
    model: ExtendedModel
    split: int  # first held-out sample


def rel_error(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Per-joint ||estimate - truth|| / ||truth||."""
    return np.linalg.norm(estimate - truth, axis=0) / np.maximum(
        np.linalg.norm(truth, axis=0), 1e-300)


def is_unexplained(diags) -> bool:
    """Structure left in a residual that the noise cannot account for."""
    return any(d.ljung_box_p < UNEXPLAINED_P and d.structure > UNEXPLAINED_SIZE for d in diags)


def _check(q, qd, qdd, tau, tau_clean, dof: int, holdout: float):
    try:
        q, qd, qdd = as_states(q, qd, qdd, dof)
        tau, tau_clean, _ = as_states(tau, tau_clean, tau_clean, dof)
    except ValueError as exc:
        raise IdentificationError(str(exc)) from None
    if len(tau) != len(q):
        raise IdentificationError(f"torque has {len(tau)} samples, states have {len(q)}")
    if not 0.0 < holdout < 1.0:
        raise IdentificationError(f"holdout must be in (0, 1), got {holdout}")
    split = int(round(len(q) * (1.0 - holdout)))
    if split < MIN_TRAIN or len(q) - split < 10:
        raise IdentificationError(f"too few samples ({len(q)}) to close the loop")
    return q, qd, qdd, tau, tau_clean, split


def _trace(residual, dictionary, sigma, q, qd, qdd, payload):
    """Select, refine Coulomb shapes, and select again on the refined dictionary, so that
    a default-shaped friction column does not drag in a compensating term."""
    selection = select_effects(residual, dictionary, sigma)
    terms = refine_coulomb(residual, dictionary, sigma, selection.terms, q, qd, qdd)
    shapes = {t.joint: (t.lead, t.eps) for t in terms if t.effect == "coulomb"}
    if not shapes:
        return selection, terms
    dictionary = build_dictionary(q, qd, qdd, payload, shapes)
    selection = select_effects(residual, dictionary, sigma)
    return selection, refine_coulomb(residual, dictionary, sigma, selection.terms, q, qd, qdd)


def close_loop(declared: TorqueModel, q, qd, qdd, tau, tau_clean, holdout: float = 0.25,
               payload: PayloadTorque | None = None, symbolic_payload=None) -> CloseLoopResult:
    """Trace the declared model's residual on measured data to named effects and add them."""
    q, qd, qdd, tau, tau_clean, split = _check(q, qd, qdd, tau, tau_clean, declared.dof, holdout)
    train = slice(0, split)
    held = slice(split, None)
    tau_declared = declared.torque(q, qd, qdd)
    residual = tau[train] - tau_declared[train]
    dictionary = build_dictionary(q[train], qd[train], qdd[train], payload)
    signals = {e.label: dictionary.columns[:, :, i] for i, e in enumerate(dictionary.effects)}
    sigma = noise_sigma(residual)
    selection, terms = _trace(residual, dictionary, sigma, q[train], qd[train], qdd[train], payload)
    model = ExtendedModel(declared, terms, payload, symbolic_payload)
    tau_after = model.torque(q, qd, qdd)
    after = tau[train] - tau_after[train]
    diags_after = tuple(diagnose(after))
    return CloseLoopResult(
        terms=terms,
        selection=selection,
        error_before=rel_error(tau_declared[held], tau_clean[held]),
        error_after=rel_error(tau_after[held], tau_clean[held]),
        diagnostics_before=tuple(diagnose(residual, signals)),
        diagnostics_after=diags_after,
        unexplained=is_unexplained(diags_after),
        model=model,
        split=split,
    )
