"""Rigid-link atom ties (prior_knowledge.link_pair_atoms): exact Euler-Lagrange torques,
span of every rigid-body torque of the arm (Pinocchio's regressor), rotor inertia kept,
and the bench's independent noise draws."""

from __future__ import annotations

import casadi
import numpy as np
import pytest

from harness.robots.arm import Arm
from identification.identify import identify
from identification.library.prior_knowledge import Atom, Combination, arm_atoms, prior_knowledge_library
from identification.regression.coupled import AtomBasis
from tests.helpers import lynxmotion_motion


@pytest.fixture(scope="module")
def motion():
    m = lynxmotion_motion(1500, seed=3)
    return m, Arm.of("lynxmotion").nominal.regressor(m.q, m.qd, m.qdd)


def _casadi_lagrangian(atom, q, qd):
    if isinstance(atom, Combination):
        return sum(w * _casadi_lagrangian(a, q, qd) for a, w in atom.parts)
    value = getattr(casadi, atom.func)(sum(c * q[k] for k, c in enumerate(atom.coeffs))) if atom.func else 1
    for k in atom.velocities:
        value = value * qd[k]
    return value


def _casadi_torque(atom, q, qd, qdd) -> np.ndarray:
    """d/dt dL/dqd - dL/dq by CasADi's exact derivatives."""
    sq, sqd, sqdd = (casadi.SX.sym(n, 3) for n in ("q", "qd", "qdd"))
    lag = _casadi_lagrangian(atom, sq, sqd)
    dl = casadi.gradient(lag, sqd)
    tau = casadi.jacobian(dl, sqd) @ sqdd + casadi.jacobian(dl, sq) @ sqd - casadi.gradient(lag, sq)
    f = casadi.Function("el", [sq, sqd, sqdd], [tau])
    return np.array([np.asarray(f(q[k], qd[k], qdd[k])).ravel() for k in range(len(q))])


@pytest.mark.parametrize("symmetric", [True, False], ids=["symmetric", "general"])
def test_tied_atom_torques_match_casadi_euler_lagrange(symmetric):
    atoms = arm_atoms(3, symmetric_links=symmetric, rigid_links=True)
    combos = [a for a in atoms if isinstance(a, Combination)]
    assert len(combos) == (2 if symmetric else 3)  # link 3's w^2 and the link pair(s)
    rng = np.random.default_rng(1)
    q, qd, qdd = (rng.uniform(-2, 2, (4, 3)) for _ in range(3))
    design = AtomBasis.from_atoms(atoms, 3).evaluate(q, qd, qdd)
    for a, atom in enumerate(atoms):
        np.testing.assert_allclose(design[:, :, a], _casadi_torque(atom, q, qd, qdd), atol=1e-12,
                                   err_msg=atom.name)


def _span_residual(atoms, motion, target: np.ndarray) -> np.ndarray:
    """Relative residual of each stacked target column (n*dof, k) fitted by the atoms; 0 for
    columns with no torque at all (e.g. a centre-of-mass offset along a joint axis)."""
    m, _ = motion
    a = AtomBasis.from_atoms(atoms, 3).evaluate(m.q, m.qd, m.qdd).reshape(-1, len(atoms))
    sol = np.linalg.lstsq(a, target, rcond=None)[0]
    norms = np.linalg.norm(target, axis=0)
    scale = np.where(norms > 1e-10 * norms.max(), norms, np.inf)
    return np.linalg.norm(a @ sol - target, axis=0) / scale


def test_general_tied_atoms_span_every_rigid_body_torque(motion):
    """Each of Pinocchio's 30 standard-parameter regressor columns (any masses, centres of
    mass and inertia tensors on this arm's kinematics) is a Lagrangian of the 22 atoms."""
    _, regressor = motion
    stacked = regressor.reshape(-1, regressor.shape[-1])
    assert np.all(_span_residual(arm_atoms(3, False, True), motion, stacked) < 1e-9)
    # the symmetric set does not: it assumes centres of mass on the link axes, Iyy = Izz
    assert np.sum(_span_residual(arm_atoms(3, True, True), motion, stacked) > 1e-6) >= 6


def test_tied_atoms_are_a_restriction_that_keeps_rotor_inertia(motion):
    m, _ = motion
    untied = arm_atoms(3, False, False)
    tied = AtomBasis.from_atoms(arm_atoms(3, False, True), 3).evaluate(m.q, m.qd, m.qdd)
    assert np.all(_span_residual(untied, motion, tied.reshape(-1, tied.shape[-1])) < 1e-9)
    for j in range(3):  # armature I_r qd_j^2 / 2: torque I_r qdd_j on joint j alone
        rotor = np.zeros_like(m.qdd)
        rotor[:, j] = m.qdd[:, j]
        assert _span_residual(arm_atoms(3, True, True), motion, rotor.reshape(-1, 1))[0] < 1e-9
    # what the tie removes: qd3^2 cos(q3) alone is no rigid arm's kinetic energy
    lone = AtomBasis.from_atoms([Atom((2, 2), "cos", (0, 0, 1))], 3).evaluate(m.q, m.qd, m.qdd)
    assert _span_residual(arm_atoms(3, False, True), motion, lone.reshape(-1, 1))[0] > 1e-3


def test_tied_library_fits_the_arm_exactly_with_fewer_coefficients(motion):
    m, _ = motion
    tau = Arm.of("lynxmotion").nominal.torque(m.q, m.qd, m.qdd)
    tied, untied = prior_knowledge_library(3), prior_knowledge_library(3, rigid_links=False)
    assert tied.names == untied.names and len(tied.atoms) < len(untied.atoms)
    r = identify(m.q, m.qd, m.qdd, tau, tied, holdout=0.25)
    assert np.all(r.heldout_rel_rmse <= 1e-8)
    kept = r.lagrangian()["atoms"]
    assert len(kept) == 8 and "qd3^2" not in kept  # 8 tied atoms (12 untied), no rotor
    # a rotor on joint 3 (MuJoCo armature: torque I_r qdd3) is the rotor atom 1/2 I_r qd3^2
    armature = 0.005
    rotor = identify(m.q, m.qd, m.qdd, tau + armature * np.eye(3)[2] * m.qdd[:, [2]], tied, 0.25)
    lag = rotor.lagrangian()
    assert set(lag["atoms"]) == set(kept) | {"qd3^2"}
    assert lag["coefficients"][lag["atoms"].index("qd3^2")] == pytest.approx(armature / 2, rel=1e-8)
