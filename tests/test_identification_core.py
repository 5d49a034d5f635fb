"""Identification cross-checks: library spans Pinocchio, exact recovery, CasADi = numpy, errors."""

from __future__ import annotations

import json
import warnings

import casadi
import numpy as np
import pytest

from harness.paper.identification.published_library import paper_library
from harness.robots.arm import Arm
from identification.errors import IdentificationError, LibraryRankWarning
from identification.identify import identify
from identification.library.features import parse_feature
from identification.library.generic import generic_library
from identification.library.prior_knowledge import prior_knowledge_library
from identification.model import load_model, model_to_dict
from identification.regression.oracle import fit_base_parameters
from tests.helpers import lynxmotion_motion


@pytest.fixture(scope="module")
def clean():
    m = lynxmotion_motion(2000, seed=3)
    pm = Arm.of("lynxmotion").nominal
    return m, pm.torque(m.q, m.qd, m.qdd), pm


def _residual(library, m, tau):
    theta = library.evaluate(m.q, m.qd, m.qdd)
    coef = np.linalg.lstsq(theta, tau, rcond=None)[0]
    return np.linalg.norm(theta @ coef - tau, axis=0) / np.linalg.norm(tau, axis=0)


@pytest.mark.parametrize("symmetric", [True, False])
def test_prior_knowledge_library_spans_rigid_body_torque(clean, symmetric):
    m, tau, _ = clean
    assert np.all(_residual(prior_knowledge_library(3, symmetric), m, tau) <= 1e-10)


def test_published_library_misses_joint_one_only(clean):
    m, tau, _ = clean
    res = _residual(paper_library(), m, tau)
    assert len(paper_library()) == 75
    assert res[0] > 1e-4 and res[1] < 1e-10 and res[2] < 1e-10


@pytest.mark.parametrize("library", [paper_library(), prior_knowledge_library(3, False),
                                     generic_library(2, 2)], ids=lambda L: L.name)
def test_feature_names_round_trip(library):
    assert all(parse_feature(f.name, library.dof) == f for f in library.features)


def test_noise_free_identification_is_exact(clean):
    m, tau, _ = clean
    lib = prior_knowledge_library(3)
    result = identify(m.q, m.qd, m.qdd, tau, lib, holdout=0.25)
    assert np.all(result.heldout_rel_rmse <= 1e-8)
    theta = lib.evaluate(m.q, m.qd, m.qdd)
    for j, joint in enumerate(result.model.joints):
        coef = np.linalg.lstsq(theta, tau[:, j], rcond=None)[0]
        true = {n for n, c, s in zip(lib.names, coef, np.linalg.norm(theta, axis=0), strict=True)
                if abs(c) * s > 1e-9 * np.linalg.norm(tau[:, j])}
        assert set(joint.terms) == true


def test_symbolic_torque_matches_numeric_and_pinocchio(clean, tmp_path):
    m, tau, pm = clean
    result = identify(m.q, m.qd, m.qdd, tau, prior_knowledge_library(3), holdout=0.25)
    path = tmp_path / "model.json"
    path.write_text(json.dumps(model_to_dict(result.model)))
    model = load_model(path)
    q, qd, qdd = (casadi.SX.sym(n, 3) for n in ("q", "qd", "qdd"))
    f = casadi.Function("f", [q, qd, qdd], [model.symbolic_torque(q, qd, qdd)])
    for k in (0, 777, 1999):
        sym = np.asarray(f(m.q[k], m.qd[k], m.qdd[k])).ravel()
        np.testing.assert_allclose(sym, model.torque(m.q[k:k + 1], m.qd[k:k + 1], m.qdd[k:k + 1])[0],
                                   atol=1e-12)
        np.testing.assert_allclose(sym, tau[k], atol=1e-10)


def test_oracle_recovers_clean_torque(clean):
    m, tau, pm = clean
    fit = fit_base_parameters(pm.regressor(m.q, m.qd, m.qdd), tau)
    assert np.allclose(fit.predict(pm.regressor(m.q, m.qd, m.qdd)), tau, atol=1e-10)


def test_bad_input_raises_one_clear_error(clean):
    m, tau, _ = clean
    lib = prior_knowledge_library(3)
    bad = tau.copy()
    bad[5, 1] = np.nan
    with pytest.raises(IdentificationError, match="NaN"):
        identify(m.q, m.qd, m.qdd, bad, lib)
    with pytest.raises(IdentificationError, match="shape mismatch"):
        identify(m.q, m.qd, m.qdd, tau[:-1], lib)
    with pytest.raises(IdentificationError, match="more samples than features"):
        identify(m.q[:30], m.qd[:30], m.qdd[:30], tau[:30], lib)
    with pytest.raises(IdentificationError, match="constant"):
        identify(m.q, m.qd, m.qdd, np.ones_like(tau), lib)


def test_rank_deficient_library_warns_with_names(clean):
    m, tau, _ = clean
    qd, qdd = m.qd.copy(), m.qdd.copy()
    qd[:, 2] = qdd[:, 2] = 0.0  # every feature with qd3 or qdd3 vanishes
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        identify(m.q, qd, qdd, tau, prior_knowledge_library(3))
    msgs = [str(w.message) for w in caught if issubclass(w.category, LibraryRankWarning)]
    assert msgs and "collinear features:" in msgs[0] and "qdd3" in msgs[0]
