"""A library generated from a robot's kinematic chain alone: its base atoms.

The rigid-body torque of any chain is linear in the bodies' standard inertial
parameters, tau = Y(q, qd, qdd) pi, and the regressor Y is the exact Jacobian of
the chain's Newton-Euler recursion with respect to pi (identification.library.chain):
one column per parameter, a vector over all joints - the parameter's atom, shared
by every joint it acts on, as a Lagrangian atom is. Per joint, a rotor armature
(qdd_j), viscous (qd_j) and Coulomb (smoothed sign of qd_j) atom follow: what a
URDF/MJCF declares as damping and armature belongs to the truth.

Not every atom is identifiable: an atom that is zero on every motion (the mass of
the first link of a vertical-axis base) is dropped, and atoms whose columns are
linearly dependent (a link's mass and the next link's, lumped at a joint) are
grouped into base atoms (pivoted QR of the atoms stacked on random states, Gautier's
numerical base parameters): each kept atom stands for itself plus the dependent ones
folded into it (its name then carries a prime). The span of the base atoms contains
the rigid-body torque of the chain exactly, whatever its inertias.

Nothing here reads an inertial value: only joint placements, axes and gravity.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import casadi as ca
import numpy as np
import scipy.linalg

from identification.library.chain import PARAMETERS, UNITS, KinematicChain, rnea

COULOMB_WIDTH = 1e-3  # rad/s: the Coulomb atom is qd / sqrt(qd^2 + w^2), sign(qd) beyond ~3 w
JOINT_ATOMS = (("armature", "kg m^2"), ("viscous", "N m s/rad"), ("coulomb", "N m"))
N_STATES = 64  # random states the base atoms are found on
RANK_TOL = 1e-4  # relative, on unit-norm columns: an atom independent of the others by less
# is never identifiable from data, and kept it takes huge opposite coefficients with its near
# twin; a URDF's angles rounded (1.5708 for pi/2) leave such a pair (docs/identification.md,
# 'identification.library.kinematic')
SPAN_TOL = 10 * RANK_TOL  # an atom outside the base atoms' span misses by O(1), a folded one by
# less than RANK_TOL


def atom_names(dof: int) -> list[str]:
    """Every candidate atom: 10 inertial parameters per body, then 3 joint atoms per joint."""
    return ([f"{p}{j + 1}" for j in range(dof) for p in PARAMETERS]
            + [f"{a}{j + 1}" for a, _ in JOINT_ATOMS for j in range(dof)])


def atom_unit(name: str) -> str:
    base = name.rstrip("'").rstrip("0123456789")
    return UNITS.get(base) or dict(JOINT_ATOMS)[base]


def _all_atoms(chain: KinematicChain, q, qd, qdd):
    """(dof, 13 dof) CasADi matrix of every candidate atom's torque."""
    params = ca.SX.sym("pi", 10 * chain.dof)
    rigid = ca.jacobian(rnea(chain, q, qd, qdd, params), params)
    coulomb = qd / ca.sqrt(qd**2 + COULOMB_WIDTH**2)
    return ca.horzcat(rigid, ca.diag(qdd), ca.diag(qd), ca.diag(coulomb))


def random_states(dof: int, n: int, seed: int = 0) -> tuple[np.ndarray, ...]:
    """Generic states (angles over the whole circle) for structural rank decisions."""
    rng = np.random.default_rng(seed)
    return rng.uniform(-np.pi, np.pi, (n, dof)), rng.normal(size=(n, dof)), rng.normal(size=(n, dof))


