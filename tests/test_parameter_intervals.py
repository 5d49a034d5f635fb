"""The identified parameters' intervals (identification.parameter_intervals) against closed
forms: on white noise the delete-one-block jackknife of a least-squares fit matches the
analytic least-squares standard error; a body reading is identifiable exactly when its
gradient adds no rank to the base parameters' map."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.stats import t as student

from harness.robots.arm import Arm
from identification.kinematic_model import KinematicModel
from identification.library.base import conditioning
from identification.parameter_intervals import body_readings, identifiable, parameter_intervals
from identification.regression.torque import TorqueFit

BLOCKS = 30  # many folds: the jackknife's own spread about 13 % (1 / sqrt(2 (B - 1)))


class LeastSquares:
    """Plain least squares on the base atoms with an offset per joint (the test's fit)."""

    def fit(self, library, q, qd, qdd, tau):
        design = library.evaluate(q, qd, qdd)  # (n, dof, p)
        n, dof, p = design.shape
        stacked = np.concatenate([design, np.broadcast_to(np.eye(dof), (n, dof, dof))], axis=2)
        x = np.linalg.lstsq(stacked.reshape(n * dof, -1), tau.reshape(-1), rcond=None)[0]
        return TorqueFit(KinematicModel(library, x[:p], x[p:]),
                         conditioning(design.reshape(-1, p), library.names), "least squares")


@pytest.fixture(scope="module")
def ur5():
    return Arm.of("ur5")


def test_white_noise_interval_is_the_least_squares_standard_error(ur5):
    library = ur5.library
    rng = np.random.default_rng(3)
    n, dof = 900, ur5.dof
    t = np.linspace(0, 30, n)[:, None]
    w = rng.uniform(0.5, 2.0, (3, dof))
    q = np.sin(w[0] * t) + 0.5 * np.sin(w[1] * t + w[2])
    qd = w[0] * np.cos(w[0] * t) + 0.5 * w[1] * np.cos(w[1] * t + w[2])
    qdd = -w[0] ** 2 * np.sin(w[0] * t) - 0.5 * w[1] ** 2 * np.sin(w[1] * t + w[2])
    truth = library.fold @ ur5.nominal.atom_parameters()
    design = library.evaluate(q, qd, qdd)
    sigma = 0.05
    tau = design @ truth + sigma * rng.normal(size=(n, dof))
    fit = LeastSquares().fit(library, q, qd, qdd, tau)
    out = parameter_intervals(LeastSquares(), library, q, qd, qdd, tau, fit, blocks=BLOCKS)
    assert out["folds"] == BLOCKS
    # the analytic standard error of each coefficient (offsets included in the design)
    stacked = np.concatenate([design, np.broadcast_to(np.eye(dof), (n, dof, dof))], axis=2)
    x = stacked.reshape(n * dof, -1)
    resid = tau.reshape(-1) - x @ np.linalg.lstsq(x, tau.reshape(-1), rcond=None)[0]
    s2 = resid @ resid / (x.shape[0] - x.shape[1])
    se = np.sqrt(s2 * np.diag(np.linalg.inv(x.T @ x)))[:len(library)]
    half = np.array([out["base_parameters"][name]["interval_95"] for name in library.names])
    ratio = half / student.ppf(0.975, BLOCKS - 1) / se
    assert 0.85 < np.median(ratio) < 1.15, np.median(ratio)
    # one coefficient's: the jackknife's own spread, and a block's leverage (conservative)
    assert np.all((ratio > 0.5) & (ratio < 2.0)), (ratio.min(), ratio.max())
    value = np.array([out["base_parameters"][name]["value"] for name in library.names])
    np.testing.assert_allclose(value, fit.model.coefficients)


def test_identifiable_readings_add_no_rank(ur5):
    """A reading is identifiable iff its gradient's row leaves the rank of the base map fold
    unchanged: an independent rank test (finite differences of the readings) against the
    projection the module uses."""
    fold = ur5.library.fold
    params = ur5.nominal.atom_parameters()
    bodies, joints = identifiable(fold, params)
    rank = np.linalg.matrix_rank(fold, tol=1e-8)
    dof = ur5.dof
    for b in range(dof):
        p = params[10 * b:10 * b + 10]
        for r in range(13):
            grad = np.zeros(fold.shape[1])
            for k in range(10):
                h = 1e-7 * max(abs(p[k]), 1e-3)
                up, down = p.copy(), p.copy()
                up[k] += h
                down[k] -= h
                grad[10 * b + k] = (body_readings(up)[r] - body_readings(down)[r]) / (2 * h)
            if not np.any(grad):
                continue
            grown = np.linalg.matrix_rank(np.vstack([fold, grad / np.linalg.norm(grad)]), tol=1e-8)
            assert bodies[b, r] == (grown == rank), (b, r)
    for j in range(dof):
        for i in range(3):
            e = np.zeros(fold.shape[1])
            e[(10 + i) * dof + j] = 1.0
            assert joints[j, i] == (np.linalg.matrix_rank(np.vstack([fold, e]), tol=1e-8) == rank)
    assert not bodies[:, 0].any()  # no UR5 body's mass alone: masses fold into base sums
    assert joints[:, 1].all()  # every viscous coefficient is its own base parameter


def test_identify_prints_and_writes_each_reading_with_its_interval(tmp_path, capsys):
    """`identify` prints `value +- interval` per base parameter and writes MODEL.json's
    parameter_intervals; each half-width recomputed here through the front door
    (identification.identify on the training samples less one of 4 contiguous blocks,
    Student's t by scipy) agrees; --no-intervals writes none."""
    from harness.cli import main
    from identification.identify import identify
    from identification.regression.torque import BaseAtomRegressor
    from tests.helpers import lynxmotion_motion

    arm = Arm.of("lynxmotion")
    m = lynxmotion_motion(1600, seed=4)
    rng = np.random.default_rng(5)
    tau = arm.nominal.torque(m.q, m.qd, m.qdd)
    tau = tau + 0.02 * tau.std(axis=0) * rng.normal(size=tau.shape)
    data = tmp_path / "d.npz"
    np.savez(data, t=m.t, q=m.q, qd=m.qd, qdd=m.qdd, tau=tau)
    out = tmp_path / "MODEL.json"
    assert main(["identify", "--data", str(data), "--out", str(out), "--library", "kinematic",
                 "--robot", "lynxmotion"]) == 0
    printed = capsys.readouterr().out
    intervals = json.loads(out.read_text())["parameter_intervals"]
    assert "value +- interval (95 %)" in printed and intervals["folds"] == 4
    every = np.arange(1200)  # the training samples: the first 75 %
    folds = [identify(m.q[rows], m.qd[rows], m.qdd[rows], tau[rows], arm.library, 0.0,
                      regressor=BaseAtomRegressor()).model.coefficients
             for rows in (np.setdiff1d(every, b) for b in np.array_split(every, 4))]
    folds = np.array(folds)
    spread = np.sqrt(3 / 4 * np.sum((folds - folds.mean(axis=0)) ** 2, axis=0))
    expected = student.ppf(0.975, 3) * spread
    for k, name in enumerate(arm.library.names):
        if name in intervals["base_parameters"]:
            e = intervals["base_parameters"][name]
            assert f"{name} = {e['value']:.4g} +- {e['interval_95']:.2g}" in printed
            np.testing.assert_allclose(e["interval_95"], expected[k], rtol=1e-6, atol=1e-12)
    assert main(["identify", "--data", str(data), "--out", str(out), "--library", "kinematic",
                 "--robot", "lynxmotion", "--no-intervals"]) == 0
    assert "parameter_intervals" not in json.loads(out.read_text())
    assert "+- interval" not in capsys.readouterr().out
