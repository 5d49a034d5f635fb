"""The declared torque model composed with named terms: itself a TorqueModel.

ExtendedModel adds joint effects to a declared model; Summed, Scaled and WithOffsets (a sensor's
offset on a model's torque) are the other pieces; closed_model composes what the measured
loop names (the declared model, a rigid-body correction's scale, a payload's body, the joint
effects and constant offsets) into one, what model.json holds.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from identification.closeloop.candidates.effects import EffectTerm, PayloadTorque, effect_torque
from identification.closeloop.candidates.payload import BodyTorque, LastBody
from identification.errors import IdentificationError
from identification.torque_model import TorqueModel, as_states


class ExtendedModel:
    """tau = declared(q, qd, qdd) + sum of effect terms (N m).

    A `load_friction` term's load is the declared model's torque (with what it sums: the
    payload, the offsets).

    payload / symbolic_payload: the unit-mass end-effector payload torque,
    numeric on (n, dof) arrays and symbolic on CasADi columns; needed only if a
    payload term is present.
    fallback: joints (1..dof) on which the model is `original` (the declared model as
    given; default `declared`) without any effect: the effects made them worse on
    validation (identification.closeloop.selection.screening).
    """

    def __init__(self, declared: TorqueModel, terms: tuple[EffectTerm, ...],
                 payload: PayloadTorque | None = None,
                 symbolic_payload: Callable | None = None,
                 fallback: tuple[int, ...] = (), original: TorqueModel | None = None):
        self.declared = declared
        self.terms = tuple(terms)
        self.dof = declared.dof
        self.fallback = tuple(fallback)
        self.original = original if original is not None else declared
        self._payload = payload
        self._symbolic_payload = symbolic_payload

    def torque(self, q, qd, qdd) -> np.ndarray:
        """Declared torque plus the effects, (n, dof) in N m."""
        q, qd, qdd = as_states(q, qd, qdd, self.dof)
        load = self.declared.torque(q, qd, qdd)
        tau = load + effect_torque(self.terms, q, qd, qdd, self._payload, load)
        if self.fallback:
            cols = [j - 1 for j in self.fallback]
            tau[:, cols] = self.original.torque(q, qd, qdd)[:, cols]
        return tau

    def symbolic_torque(self, q, qd, qdd):
        """CasADi form: the declared model's expression plus each effect's."""
        import casadi as ca

        load = self.declared.symbolic_torque(q, qd, qdd)
        tau = load
        for t in self.terms:
            if t.effect == "payload":
                if self._symbolic_payload is None:
                    raise ValueError("symbolic payload torque not provided")
                tau = tau + t.coefficient * self._symbolic_payload(q, qd, qdd)
                continue
            j = t.joint - 1
            coulomb = sigmoid = 0
            if t.effect in ("coulomb", "load_friction"):
                coulomb = ca.fmin(ca.fmax((qd[j] + t.lead * qdd[j]) / t.eps, -1), 1)
            if t.effect == "sigmoid":
                sigmoid = (1 / (1 + ca.exp(-t.steepness * (qd[j] + t.shift)))
                           - 1 / (1 + np.exp(-t.steepness * t.shift)))
            signal = {"viscous": qd[j], "coulomb": coulomb, "sigmoid": sigmoid,
                      "armature": qdd[j], "offset": 1.0, "spring": q[j],
                      "load_friction": ca.fabs(load[j]) * coulomb}[t.effect]
            unit = ca.DM.zeros(self.dof, 1)
            unit[j] = 1.0
            tau = tau + t.coefficient * signal * unit
        if self.fallback:
            plain = self.original.symbolic_torque(q, qd, qdd)
            tau = ca.vertcat(*[plain[j] if j + 1 in self.fallback else tau[j]
                               for j in range(self.dof)])
        return tau


class Summed:
    """Sum of torque models plus a constant torque per joint (offsets, N m)."""

    def __init__(self, models: tuple[TorqueModel, ...], offsets: np.ndarray):
        self.models, self.offsets, self.dof = models, np.asarray(offsets, float), models[0].dof

    def torque(self, q, qd, qdd) -> np.ndarray:
        q, qd, qdd = as_states(q, qd, qdd, self.dof)
        return sum(m.torque(q, qd, qdd) for m in self.models) + self.offsets

    def symbolic_torque(self, q, qd, qdd):
        return sum(m.symbolic_torque(q, qd, qdd) for m in self.models) + self.offsets


class WithOffsets:
    """A torque model plus a constant torque per joint (a sensor offset, N m): what a
    measured torque is compared with."""

    def __init__(self, model, offsets: np.ndarray):
        # `bias`, not `offsets`: a model's `offsets` are the ones its torque leaves out
        self.model, self.bias, self.dof = model, np.asarray(offsets, float), model.dof

    def torque(self, q, qd, qdd) -> np.ndarray:
        return self.model.torque(q, qd, qdd) + self.bias

    def symbolic_torque(self, q, qd, qdd):
        return self.model.symbolic_torque(q, qd, qdd) + self.bias


class Scaled:
    """A torque model times a constant (the named inertial correction's scale)."""

    def __init__(self, model: TorqueModel, scale: float):
        self.model, self.scale, self.dof = model, float(scale), model.dof

    def torque(self, q, qd, qdd) -> np.ndarray:
        return self.scale * self.model.torque(q, qd, qdd)

    def symbolic_torque(self, q, qd, qdd):
        return self.scale * self.model.symbolic_torque(q, qd, qdd)


def closed_model(declared: TorqueModel, offsets, terms: tuple[EffectTerm, ...],
                 inertial: TorqueModel | None = None, body: LastBody | None = None,
                 ) -> ExtendedModel:
    """The declared model with the named terms (an `inertial` term scales inertial; a
    payload with parameters sits on body) and the offsets: what model.json holds."""
    parts = [declared]
    for t in terms:
        if t.effect == "inertial":
            parts.append(Scaled(inertial, t.coefficient))
        if _body_level(t):
            if body is None:
                raise IdentificationError("a payload with parameters needs the last body")
            parts.append(BodyTorque(body, t.params))
    return ExtendedModel(Summed(tuple(parts), offsets),
                         tuple(t for t in terms if t.effect != "inertial" and not _body_level(t)))


def _body_level(term: EffectTerm) -> bool:
    return term.effect == "payload" and bool(term.params)
