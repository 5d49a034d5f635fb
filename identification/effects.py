"""A dictionary of named physical effects a declared torque model may lack.

Each candidate is one column of torque per joint: the torque the actuator must
add to the declared model's for a unit coefficient of the effect. Units of the
coefficient follow the CLI contract:

- `viscous`  tau_j = b qd_j                     b in N m s/rad
- `coulomb`  tau_j = f tanh((qd_j + lead qdd_j) / eps)
                                                f in N m; a smooth sign (eps in rad/s) of the
                                                velocity `lead` seconds ahead: dry friction
                                                switches as the joint is about to reverse
                                                (presliding; MuJoCo's soft friction
                                                constraint leads by about half its time
                                                constant). lead and eps are shape parameters
                                                refined per joint once the effect is selected.
- `armature` tau_j = a qdd_j                    a in kg m^2
- `offset`   tau_j = c                          c in N m
- `spring`   tau_j = k q_j                      k in N m/rad (passive -k (q - q_ref), q_ref = 0;
                                                a non-zero q_ref shows up as an offset)
- `payload`  tau = m * tau_unit(q, qd, qdd)     m in kg, a point mass at the end effector;
                                                tau_unit couples all joints.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

JOINT_EFFECTS = ("viscous", "coulomb", "armature", "offset", "spring")
UNITS = {"viscous": "N m s/rad", "coulomb": "N m", "armature": "kg m^2", "offset": "N m",
         "spring": "N m/rad", "payload": "kg"}
COULOMB_EPS = 0.01  # rad/s, default width of the smooth sign
COULOMB_LEAD = 0.01  # s, default lead of the switching velocity
COULOMB_SHAPES = tuple((lead, eps) for lead in (0.0, 0.005, 0.01, 0.015, 0.02, 0.03)
                       for eps in (0.003, 0.01, 0.02, 0.05, 0.1))  # grid refined over

PayloadTorque = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Effect:
    """A named effect on a joint (1..dof); a `payload` sits on the last joint's link (the
    end effector) and acts on all joints."""

    effect: str
    joint: int

    @property
    def label(self) -> str:
        return self.effect if self.effect == "payload" else f"{self.effect}@{self.joint}"


@dataclass(frozen=True)
class EffectTerm:
    """An effect with its coefficient (units in UNITS)."""

    effect: str
    joint: int
    coefficient: float
    lead: float = COULOMB_LEAD  # s, coulomb shape only
    eps: float = COULOMB_EPS  # rad/s, coulomb shape only

    def to_json(self) -> dict:
        out = {"joint": self.joint, "effect": self.effect, "coefficient": self.coefficient,
               "unit": UNITS[self.effect]}
        if self.effect == "coulomb":
            out.update(lead=self.lead, eps=self.eps)
        return out


def joint_signal(effect: str, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                 lead: float = COULOMB_LEAD, eps: float = COULOMB_EPS) -> np.ndarray:
    """The (n, dof) per-joint signal of a joint effect for unit coefficient."""
    if effect == "viscous":
        return qd
    if effect == "coulomb":
        return np.tanh((qd + lead * qdd) / eps)
    if effect == "armature":
        return qdd
    if effect == "offset":
        return np.ones_like(q)
    if effect == "spring":
        return q
    raise ValueError(f"unknown joint effect '{effect}'")


@dataclass(frozen=True)
class EffectDictionary:
    """Candidate effects and their torque columns on a dataset.

    columns[:, :, i] is the (n, dof) torque of effects[i] at unit coefficient.
    """

    effects: tuple[Effect, ...]
    columns: np.ndarray

    def index(self, effect: Effect) -> int:
        return self.effects.index(effect)


def build_dictionary(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                     payload: PayloadTorque | None = None,
                     shapes: dict[int, tuple[float, float]] | None = None) -> EffectDictionary:
    """All joint effects on every joint, plus the end-effector payload when given.

    shapes: joint (1..dof) -> Coulomb (lead, eps); default (COULOMB_LEAD, COULOMB_EPS).
    """
    n, dof = q.shape
    effects: list[Effect] = []
    cols: list[np.ndarray] = []
    for name in JOINT_EFFECTS:
        for j in range(dof):
            lead, eps = (shapes or {}).get(j + 1, (COULOMB_LEAD, COULOMB_EPS))
            signal = joint_signal(name, q, qd, qdd, lead, eps)
            col = np.zeros((n, dof))
            col[:, j] = signal[:, j]
            effects.append(Effect(name, j + 1))
            cols.append(col)
    if payload is not None:
        effects.append(Effect("payload", dof))
        cols.append(np.asarray(payload(q, qd, qdd), dtype=float).reshape(n, dof))
    return EffectDictionary(tuple(effects), np.stack(cols, axis=2))


def effect_torque(terms: tuple[EffectTerm, ...], q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                  payload: PayloadTorque | None = None) -> np.ndarray:
    """Sum of the terms' torques (n, dof) in N m."""
    tau = np.zeros_like(q)
    for term in terms:
        if term.effect == "payload":
            if payload is None:
                raise ValueError("a payload term needs the payload torque function")
            tau += term.coefficient * payload(q, qd, qdd)
        else:
            tau[:, term.joint - 1] += term.coefficient * joint_signal(
                term.effect, q, qd, qdd, term.lead, term.eps)[:, term.joint - 1]
    return tau
