"""Joint friction an identified model's torque carries and MuJoCo's joints cannot: felt by the
replay's plant as a torque on its joints.

A MuJoCo joint has armature, linear damping and dry friction (frictionloss); a consistent
fit's MODEL.json gives them one to one (harness.robots.inertials). A joint whose friction law
has a column of its own (Gaz et al.'s sigmoid, a Stribeck term: identification.friction) has
no MuJoCo counterpart: left out, the plant did not spend that friction while the plan, on the
model, paid for it (on the Panda's log, a plan of 0.0812 J replayed at 0.8498 J,
docs/planning.md, 'Replay'). Here it is a force -f(qd) on the joint (qfrc_applied), at the
velocity of the step's start, as the tracking controller's torque is. Both laws saturate, so
the explicit force stays bounded; moving its slope into MuJoCo's implicit damping did no
better (the same energy within 0.1 % on sigmoids of slopes 30 and 100 s/rad, the Panda's plan
and a double pendulum's) and worse on a Stribeck term, whose linearization at rest (slope
F_s / 1 mm/s) holds for no step's change of velocity (the model's energy along the plan
missed by +2.95 %, against +1.25 % explicit, on the double pendulum).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np


@dataclass(frozen=True)
class PlantFriction:
    """The friction torque (n, dof) N m the joints need at velocities (n, dof) rad/s, beyond
    what the MuJoCo plant's joints have, and each such joint's words for REPLAY.json."""

    torque: Callable[[np.ndarray], np.ndarray]
    described: tuple[str, ...]

    @classmethod
    def of(cls, model) -> PlantFriction | None:
        """The part of a torque model's friction in laws of their own (a KinematicModel's
        law_torque), None when it has none."""
        terms = model.law_terms() if hasattr(model, "law_terms") else []
        if not terms:
            return None
        return cls(model.law_torque, tuple(f"joint {j + 1}: {c:.4g} N m x {law.describe()}"
                                           for j, law, c in terms))

    def apply(self, data: mujoco.MjData) -> None:
        """The friction at data's joint velocities, opposing them, in data.qfrc_applied for
        the next step (the plant's joints in the model's joint order: one hinge per dof)."""
        data.qfrc_applied[:] = -self.torque(data.qvel[None].copy())[0]
