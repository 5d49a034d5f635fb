"""Closing the loop when the declared model is itself identified from the same data.

A sparse model fitted on data from a plant with, say, joint friction has already
absorbed the part of the friction its library spans (its qdd_j term is an
armature; its coefficients are biased by the friction's projection on its
terms). Tracing on its plain residual would therefore split an effect between
the model and the added term. Instead the identified model's kept terms and the
effect columns are refitted jointly by least squares on the training part.

By the Frisch-Waugh-Lovell theorem, the joint fit's effect coefficients are the
least-squares fit of the effects on the *projected* problem: each joint's
measured torque and each candidate's torque on that joint with that joint's
kept-term columns projected out (the per-joint noise weights are constants, so
they commute with the projection). Selection runs on that projected problem, so
BIC compares candidates by what the identified model cannot already explain; an
effect the kept terms span exactly (an armature on a joint with a qdd_j term,
or a payload under a full rigid-body library) is invisible and is not named -
the identified model carries it already. The kept terms are then refitted to
the torque minus the named effects (`refit_kept`).

The identification is the loop's own: `close_loop_identified` takes the library (the
identification's configuration), fits it on the training part (identification.identify,
nothing held out) and re-identifies with it as the named effects require; the caller
supplies only data.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from identification.closeloop.candidates.effects import EffectTerm, PayloadTorque, effect_torque
from identification.closeloop.closed.extended import ExtendedModel
from identification.closeloop.selection.plant import (
    CloseLoopResult,
    check_data,
    outcome,
    screened_trace,
    trace,
)
from identification.closeloop.selection.residual import noise_sigma
from identification.feature_model import IdentifiedModel
from identification.identify import identify
from identification.library.base import Library
from identification.model import model_from_dict, model_to_dict


def identified_model(library: Library, q, qd, qdd, tau) -> IdentifiedModel:
    """The declared model of an identified loop: library fitted on all the given samples (the
    training part; nothing held out)."""
    return identify(q, qd, qdd, tau, library, holdout=0.0).model


def term_columns(model: IdentifiedModel, q, qd, qdd) -> list[np.ndarray]:
    """Per joint, the (n, k_j) torques of its kept terms at unit coefficient (N m)."""
    spec = model_to_dict(model)
    dof = int(spec["dof"])
    out = []
    for j, joint in enumerate(spec["joints"]):
        cols = []
        for term in joint["terms"]:
            unit = {"dof": dof, "joints": [{"terms": [term] if i == j else [],
                                            "coefficients": [1.0] if i == j else []}
                                           for i in range(dof)]}
            cols.append(model_from_dict(unit).torque(q, qd, qdd)[:, j])
        out.append(np.stack(cols, axis=1) if cols else np.zeros((len(q), 0)))
    return out


@dataclass(frozen=True)
class KeptSpan:
    """Orthonormal bases (n, r_j) of each joint's kept-term columns on a set of samples."""

    bases: tuple[np.ndarray, ...]

    @classmethod
    def of(cls, model: IdentifiedModel, q, qd, qdd) -> KeptSpan:
        bases = []
        for X in term_columns(model, q, qd, qdd):
            if X.shape[1] == 0:
                bases.append(X)
                continue
            u, s, _ = np.linalg.svd(X, full_matrices=False)
            bases.append(u[:, s > 1e-10 * s[0]])
        return cls(tuple(bases))

    def project(self, x: np.ndarray) -> np.ndarray:
        """x (n, dof) with each joint's kept-term span removed from its column."""
        out = np.array(x, dtype=float, copy=True)
        for j, Q in enumerate(self.bases):
            out[:, j] -= Q @ (Q.T @ out[:, j])
        return out


def refit_kept(model: IdentifiedModel, terms: tuple[EffectTerm, ...], q, qd, qdd, tau,
               payload: PayloadTorque | None = None) -> IdentifiedModel:
    """The model with its kept terms' coefficients refitted by least squares, per joint, to
    tau minus the effects' torque (the joint refit); unchanged if there are no effects.

    The refit is plain least squares even if the identification shared coefficients
    across joints (coupled fit) or denoised first: correcting its coefficients by only the
    effects' projection is not the joint refit then. A joint no effect acts on is left as
    identified: the joint refit leaves its least-squares coefficients unchanged there, and
    the identification's own (regularized, possibly coupled) fit is better on it
    (docs/identification.md, 'identification.closeloop.selection.plant_identified')."""
    if not terms:
        return model
    target = tau - effect_torque(terms, q, qd, qdd, payload)
    touched = np.any(effect_torque(terms, q, qd, qdd, payload) != 0, axis=0)
    spec = model_to_dict(model)
    for j, (X, joint) in enumerate(zip(term_columns(model, q, qd, qdd), spec["joints"],
                                       strict=True)):
        if X.shape[1] and touched[j]:  # a joint no effect acts on keeps its identification
            joint["coefficients"] = np.linalg.lstsq(X, target[:, j], rcond=None)[0].tolist()
    return model_from_dict(spec)


