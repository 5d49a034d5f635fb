"""A torque model on a robot's base atoms (identification.library.kinematic).

tau(q, qd, qdd) = sum_k coef_k * atom_k(q, qd, qdd): each coefficient is a base
inertial parameter (kg, kg m, kg m^2; a primed name is a sum of the standard
parameters folded into it) or a joint's armature, viscous or Coulomb coefficient,
shared by every joint the atom acts on. Implements TorqueModel; the fitted
intercept (a sensor bias) is stored as `offset`, not part of the torque.

MODEL.json keeps the CLI contract (`joints[j].terms` / `coefficients`: the atoms that
act on joint j and their coefficients) and records the robot it was identified for
(`robot`: name and a hash of its kinematics) and the base atoms (`atoms`); loading it
needs that robot's chain, and another robot is an error (`from_dict`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.errors import IdentificationError
from identification.friction import FrictionLaw
from identification.library.kinematic import KinematicLibrary, atom_unit
from identification.model import joint_entries
from identification.torque_model import as_states

LIBRARY = "kinematic"


@dataclass(frozen=True)
class KinematicModel:
    """Coefficients (p,) of a library's base atoms, and per-joint offsets (dof,) in N m."""

    library: KinematicLibrary
    coefficients: np.ndarray
    offsets: np.ndarray
    method: str = "coupled"
    laws: tuple[FrictionLaw, ...] = ()  # per joint, with its column's coefficient below
    law_coefficients: np.ndarray | None = None  # (empty: viscous-coulomb on every joint)

    def _law_terms(self) -> list[tuple[int, FrictionLaw, float]]:
        """(joint, law, coefficient) of every joint whose law has a column of its own."""
        return [(j, law, float(self.law_coefficients[j])) for j, law in enumerate(self.laws)
                if law.has_column]

    @property
    def dof(self) -> int:
        return self.library.dof

    def torque(self, q, qd, qdd) -> np.ndarray:
        """Torques (n, dof) in N m at states of shape (n, dof)."""
        q, qd, qdd = as_states(q, qd, qdd, self.dof)
        kept = np.flatnonzero(self.coefficients)
        tau = (self.library.evaluate(q, qd, qdd)[:, :, kept] @ self.coefficients[kept]
               if len(kept) else np.zeros_like(q))
        for j, law, c in self._law_terms():
            tau[:, j] += c * law.column(qd[:, j])
        return tau

    def symbolic_torque(self, q, qd, qdd):
        """CasADi (dof, 1) expression of the same model."""
        import casadi

        tau = self.library.symbolic(q, qd, qdd) @ self.coefficients
        if not self._law_terms():
            return tau
        own = [0] * self.dof
        for j, law, c in self._law_terms():
            own[j] = c * law.column(qd[j], casadi)
        return tau + casadi.vertcat(*own)

    def joint_terms(self, j: int) -> list[tuple[str, float]]:
        """(atom name, coefficient) of the kept atoms acting on joint j (0-based)."""
        names = self.library.names
        return ([(names[k], float(self.coefficients[k])) for k in np.flatnonzero(self.coefficients)
                 if self.library.acts_on[j, k]]
                + [(law.term(j + 1), c) for i, law, c in self._law_terms() if i == j])

    def equations(self, digits: int = 4) -> list[str]:
        """Per joint: tau_j = sum of coefficient [unit] * Y_j[atom] (N m)."""
        out = []
        own = {law.term(j + 1): law for j, law in enumerate(self.laws)}
        for j in range(self.dof):
            body = " + ".join(f"{c:.{digits}g} N m * {n}[{own[n].describe()}]" if n in own else
                              f"{c:.{digits}g} {atom_unit(n)} * Y{j + 1}[{n}]"
                              for n, c in self.joint_terms(j))
            law = f"  (friction: {self.laws[j].describe()})" if self.laws else ""
            out.append(f"tau{j + 1} (N m) = {body or '0'}{law}".replace("+ -", "- "))
        return out

    def to_dict(self) -> dict:
        chain = self.library.chain
        return {"dof": self.dof, "library": LIBRARY, "method": self.method,
                "robot": {"name": chain.name, "hash": chain.digest()},
                "atoms": self.library.names,
                **({"friction": [law.to_dict() for law in self.laws]} if self.laws else {}),
                "joints": [{"terms": [n for n, _ in self.joint_terms(j)],
                            "coefficients": [c for _, c in self.joint_terms(j)],
                            "offset": float(self.offsets[j])} for j in range(self.dof)]}

    @classmethod
    def from_dict(cls, payload: dict, library: KinematicLibrary) -> KinematicModel:
        """Inverse of to_dict for the robot whose library is given; IdentificationError if the
        model was identified for another robot or is malformed."""
        robot = payload.get("robot") if isinstance(payload.get("robot"), dict) else {}
        chain = library.chain
        if robot.get("hash") != chain.digest():
            raise IdentificationError(
                f"model was identified for robot '{robot.get('name')}' (kinematics "
                f"{robot.get('hash')}), not '{chain.name}' ({chain.digest()})")
        if payload.get("atoms") != library.names:
            raise IdentificationError("model atoms differ from this robot's base atoms "
                                      "(generated by another version?)")
        index = {n: k for k, n in enumerate(library.names)}
        laws = payload.get("friction", [])
        if not isinstance(laws, list) or laws and len(laws) != library.dof:
            raise IdentificationError(f"malformed model: 'friction' must list {library.dof} laws")
        laws = tuple(FrictionLaw.from_dict(law) for law in laws)
        own = {law.term(j + 1): j for j, law in enumerate(laws) if law.has_column}
        coef, offsets = np.zeros(len(library)), np.zeros(library.dof)
        law_coef = np.zeros(library.dof)
        for j, joint in enumerate(joint_entries(payload, library.dof)):
            offsets[j] = float(joint.get("offset", 0.0))
            for name, c in zip(joint["terms"], joint["coefficients"], strict=True):
                if own.get(name) == j:
                    law_coef[j] = float(c)
                elif name in index:
                    coef[index[name]] = float(c)
                else:
                    raise IdentificationError(f"malformed model: joint {j + 1} term '{name:.40}' "
                                              "is not one of the robot's base atoms")
        return cls(library, coef, offsets, str(payload.get("method", "coupled")), laws,
                   law_coef if laws else None)
