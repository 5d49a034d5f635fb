"""A dictionary of named physical effects a declared torque model may lack.

Each candidate is one column of torque per joint: the torque the actuator must
add to the declared model's for a unit coefficient of the effect. Units of the
coefficient follow the CLI contract:

- `viscous`  tau_j = b qd_j                     b in N m s/rad
- `coulomb`  tau_j = f sat((qd_j + lead qdd_j) / eps)
                                                f in N m; sat(x) = clip(x, -1, 1): dry friction
                                                that saturates at f outside a linear zone
                                                |qd + lead qdd| < eps (rad/s). This is exactly
                                                MuJoCo's regularized frictionloss (see below);
                                                lead (s) and eps are shape parameters estimated
                                                per joint from the data once the effect is
                                                selected (effects_selection.refine_coulomb).
- `armature` tau_j = a qdd_j                    a in kg m^2
- `offset`   tau_j = c                          c in N m
- `spring`   tau_j = k q_j                      k in N m/rad (passive -k (q - q_ref), q_ref = 0;
                                                a non-zero q_ref shows up as an offset)
- `payload`  tau = m * tau_unit(q, qd, qdd)     m in kg, a point mass at the end effector;
                                                tau_unit couples all joints.
- `load_friction`
             tau_j = mu |L_j| sat((qd_j + lead qdd_j) / eps)
                                                mu in N m per N m: dry friction that grows
                                                with the torque L_j the joint's gears carry
                                                (Hamon, Gautier & Garrec, IROS 2010: a load
                                                presses the gear teeth together), L the rest
                                                of the model's torque (the declared model and
                                                its payload); the shape is the joint's Coulomb
                                                shape. On a measured log only
                                                (identification.closeloop.selection.runs).
- `sigmoid`  tau_j = phi1 [s(phi2 (qd_j + phi3)) - s(phi2 phi3)], s(x) = 1 / (1 + e^-x)
                                                phi1 in N m; the friction model Gaz et al.
                                                (RA-L 2019) identified on a real Panda:
                                                steepness phi2 (s/rad) and shift phi3 (rad/s)
                                                are shape parameters estimated from the data
                                                (identification.closeloop.selection.one_log). Not in
                                                the default dictionary of simulated plants.

Why that Coulomb shape. MuJoCo's dry friction (joint `frictionloss` f) is a soft
constraint row whose force F minimizes a Huber cost of the constraint acceleration
jar = qdd - aref, aref = -b qd (no position term for friction), b = 2 / (dmax
timeconst) from `solreffriction`/`solimpfriction`; the force is F = -clip(jar / R, -f, f)
with R = (1 - dmin) / dmin * dof_invweight0 (impedance at zero violation is dmin, and
MuJoCo's diagonal approximation for a friction row is the dof's inverse weight at qpos0,
a constant). The actuator must therefore supply
    f clip((qd + qdd / b) / (R f / b), -1, 1),
a saturated-linear function of the velocity `lead` = 1 / b ahead (0.0095 s with the
default solref 0.02 s, dmax 0.95) with a linear zone eps = R f / b that depends on the
joint (light joints have a large inverse weight: 0.26 rad/s on the Lynxmotion's joint 3 at
f = 0.05 N m, 0.0017 rad/s on joint 1). Evaluated at the simulator's true states this
reproduces the actuator force of a frictionloss plant to 1e-16 N m; a tanh of fixed
width cannot (0.0096 N m RMS left on joint 3). The shape is still estimated from data,
never read from the plant.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from identification.friction import sigmoid_friction

JOINT_EFFECTS = ("viscous", "coulomb", "armature", "offset", "spring")
# the candidates on a measured log (identification.closeloop.selection.one_log): Gaz et al.'s sigmoid
# friction beside viscous and Coulomb; the offset is part of the declared model there
MEASURED_EFFECTS = ("viscous", "coulomb", "sigmoid", "armature", "spring")
UNITS = {"viscous": "N m s/rad", "coulomb": "N m", "armature": "kg m^2", "offset": "N m",
         "spring": "N m/rad", "payload": "kg", "sigmoid": "N m",
         "load_friction": "N m per N m of the joint's load torque",
         "inertial": "1 (x the consistent fit's rigid-body correction)"}
SIGMOID_STEEPNESS = 10.0  # s/rad, default phi2 of the sigmoid friction
COULOMB_EPS = 0.01  # rad/s, default half-width of the linear zone
COULOMB_LEAD = 0.01  # s, default lead of the switching velocity
COULOMB_SHAPES = tuple((lead, eps) for lead in (0.0, 0.005, 0.01, 0.02)
                       for eps in (0.001, 0.003, 0.01, 0.03, 0.1, 0.3))  # start grid of refinement

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
    steepness: float = SIGMOID_STEEPNESS  # s/rad, sigmoid shape only (phi2)
    shift: float = 0.0  # rad/s, sigmoid shape only (phi3)
    params: tuple[float, ...] = ()  # payload on a measured log: the last body's 10 standard
    # parameters (identification.closeloop.candidates.payload), coefficient = mass (kg)
    body: str = ""  # the body a payload is on

    def to_json(self) -> dict:
        out = {"joint": self.joint, "effect": self.effect, "coefficient": self.coefficient,
               "unit": UNITS[self.effect]}
        if self.effect == "payload" and self.params:
            from identification.closeloop.candidates.payload import describe

            mass, com, inertia = describe(self.params)
            out.update(body=self.body, mass=mass, com=com.tolist(), inertia=inertia.tolist(),
                       inertia_definition="Ixx, Ixy, Iyy, Ixz, Iyz, Izz (kg m^2) about the "
                                          "centre of mass, axes of the body's frame",
                       frame="the body's (its joint's) frame, m")
        if self.effect in ("coulomb", "load_friction"):
            out.update(lead=self.lead, eps=self.eps)
        if self.effect == "sigmoid":
            out.update(steepness=self.steepness, shift=self.shift)
        return out


def joint_signal(effect: str, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                 lead: float = COULOMB_LEAD, eps: float = COULOMB_EPS,
                 steepness: float = SIGMOID_STEEPNESS, shift: float = 0.0) -> np.ndarray:
    """The (n, dof) per-joint signal of a joint effect for unit coefficient."""
    if effect == "viscous":
        return qd
    if effect == "sigmoid":
        return sigmoid_friction(qd, steepness, shift)
    if effect == "coulomb":
        return np.clip((qd + lead * qdd) / eps, -1.0, 1.0)
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


def load_signal(load: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                lead: float = COULOMB_LEAD, eps: float = COULOMB_EPS) -> np.ndarray:
    """The (n, dof) per-joint signal of `load_friction` for unit coefficient, under the joints'
    load torque load (n, dof) N m."""
    return np.abs(load) * joint_signal("coulomb", q, qd, qdd, lead, eps)


def effect_torque(terms: tuple[EffectTerm, ...], q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                  payload: PayloadTorque | None = None, load: np.ndarray | None = None,
                  ) -> np.ndarray:
    """Sum of the terms' torques (n, dof) in N m; load: the joints' load torque (n, dof) N m,
    needed by a `load_friction` term only."""
    tau = np.zeros_like(q)
    for term in terms:
        if term.effect == "load_friction":
            if load is None:
                raise ValueError("a load_friction term needs the joints' load torque")
            tau[:, term.joint - 1] += term.coefficient * load_signal(
                load, q, qd, qdd, term.lead, term.eps)[:, term.joint - 1]
        elif term.effect == "payload":
            if payload is None:
                raise ValueError("a payload term needs the payload torque function")
            tau += term.coefficient * payload(q, qd, qdd)
        else:
            tau[:, term.joint - 1] += term.coefficient * joint_signal(
                term.effect, q, qd, qdd, term.lead, term.eps, term.steepness,
                term.shift)[:, term.joint - 1]
    return tau