def _not_better_in_training(extended: ExtendedModel, identified: IdentifiedModel, states,
                            tau: np.ndarray) -> set[int]:
    """Joints (1..dof) that no named effect acts on and on which the re-identified model's
    training residual sum of squares is not clearly below the identified model's: by less
    than sqrt(2 / n) of it, one standard deviation of a noise-only sum of squares of n
    samples. There the two differ only by the re-identification (shared coefficients move
    when another joint's target changes), a fit on the same training part, whose small
    in-sample gains do not carry over; large ones do (docs/identification.md,
    'identification.closeloop.selection.plant_identified')."""
    touched = np.any(effect_torque(extended.terms, *states, extended._payload) != 0, axis=0)
    sse = [np.sum((tau - m.torque(*states)) ** 2, axis=0) for m in (extended, identified)]
    margin = 1.0 - np.sqrt(2.0 / len(tau))
    return {int(j) + 1 for j in np.flatnonzero(~touched & (sse[0] > sse[1] * margin))}


def _labels(terms) -> set[tuple[str, int]]:
    return {(t.effect, t.joint) for t in terms}


def _joint_effects(terms: tuple[EffectTerm, ...]) -> tuple[EffectTerm, ...]:
    return tuple(t for t in terms if t.effect != "payload")


def close_loop_identified(library: Library, q, qd, qdd, tau, tau_clean,
                          holdout: float = 0.25, payload: PayloadTorque | None = None,
                          symbolic_payload=None, rounds: int = 3,
                          scales=None) -> CloseLoopResult:
    """Identify the declared model with library on the training part, then trace effects
    jointly with its kept terms; error before is the identified model's, error after that of
    its refit plus the named effects (result.model.original is the identified model).

    A sparse fit on data carrying friction may drop rigid-body terms it needs; the
    dictionary's payload column then stands in for them. The loop therefore re-identifies
    with the same library on the training torque minus the named joint effects (a payload is
    rigid-body dynamics the identified model should carry itself) and traces again, until
    the named set stops changing (at most `rounds` times), which removes that artefact."""
    q, qd, qdd, tau, tau_clean, split = check_data(q, qd, qdd, tau, tau_clean,
                                                   library.dof, holdout)
    tr = slice(0, split)
    states = (q[tr], qd[tr], qdd[tr])

    def reidentify(target: np.ndarray) -> IdentifiedModel:
        return identified_model(library, *states, target)

    identified = reidentify(tau[tr])
    model, named = identified, None
    for _ in range(rounds):
        span = KeptSpan.of(model, *states)
        residual = span.project(tau[tr])  # the residual of the kept terms refitted alone
        selection, terms = trace(residual, noise_sigma(residual), *states, payload, span.project)
        labels = _labels(terms)
        if labels == named:
            break
        named = labels
        model = reidentify(tau[tr] - effect_torque(_joint_effects(terms), *states))
    span = KeptSpan.of(model, *states)
    selection, screening = screened_trace(tau[tr], term_columns(model, *states),
                                          span.project(tau[tr]), noise_sigma(residual), states,
                                          payload, span.project, scales=scales)
    if _labels(screening.named) != labels:
        # the model was re-identified without effects that screening then rejected
        joint = _joint_effects(screening.named)
        model = reidentify(tau[tr] - effect_torque(joint, *states)) if joint else identified
        span = KeptSpan.of(model, *states)
        rejected = screening.candidates
        residual = span.project(tau[tr])
        selection, screening = screened_trace(tau[tr], term_columns(model, *states), residual,
                                              noise_sigma(residual), states, payload,
                                              span.project, scales=scales)
        seen = {(c.term.effect, c.term.joint) for c in screening.candidates} | _labels(
            screening.named)
        screening = replace(screening, candidates=screening.candidates + tuple(
            c for c in rejected if (c.term.effect, c.term.joint) not in seen))
    if not screening.named:  # nothing named: the declared model as it is
        extended = ExtendedModel(identified, (), payload, symbolic_payload)
        return outcome(identified, extended, selection, screening, q, qd, qdd, tau, tau_clean,
                       split)
    refitted = refit_kept(model, screening.named, *states, tau[tr], payload)
    extended = ExtendedModel(refitted, screening.named, payload, symbolic_payload,
                             screening.fallback, identified)
    worse = _not_better_in_training(extended, identified, states, tau[tr])
    if worse:  # joints the re-identification does not clearly improve: the model as identified
        screening = replace(screening, fallback=tuple(sorted(set(screening.fallback) | worse)))
        extended = ExtendedModel(refitted, screening.named, payload, symbolic_payload,
                                 screening.fallback, identified)
    return outcome(identified, extended, selection, screening, q, qd, qdd, tau, tau_clean, split)
