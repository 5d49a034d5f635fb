"""The base-atom regressor keeps the rigid body's and the drives' atoms out of the sparsity
(identification.regression.torque.SELECTED_ATOMS): every such base atom is in the support,
fitted by weighted least squares (never shrunk), where the rule before (every atom selected,
`selected=EVERY_ATOM`) drops some on a draw that barely excites them."""

from __future__ import annotations

import numpy as np

from harness.identify.outside_default import datasets
from harness.robots.arm import Arm
from identification.regression.torque import EVERY_ATOM, BaseAtomRegressor
from identification.regression.weighted import weighted_lstsq


def test_the_rigid_body_and_drive_atoms_stay_unshrunk_where_the_rule_before_dropped_some():
    arm = Arm.of("ur5")
    data = datasets(arm, (3008,), 1500, ("multisine",), (0.10,))[0]  # development draw
    library = arm.library
    kept_out = np.array([not n.startswith("coulomb") for n in library.names])
    args = (library, data.q, data.qd, data.qdd, data.tau)

    default = BaseAtomRegressor().fit(*args).regressions[0]
    base = np.zeros(len(library), bool)
    base[default.base_] = True
    support = np.flatnonzero(default.support_)
    assert np.all(default.support_[kept_out & base])  # none dropped
    # never shrunk: the coefficients are the weighted least squares refit on the support
    design = library.evaluate(data.q, data.qd, data.qdd)
    centred = design - design.mean(axis=0), data.tau - data.tau.mean(axis=0)
    refit = weighted_lstsq(*centred, support, default.sigma_)[0]
    rows = kept_out[support]
    np.testing.assert_allclose(default.coef_[support][rows], refit[rows], rtol=1e-9, atol=1e-12)

    before = BaseAtomRegressor(selected=EVERY_ATOM).fit(*args).regressions[0]
    assert np.any(~before.support_[kept_out & base])  # the rule before drops some here
