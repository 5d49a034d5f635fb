"""Coupled (one-Lagrangian) regression: atom torques vs CasADi Euler-Lagrange, exact
recovery, base atoms, noise weighting, and the 5 % comparison with per-joint and oracle."""

from __future__ import annotations

import json

import casadi
import numpy as np
import pytest

from harness.data.generate import generate
from harness.paper.identification.published_library import paper_library
from harness.robots.arm import Arm
from identification.errors import IdentificationError
from identification.identify import identify
from identification.library.prior_knowledge import absolute_chain_atoms, arm_atoms, prior_knowledge_library
from identification.model import load_model, model_to_dict
from identification.regression.coupled import AtomBasis, CoupledRegression, base_atoms
from identification.regression.oracle import fit_base_parameters
from tests.helpers import lynxmotion_motion


@pytest.fixture(scope="module")
def clean():
    m = lynxmotion_motion(2000, seed=3)
    pm = Arm.of("lynxmotion").nominal
    return m, pm.torque(m.q, m.qd, m.qdd), pm


def _casadi_euler_lagrange(atom, dof: int, q, qd, qdd) -> np.ndarray:
    """tau = d/dt dL/dqd - dL/dq by CasADi's exact derivatives, for L = atom."""
    sq, sqd, sqdd = (casadi.SX.sym(n, dof) for n in ("q", "qd", "qdd"))
    angle = sum(c * sq[k] for k, c in enumerate(atom.coeffs)) if atom.func else 0
    value = getattr(casadi, atom.func)(angle) if atom.func else 1
    for k in atom.velocities:
        value = value * sqd[k]
    dl_dqd = casadi.gradient(value, sqd)
    tau = casadi.jacobian(dl_dqd, sqd) @ sqdd + casadi.jacobian(dl_dqd, sq) @ sqd - casadi.gradient(value, sq)
    f = casadi.Function("el", [sq, sqd, sqdd], [tau])
    return np.array([np.asarray(f(q[k], qd[k], qdd[k])).ravel() for k in range(len(q))])


@pytest.mark.parametrize("dof, atoms", [(3, arm_atoms(3, symmetric_links=False)),
                                        (2, absolute_chain_atoms(2, symmetric=False))],
                         ids=["arm-3dof", "chain-2dof"])
def test_atom_torques_match_casadi_euler_lagrange(dof, atoms):
    rng = np.random.default_rng(0)
    q, qd, qdd = (rng.uniform(-2, 2, (5, dof)) for _ in range(3))
    design = AtomBasis.from_atoms(atoms, dof).evaluate(q, qd, qdd)
    for a, atom in enumerate(atoms):
        np.testing.assert_allclose(design[:, :, a], _casadi_euler_lagrange(atom, dof, q, qd, qdd),
                                   atol=1e-12, err_msg=atom.name)


def test_noise_free_coupled_fit_is_exact_with_the_true_atoms(clean):
    m, tau, _ = clean
    lib = prior_knowledge_library(3)
    basis = AtomBasis.from_atoms(lib.atoms, 3)
    design = basis.evaluate(m.q, m.qd, m.qdd)
    coef = np.linalg.lstsq(design.reshape(-1, len(basis.atoms)), tau.reshape(-1), rcond=None)[0]
    true = {n for n, c in zip(basis.names, coef, strict=True) if abs(c) > 1e-9}
    result = identify(m.q, m.qd, m.qdd, tau, lib, holdout=0.25)
    assert result.method == "coupled" and result.model.method == "coupled"
    assert np.all(result.heldout_rel_rmse <= 1e-8)
    assert set(result.lagrangian()["atoms"]) == true
    # the per-joint equations are the atoms' expansions: the library's exact per-joint terms
    theta = lib.evaluate(m.q, m.qd, m.qdd)
    for j, joint in enumerate(result.model.joints):
        c = np.linalg.lstsq(theta, tau[:, j], rcond=None)[0]
        assert set(joint.terms) == {n for n, x in zip(lib.names, c, strict=True) if abs(x) > 1e-9}


def test_collinear_atoms_fold_into_base_atoms(clean):
    m, tau, _ = clean
    q = m.q.copy()
    q[:, 2] = 0.0  # frozen elbow: cos(2q2 + q3) = cos(2q2 + 2q3) = cos(2q2), cos(q3) = 1, ...
    qd, qdd = m.qd.copy(), m.qdd.copy()
    qd[:, 2] = qdd[:, 2] = 0.0
    basis = AtomBasis.from_atoms(arm_atoms(3), 3)
    design = basis.evaluate(q, qd, qdd)
    base, folded = base_atoms(design)
    folded_names = {basis.names[k] for k in folded}
    assert len(base) + len(folded) == len(basis.atoms) and len(folded) >= 5
    # qd3^2 has no signature at all; the others equal base atoms' signatures once q3 = 0
    assert {"qd3^2", "qd1^2*cos(2*q2+q3)", "qd2^2*cos(q3)", "qd2*qd3*cos(q3)"} <= folded_names
    pm = Arm.of("lynxmotion").nominal
    reg = CoupledRegression().fit(design, pm.torque(q, qd, qdd))
    np.testing.assert_allclose(reg.predict(design), pm.torque(q, qd, qdd), atol=1e-9)


