"""The coupled fit on the prior-knowledge library held to the robot's rigid-body structure
(identification.regression.structure): the shared directions against principal angles
(scipy), the truth inside them, the held fit's error against the free one's over noise
draws (Gauss-Markov on nested models), and the F-test's guard."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from harness.identify.fits import arm_identification
from harness.identify.outside_default import BIAS, motion
from harness.robots.arm import Arm
from identification.regression.coupled import AtomBasis, CoupledRegression
from identification.regression.structure import hold_to_structure, shared_directions


@pytest.fixture(scope="module")
def lynx():
    arm = Arm.of("lynxmotion")
    library, _ = arm_identification(arm)
    basis = AtomBasis.from_atoms(library.atoms, library.dof, library.name)
    q, qd, qdd, clean = motion(arm, "multisine", 3001, 3000)
    return arm, basis, (q, qd, qdd), clean


def test_shared_directions_count_the_zero_principal_angles(lynx):
    """The dimension of the span the atoms share with the rigid body's base atoms is the
    number of zero principal angles between the two column spaces (scipy's
    subspace_angles, an independent computation), and each direction's torque lies in it."""
    arm, basis, states, _ = lynx
    atoms, rigid = basis.evaluate(*states), arm.library.evaluate(*states)
    shared = shared_directions(atoms, rigid)
    a, b = atoms.reshape(-1, atoms.shape[-1]), rigid.reshape(-1, rigid.shape[-1])
    angles = scipy.linalg.subspace_angles(a / np.linalg.norm(a, axis=0),
                                          b / np.linalg.norm(b, axis=0))
    assert shared.shape[1] == int(np.sum(angles < 1e-6)) > 0
    np.testing.assert_allclose(shared.T @ shared, np.eye(shared.shape[1]), atol=1e-10)
    for v in shared.T:
        x = a @ v
        residual = x - b @ np.linalg.lstsq(b, x, rcond=None)[0]
        assert np.linalg.norm(residual) <= 1e-8 * np.linalg.norm(x)


def test_the_truth_lies_in_the_shared_directions_and_the_noise_free_fit_stays_exact(lynx):
    arm, basis, states, clean = lynx
    design = basis.evaluate(*states)
    reg = CoupledRegression().fit(design, clean)
    support = np.flatnonzero(reg.support_)
    truth = reg.coef_[support].copy()
    shared = shared_directions(design[:, :, support], arm.library.evaluate(*states))
    assert 0 < shared.shape[1] < len(support)  # the prior library has a free direction here
    assert np.linalg.norm(truth - shared @ (shared.T @ truth)) <= 1e-9 * np.linalg.norm(truth)
    done = hold_to_structure(reg, design, clean, arm.library.evaluate(*states))
    assert done["held"]
    np.testing.assert_allclose(reg.coef_[support], truth, rtol=1e-7, atol=1e-12)


@pytest.mark.slow
def test_held_fit_beats_the_free_fit_over_noise_draws(lynx):
    """Both models contain the truth and the held one is nested in the free one, so its
    expected squared error on any motion is lower (Gauss-Markov): over 12 noise draws at
    10 % on one training motion, scored on a fresh motion of another family."""
    from harness.data.sensors import torque_noise

    arm, basis, states, clean = lynx
    design, rigid = basis.evaluate(*states), arm.library.evaluate(*states)
    judge = motion(arm, "sines", 3050, 3000)
    judged = basis.evaluate(*judge[:3])
    squared = {"free": [], "held": []}
    for k in range(12):
        tau = clean + torque_noise(clean, 0.10, BIAS, np.random.default_rng([k, 5]))
        reg = CoupledRegression().fit(design, tau)
        squared["free"].append(np.mean((judged @ reg.coef_ - judge[3]) ** 2, axis=0))
        assert hold_to_structure(reg, design, tau, rigid)["held"]
        squared["held"].append(np.mean((judged @ reg.coef_ - judge[3]) ** 2, axis=0))
    free, held = (np.mean(squared[k], axis=0) for k in ("free", "held"))
    assert np.all(held <= 1.02 * free) and held[2] <= 0.8 * free[2], (held / free)


def test_a_structure_the_data_reject_is_not_imposed(lynx):
    """A structure that shares directions with the atoms but not the truth's (the atoms'
    own torques with joint 3's sign flipped: only the atoms acting on joints 1-2 alone are
    shared): the F-test rejects it and the fit is left as selected."""
    from harness.data.sensors import torque_noise

    _, basis, states, clean = lynx
    design = basis.evaluate(*states)
    tau = clean + torque_noise(clean, 0.02, BIAS, np.random.default_rng(11))
    reg = CoupledRegression().fit(design, tau)
    before = reg.coef_.copy()
    other = design.copy()
    other[:, 2, :] *= -1.0
    done = hold_to_structure(reg, design, tau, other)
    assert 0 < done["directions"] < done["atoms"]
    assert not done["held"] and done["pvalue"] < 0.01
    np.testing.assert_array_equal(reg.coef_, before)
