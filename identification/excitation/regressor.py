"""The identification's design matrix as an excitation design sees it: a library's base
atoms (rigid body, armature, viscous, Coulomb) and one torque offset per joint, with the
vector-Jacobian product the design's gradient needs."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np

from identification.library.kinematic import KinematicLibrary


@dataclass(frozen=True)
class AtomRegressor:
    """Columns (n, dof, p + dof): the library's atoms at the states, then offsets (a
    constant unit torque on joint j); torques in N m per unit coefficient."""

    library: KinematicLibrary

    @property
    def dof(self) -> int:
        return self.library.dof

    def evaluate(self, q, qd, qdd) -> np.ndarray:
        atoms = self.library.evaluate(q, qd, qdd)
        offsets = np.broadcast_to(np.eye(self.dof), (len(q), self.dof, self.dof))
        return np.concatenate([atoms, offsets], axis=2)

    @cached_property
    def _reverse(self) -> ca.Function:
        return self.library.function.reverse(1)

    def vjp(self, q, qd, qdd, adjoint: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """d<adjoint, evaluate(q, qd, qdd)> / d(q, qd, qdd), each (n, dof); adjoint is
        (n, dof, p + dof) (the offsets depend on no state)."""
        n, p = len(q), len(self.library)
        states = [np.asarray(x, float).T for x in (q, qd, qdd)]
        atoms = self.library.function.map(n)(*states)
        seed = np.ascontiguousarray(adjoint[:, :, :p].transpose(1, 0, 2)).reshape(self.dof, n * p)
        grads = self._reverse.map(n)(*states, atoms, seed)
        return tuple(np.asarray(g).T for g in grads)
