"""A torque model on a robot's base atoms (identification.library.kinematic).

tau(q, qd, qdd) = sum_k coef_k * atom_k(q, qd, qdd): each coefficient is a base
inertial parameter (kg, kg m, kg m^2; a primed name is a sum of the standard
parameters folded into it) or a joint's armature, viscous or Coulomb coefficient,
shared by every joint the atom acts on. Implements TorqueModel; the fitted
intercept (a sensor bias) is stored as `offset`, not part of the torque.
Read from and written to MODEL.json by identification.model (`joints[j].terms`: the atoms
that act on joint j).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.friction import FrictionLaw
from identification.library.kinematic import KinematicLibrary, atom_unit
from identification.torque_model import as_states


@dataclass(frozen=True)
class KinematicModel:
    """Coefficients (p,) of a library's base atoms, and per-joint offsets (dof,) in N m."""

    library: KinematicLibrary
    coefficients: np.ndarray
    offsets: np.ndarray
    method: str = "coupled"
    laws: tuple[FrictionLaw, ...] = ()  # per joint, with its column's coefficient below
    law_coefficients: np.ndarray | None = None  # (empty: viscous-coulomb on every joint)

    def law_terms(self) -> list[tuple[int, FrictionLaw, float]]:
        """(joint, law, coefficient) of every joint whose law has a column of its own."""
        return [(j, law, float(self.law_coefficients[j])) for j, law in enumerate(self.laws)
                if law.has_column]

    @property
    def dof(self) -> int:
        return self.library.dof

    def law_torque(self, qd) -> np.ndarray:
        """(n, dof) N m: the part of the torque the laws' own columns give at joint velocities
        qd (n, dof) (a sigmoid's or a Stribeck's friction; zero on the other joints), what a
        rigid body with armature, viscous damping and dry friction does not have."""
        qd = np.atleast_2d(np.asarray(qd, float))
        tau = np.zeros_like(qd)
        for j, law, c in self.law_terms():
            tau[:, j] = c * law.column(qd[:, j])
        return tau

    def torque(self, q, qd, qdd) -> np.ndarray:
        """Torques (n, dof) in N m at states of shape (n, dof)."""
        q, qd, qdd = as_states(q, qd, qdd, self.dof)
        kept = np.flatnonzero(self.coefficients)
        tau = (self.library.evaluate(q, qd, qdd)[:, :, kept] @ self.coefficients[kept]
               if len(kept) else np.zeros_like(q))
        return tau + self.law_torque(qd)

    def symbolic_torque(self, q, qd, qdd):
        """CasADi (dof, 1) expression of the same model."""
        import casadi

        tau = self.library.symbolic(q, qd, qdd) @ self.coefficients
        if not self.law_terms():
            return tau
        own = [0] * self.dof
        for j, law, c in self.law_terms():
            own[j] = c * law.column(qd[j], casadi)
        return tau + casadi.vertcat(*own)

    def joint_terms(self, j: int) -> list[tuple[str, float]]:
        """(atom name, coefficient) of the kept atoms acting on joint j (0-based)."""
        names = self.library.names
        return ([(names[k], float(self.coefficients[k])) for k in np.flatnonzero(self.coefficients)
                 if self.library.acts_on[j, k]]
                + [(law.term(j + 1), c) for i, law, c in self.law_terms() if i == j])

    def equations(self, digits: int = 4) -> list[str]:
        """Per joint: tau_j = sum of coefficient [unit] * Y_j[atom] (N m)."""
        out = []
        # the laws with a column of their own (a viscous law's name is also its atom's)
        own = {law.term(j + 1): law for j, law in enumerate(self.laws) if law.has_column}
        for j in range(self.dof):
            body = " + ".join(f"{c:.{digits}g} N m * {n}[{own[n].describe()}]" if n in own else
                              f"{c:.{digits}g} {atom_unit(n)} * Y{j + 1}[{n}]"
                              for n, c in self.joint_terms(j))
            law = f"  (friction: {self.laws[j].describe()})" if self.laws else ""
            out.append(f"tau{j + 1} (N m) = {body or '0'}{law}".replace("+ -", "- "))
        return out
