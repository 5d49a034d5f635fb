"""The real-data section on the shipped Panda log, cross-checked: its least-squares reference
equals least squares on Pinocchio's joint-torque regressor (an independent implementation of
the rigid-body columns) plus the same friction columns; its nominal model's error equals
Pinocchio's RNEA scored here; its targets are the ratios of its own per-joint errors; its
checks say what its results show."""

from __future__ import annotations

import numpy as np
import pytest

from harness.data.ingest import ingest
from harness.experiments.peers import joint_friction_columns
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import load_pinocchio
from harness.sections.real_data.section import HOLDOUT, LOG, RATE, ROBOT, log_result
from identification.metrics import rel_error


@pytest.fixture(scope="module")
def section(tmp_path_factory):
    return log_result(tmp_path_factory.mktemp("real"))


@pytest.fixture(scope="module")
def data():
    a = ingest(LOG / "panda_gaz2019.csv.gz", 7, ROBOT, RATE, None).arrays
    return a["q"], a["qd"], a["qdd"], a["tau"]


def test_references_recomputed_independently(section, data):
    q, qd, qdd, tau = data
    split = int(round(len(q) * (1 - HOLDOUT)))
    baseline = PinocchioModel(load_pinocchio(ROBOT))
    X = np.concatenate([baseline.regressor(q, qd, qdd), joint_friction_columns(qd)], axis=2)
    coef, *_ = np.linalg.lstsq(X[:split].reshape(-1, X.shape[2]), tau[:split].ravel(), rcond=None)
    models = section.results["models"]
    np.testing.assert_allclose(models["least_squares"]["heldout_rel_rmse"],
                               rel_error((X @ coef)[split:], tau[split:]), rtol=1e-6)
    np.testing.assert_allclose(models["nominal"]["heldout_rel_rmse"],
                               rel_error(baseline.torque(q, qd, qdd)[split:], tau[split:]),
                               rtol=1e-9)


def test_targets_are_the_ratios_of_its_errors(section):
    models = section.results["models"]
    ratio = (np.array(models["identified"]["heldout_rel_rmse"])
             / np.array(models["least_squares"]["heldout_rel_rmse"]))
    median, worst = section.targets[:2]
    assert median.measured == pytest.approx(np.median(ratio))
    assert worst.measured == pytest.approx(ratio.max())
    assert "same ingested data" in median.name


def test_checks_follow_the_results(section):
    loop = section.results["closeloop"]
    checks = {c.name: c.passed for c in section.checks}
    assert checks["closeloop_never_worse_held_out"] == bool(
        np.all(np.array(loop["error_after"]) <= np.array(loop["error_before"])))
    assert set(checks) == {"closeloop_never_worse_held_out", "closeloop_friction_named_first",
                           "identified_bodies_physically_consistent"}
    physical = section.results["identified"]["physical"]
    assert checks["identified_bodies_physically_consistent"] == bool(
        min(physical["min_pseudo_eigenvalues"]) >= -1e-8)
    assert physical["prior"] == "nominal" and len(physical["friction"]) == 7