@dataclass(frozen=True)
class KinematicLibrary:
    """The base atoms of a chain: columns (indices into atom_names), each with its group."""

    chain: KinematicChain
    columns: tuple[int, ...]
    grouped: tuple[bool, ...]  # other atoms fold into this one (its coefficient is a sum)
    acts_on: np.ndarray = field(repr=False)  # (dof, p) bool: the atom's torque on joint j is not 0

    @property
    def dof(self) -> int:
        return self.chain.dof

    @property
    def name(self) -> str:
        return f"kinematic-{self.chain.name}"

    @property
    def names(self) -> list[str]:
        every = atom_names(self.dof)
        return [every[c] + ("'" if g else "") for c, g in zip(self.columns, self.grouped, strict=True)]

    def __len__(self) -> int:
        return len(self.columns)

    @cached_property
    def function(self) -> ca.Function:
        """CasADi function (q, qd, qdd) -> (dof, p) base-atom torques."""
        q, qd, qdd = (ca.SX.sym(s, self.dof) for s in ("q", "qd", "qdd"))
        atoms = _all_atoms(self.chain, q, qd, qdd)[:, list(self.columns)]
        return ca.Function("base_atoms", [q, qd, qdd], [atoms])

    def evaluate(self, q, qd, qdd) -> np.ndarray:
        """Atom torques (n, dof, p) at states (n, dof)."""
        n = len(q)
        out = self.function.map(n)(np.asarray(q, float).T, np.asarray(qd, float).T,
                                   np.asarray(qdd, float).T)
        return np.asarray(out).reshape(self.dof, n, len(self)).transpose(1, 0, 2)

    def joint_designs(self, q, qd, qdd) -> list[np.ndarray]:
        """Per joint, the (n, p_j) torques of the base atoms acting on it."""
        design = self.evaluate(q, qd, qdd)
        return [design[:, j][:, self.acts_on[j]] for j in range(self.dof)]

    def symbolic(self, q, qd, qdd):
        """(dof, p) CasADi expression of the base atoms at column vectors q, qd, qdd."""
        return self.function(q, qd, qdd)

    @cached_property
    def every_function(self) -> ca.Function:
        """CasADi function (q, qd, qdd) -> (dof, 13 dof): every candidate atom (atom_names)."""
        q, qd, qdd = (ca.SX.sym(s, self.dof) for s in ("q", "qd", "qdd"))
        return ca.Function("every_atom", [q, qd, qdd], [_all_atoms(self.chain, q, qd, qdd)])

    def evaluate_every(self, q, qd, qdd) -> np.ndarray:
        """Every candidate atom's torque (n, dof, 13 dof) at states (n, dof): the standard
        parameters' regressor, then armature, viscous and Coulomb per joint."""
        n, p = len(q), self.every_function.size2_out(0)
        out = self.every_function.map(n)(np.asarray(q, float).T, np.asarray(qd, float).T,
                                         np.asarray(qdd, float).T)
        return np.asarray(out).reshape(self.dof, n, p).transpose(1, 0, 2)

    @cached_property
    def fold(self) -> np.ndarray:
        """(p, 13 dof): the base coefficients of any candidate-atom coefficients x are fold @ x
        (every atom's torque is the base atoms' times its column); ValueError if an atom is
        outside the base atoms' span (a library generated without it)."""
        states = random_states(self.dof, N_STATES, seed=1)
        every = self.evaluate_every(*states).reshape(-1, 13 * self.dof)
        base = every[:, list(self.columns)]
        fold = np.linalg.lstsq(base, every, rcond=None)[0]
        miss = np.linalg.norm(base @ fold - every, axis=0) > SPAN_TOL * (1 + np.linalg.norm(every, axis=0))
        if miss.any():
            names = [atom_names(self.dof)[k] for k in np.flatnonzero(miss)]
            raise ValueError(f"library {self.name} does not span the atoms {', '.join(names[:5])}")
        fold[np.abs(fold) < 1e-12] = 0.0
        return fold

    @classmethod
    def generate(cls, chain: KinematicChain, coulomb: bool = True,
                 joint_atoms: bool = True) -> KinematicLibrary:
        """Base atoms of chain: zero atoms dropped, dependent ones folded (pivoted QR).
        coulomb False: without the Coulomb atoms; joint_atoms False: the rigid body alone
        (no armature, viscous or Coulomb atom)."""
        q, qd, qdd = (ca.SX.sym(s, chain.dof) for s in ("q", "qd", "qdd"))
        every = ca.Function("atoms", [q, qd, qdd], [_all_atoms(chain, q, qd, qdd)])
        states = random_states(chain.dof, N_STATES)
        p = every.size2_out(0)
        stack = np.asarray(every.map(N_STATES)(*(s.T for s in states)))  # (dof, N * p)
        stack = stack.reshape(chain.dof, N_STATES, p).transpose(1, 0, 2)  # (N, dof, p)
        if not coulomb:
            stack[:, :, p - chain.dof:] = 0.0
        if not joint_atoms:
            stack[:, :, 10 * chain.dof:] = 0.0
        flat = stack.reshape(-1, p)
        norms = np.linalg.norm(flat, axis=0)
        usable = np.flatnonzero(norms > 1e-10 * norms.max())
        _, r, perm = scipy.linalg.qr(flat[:, usable] / norms[usable], mode="economic",
                                     pivoting=True)
        diag = np.abs(np.diag(r))
        rank = int(np.sum(diag > RANK_TOL * diag[0]))
        kept = np.sort(usable[perm[:rank]])
        dependent = np.setdiff1d(usable, kept)
        grouped = np.zeros(len(kept), bool)
        if len(dependent):
            fold = np.linalg.lstsq(flat[:, kept], flat[:, dependent], rcond=None)[0]
            grouped = np.any(np.abs(fold) > 1e-9, axis=1)
        acts_on = np.any(np.abs(stack[:, :, kept]) > 1e-12 * norms[kept], axis=0)
        return cls(chain, tuple(int(k) for k in kept), tuple(bool(g) for g in grouped), acts_on)
