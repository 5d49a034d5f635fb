"""Physical or nothing: the range in which each named effect's coefficient reads as a property
of the robot, derived from the robot's own scales. An effect outside its range is not named,
whatever it does to the error: a push fitted as friction comes out negative or absurdly large
(a viscous friction of 4058 N m s/rad on a real arm held still and pushed by hand).

Per joint j, with tau_max its torque bound (the motors' or the URDF's effort limit, else
twice the largest torque the data show), v_max its speed bound (the URDF's, else the larger
of twice the data's fastest speed and 1 rad/s) and s its position span (below):

- viscous  b in [0, tau_max / v_max]: at full speed it needs no more than the joint's torque;
- coulomb, sigmoid  f in [0, tau_max];
- armature  a in [0, tau_max ACCEL_TIME / v_max]: the rotor alone lets the joint reach full
  speed in ACCEL_TIME under full torque;
- spring  k in [0, 2 tau_max / s]: half across the span s the data cover (its rest inside it;
  s at least MIN_SPAN, at most the joint's own: a UR5's wrist turns +-2 pi, which no run
  covers) it needs no more than the joint's torque;
- offset  |c| <= tau_max (a sensor's offset, either sign);
- load_friction  mu in [0, LOAD_FRICTION_MAX) N m per N m (Hamon, Gautier & Garrec's gears
  lose a fraction of the load they carry);
- payload  mass in (0, the robot's mass] (its centre of mass is held within reach by the fit);
- inertial  scale in [0, 1]: between the declared rigid body and the consistent fit, both
  physically consistent, so every point between is too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.closeloop.candidates.effects import EffectTerm

ACCEL_TIME = 0.5  # s
LOAD_FRICTION_MAX = 0.5  # N m per N m
MIN_SPEED = 1.0  # rad/s: the speed bound of a robot that declares none, at least
MIN_SPAN = 0.5  # rad: a spring is judged over the data's span, at least this


@dataclass(frozen=True)
class Scales:
    """A robot's scales, per joint (dof,): torque bound (N m), speed bound (rad/s), position
    span (rad); its mass (kg)."""

    torque: np.ndarray
    speed: np.ndarray
    span: np.ndarray
    mass: float

    @classmethod
    def of(cls, torque_limit, speed_limit, lower, upper, mass: float, tau: np.ndarray,
           qd: np.ndarray, q: np.ndarray | None = None) -> Scales:
        """From what the robot declares (None or non-finite where it declares nothing), the
        data's torque tau and speed qd (n, dof) filling the gaps; q (n, dof): the span a
        spring is judged over is the data's (at least MIN_SPAN), within the joint's own."""
        dof = tau.shape[1]
        peak_tau = 2.0 * np.max(np.abs(tau), axis=0)
        peak_qd = np.maximum(2.0 * np.max(np.abs(qd), axis=0), MIN_SPEED)
        torque = _declared(torque_limit, peak_tau, dof)
        speed = _declared(speed_limit, peak_qd, dof)
        span = np.asarray(upper, float) - np.asarray(lower, float)
        span = np.where(np.isfinite(span) & (span > 0), span, 2 * np.pi)
        if q is not None:
            span = np.clip(np.ptp(q, axis=0), np.minimum(MIN_SPAN, span), span)
        return cls(torque, speed, span, float(mass) if mass > 0 else np.inf)

    def bounds(self, term: EffectTerm) -> tuple[float, float]:
        """(low, high) of the term's coefficient."""
        j = term.joint - 1
        tau, v = float(self.torque[j]), float(self.speed[j])
        return {"viscous": (0.0, tau / v), "coulomb": (0.0, tau), "sigmoid": (0.0, tau),
                "armature": (0.0, tau * ACCEL_TIME / v),
                "spring": (0.0, 2.0 * tau / self.span[j]),
                "offset": (-tau, tau), "load_friction": (0.0, LOAD_FRICTION_MAX),
                "payload": (0.0, self.mass), "inertial": (0.0, 1.0)}[term.effect]

    def holds(self, term: EffectTerm) -> bool:
        """Whether the term's coefficient lies in its range (open at 0 for a payload's mass and
        at the top for load friction)."""
        low, high = self.bounds(term)
        c = term.coefficient
        if term.effect == "payload":
            return 0.0 < c <= high
        if term.effect == "load_friction":
            return low <= c < high
        return low <= c <= high

    def why_not(self, term: EffectTerm) -> str:
        """'' if the term holds, else why it is not physical."""
        if self.holds(term):
            return ""
        low, high = self.bounds(term)
        return (f"not physical: {term.effect} {term.coefficient:.3g} outside [{low:.3g}, "
                f"{high:.3g}]")


def _declared(limit, fallback: np.ndarray, dof: int) -> np.ndarray:
    if limit is None:
        return fallback
    v = np.asarray(limit, float).ravel()
    if v.size != dof:
        return fallback
    return np.where(np.isfinite(v) & (v > 0) & (v < 1e10), v, fallback)


def unbounded(dof: int) -> Scales:
    """No bounds but the signs (a caller with no robot at hand: tests of the fits alone)."""
    inf = np.full(dof, np.inf)
    return Scales(inf, np.ones(dof), np.ones(dof), np.inf)


def ranges_json(scales: Scales) -> dict:
    """Per effect, its range per joint ([low, high]), as closeloop.json states it."""
    dof = len(scales.torque)
    out = {e: [list(scales.bounds(EffectTerm(e, j, 0.0))) for j in range(1, dof + 1)]
           for e in ("viscous", "coulomb", "sigmoid", "armature", "spring", "load_friction")}
    out["payload_mass"] = list(scales.bounds(EffectTerm("payload", dof, 0.0)))
    out["inertial_scale"] = [0.0, 1.0]
    out["rule"] = ("identification.closeloop.verdicts.ranges: from the robot's torque and speed limits "
                   "(the data's where it declares none), joint spans and mass")
    return out
