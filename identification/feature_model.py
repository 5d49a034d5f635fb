"""The identified model on a feature library: per joint, named terms and coefficients.

Implements TorqueModel. The fitted intercept (a constant sensor bias in the data) is stored
as `offset` but is NOT part of the torque: the model predicts the torque the robot needs,
not what a biased sensor reads. Read from and written to MODEL.json by identification.model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.library.features import Feature, parse_feature
from identification.torque_model import as_states


@dataclass(frozen=True)
class JointModel:
    """tau_j = sum_k coefficients[k] * terms[k](q, qd, qdd)  (N m)."""

    terms: tuple[str, ...]
    coefficients: tuple[float, ...]
    offset: float = 0.0  # fitted sensor bias, N m (not in the torque)

    def equation(self, joint: int, digits: int = 6) -> str:
        body = " + ".join(f"{c:.{digits}g}*{t}" for c, t in zip(self.coefficients, self.terms,
                                                                 strict=True))
        return f"tau{joint} = {body or '0'}".replace("+ -", "- ")


@dataclass(frozen=True)
class IdentifiedModel:
    """A sparse torque model; `torque` on arrays, `symbolic_torque` on CasADi vectors."""

    dof: int
    joints: tuple[JointModel, ...]
    library: str = ""
    method: str = ""  # "coupled" (one Lagrangian, shared atoms) or "per-joint" (the paper)

    @property
    def offsets(self) -> np.ndarray:
        """The fitted sensor bias per joint (dof,), N m."""
        return np.array([j.offset for j in self.joints])

    def features(self, j: int) -> list[Feature]:
        return [parse_feature(t, self.dof) for t in self.joints[j].terms]

    def torque(self, q, qd, qdd) -> np.ndarray:
        """Torques (n, dof) in N m at states of shape (n, dof)."""
        q, qd, qdd = as_states(q, qd, qdd, self.dof)
        tau = np.zeros_like(q)
        for j, joint in enumerate(self.joints):
            for f, c in zip(self.features(j), joint.coefficients, strict=True):
                tau[:, j] += c * f.evaluate(q, qd, qdd)
        return tau

    def symbolic_torque(self, q, qd, qdd):
        """CasADi (dof, 1) expression of the same model (SX or MX inputs)."""
        import casadi

        rows = []
        for j, joint in enumerate(self.joints):
            expr = 0
            for f, c in zip(self.features(j), joint.coefficients, strict=True):
                expr = expr + c * f.evaluate(q, qd, qdd, lib=casadi)
            rows.append(expr)
        return casadi.vertcat(*rows)

    def equations(self) -> list[str]:
        return [jm.equation(j + 1) for j, jm in enumerate(self.joints)]