def test_coupled_beats_per_joint_and_oracle_at_five_percent():
    """Issue #3 on the default data: generate('lynxmotion', 4000, 0.05, seed=0), last 25 %."""
    d = generate(Arm.of("lynxmotion"), 4000, 0.05, seed=0)
    lib = prior_knowledge_library(3)
    coupled = identify(d.q, d.qd, d.qdd, d.tau, lib, 0.25, d.tau_clean)
    per_joint = identify(d.q, d.qd, d.qdd, d.tau, lib, 0.25, d.tau_clean, method="per-joint")
    y = Arm.of("lynxmotion").nominal.regressor(d.q, d.qd, d.qdd)
    fit = fit_base_parameters(y[:3000], d.tau[:3000])
    oracle = np.linalg.norm(fit.predict(y[3000:]) - d.tau_clean[3000:], axis=0) / np.linalg.norm(
        d.tau_clean[3000:], axis=0)
    assert np.all(coupled.heldout_rel_rmse <= 1.25 * oracle)
    assert np.all(coupled.heldout_rel_rmse <= 0.005)
    assert np.all(coupled.heldout_rel_rmse < per_joint.heldout_rel_rmse)
    sigma = 0.05 * d.tau_clean.std(axis=0)  # the noise weights estimate the noise std
    np.testing.assert_allclose(coupled.regressions[0].sigma_, sigma, rtol=0.1)
    offsets = np.array([j.offset for j in coupled.model.joints])  # the sensor bias, 0.2 sigma
    assert np.all(np.abs(offsets - 0.2 * sigma) <= 0.1 * sigma)


def test_coupled_model_round_trips_through_model_json(clean, tmp_path):
    m, tau, _ = clean
    result = identify(m.q, m.qd, m.qdd, tau, prior_knowledge_library(3), holdout=0.25)
    path = tmp_path / "model.json"
    path.write_text(json.dumps(model_to_dict(result.model)))
    model = load_model(path)
    assert model.method == "coupled"
    np.testing.assert_allclose(model.torque(m.q, m.qd, m.qdd), tau, atol=1e-9)


def test_coupled_needs_atoms(clean):
    m, tau, _ = clean
    with pytest.raises(IdentificationError, match="no Lagrangian atoms"):
        identify(m.q, m.qd, m.qdd, tau, paper_library(), method="coupled")
    with pytest.raises(IdentificationError, match="method must be"):
        identify(m.q, m.qd, m.qdd, tau, prior_knowledge_library(3), method="joint")


def test_an_atom_constant_on_the_data_is_folded_into_the_offset():
    """A Coulomb atom of a joint that never reverses in the training data is the per-joint
    offset: fitted beside it, the two cancel with huge coefficients (seen: 7731 N m and a
    held-out error of 1.8e4 on a 300-sample double pendulum); it must be folded, and the fit
    must then predict a motion that does reverse."""
    rng = np.random.default_rng(0)
    n = 400
    qd = 1.0 + 0.5 * np.abs(rng.standard_normal(n))  # joint 1 never reverses
    coulomb = qd / np.sqrt(qd**2 + 1e-6)
    design = np.zeros((n, 2, 3))
    design[:, 0, 0], design[:, 1, 1] = rng.standard_normal(n), rng.standard_normal(n)
    design[:, 0, 2] = coulomb
    base, folded = base_atoms(design)
    assert list(folded) == [2] and list(base) == [0, 1]
    tau = np.stack([2.0 * design[:, 0, 0], -1.0 * design[:, 1, 1]], axis=1) + 0.3
    tau = tau + 0.01 * rng.standard_normal(tau.shape)
    reg = CoupledRegression().fit(design, tau)
    assert reg.coef_[2] == 0.0 and np.all(np.abs(reg.coef_) < 10)
    np.testing.assert_allclose(reg.coef_[:2], [2.0, -1.0], atol=0.01)


def test_shrink_factors_trade_weak_for_moderate_coefficients():
    """1 - 1/t^2 on b ~ N(beta, s^2) (Monte Carlo, 200 000 draws): the shrunk estimate's mean
    squared error is a third of b's for a null coefficient, below b's up to beta = s, at most
    1.5x b's for beta of 2-3 s, within 4 % at 10 s and 1 % at 30 s (the profile documented
    in shrink_factors); a coefficient with no standard error (exact data) is kept."""
    from identification.regression.coupled import shrink_factors

    rng = np.random.default_rng(0)
    s = 0.3
    for ratio, low, high in ((0.0, 0.30, 0.37), (1.0, 0.80, 0.95), (2.0, 1.3, 1.5),
                             (3.0, 1.3, 1.5), (10.0, 1.0, 1.04), (30.0, 1.0, 1.01)):
        b = ratio * s + s * rng.normal(size=200_000)
        shrunk = b * shrink_factors(b, np.full_like(b, s))
        relative = np.mean((shrunk - ratio * s) ** 2) / np.mean((b - ratio * s) ** 2)
        assert low <= relative <= high, (ratio, relative)
    assert shrink_factors(np.array([2.0, 0.5, -3.0]), np.array([0.0, 1.0, 1.0])).tolist() == \
        [1.0, 0.0, pytest.approx(1 - 1 / 9)]
