"""The real-data section on the shipped Panda log, cross-checked: its least-squares reference
equals least squares on Pinocchio's joint-torque regressor (an independent implementation of
the rigid-body columns) plus the same friction columns; its nominal model's error equals
Pinocchio's RNEA scored here; its targets are the ratios of its own per-joint errors; its
checks say what its results show."""

from __future__ import annotations

import numpy as np
import pytest

from harness.bench.real_data.section import HOLDOUT, LOG, RATE, ROBOT, log_result
from harness.data.ingest import ingest
from harness.identify.peers import joint_friction_columns
from harness.robots.arm import Arm
from harness.robots.baseline import PinocchioModel

pytestmark = pytest.mark.slow  # the section on the whole log: half a minute


@pytest.fixture(scope="module")
def section(tmp_path_factory):
    return log_result(tmp_path_factory.mktemp("real"))


@pytest.fixture(scope="module")
def data():
    a = ingest(LOG / "panda_gaz2019.csv.gz", Arm.of(ROBOT), RATE, None).arrays
    return a["q"], a["qd"], a["qdd"], a["tau"]


def _rel(estimate, truth):
    """||estimate - truth|| / ||truth|| per joint, written out (not identification.metrics)."""
    return np.sqrt(((estimate - truth) ** 2).sum(axis=0) / (truth ** 2).sum(axis=0))


@pytest.fixture(scope="module")
def independent(data):
    """The least-squares reference on Pinocchio's joint-torque regressor plus the friction
    columns, and the nominal URDF's torque by Pinocchio's RNEA called sample by sample (plus
    the URDF's joint damping), each scored on the held-out part here."""
    import pinocchio as pin

    q, qd, qdd, tau = data
    split = int(round(len(q) * (1 - HOLDOUT)))
    model = Arm.of(ROBOT).pinocchio
    X = np.concatenate([PinocchioModel(model).regressor(q, qd, qdd), joint_friction_columns(qd)],
                       axis=2)
    coef, *_ = np.linalg.lstsq(X[:split].reshape(-1, X.shape[2]), tau[:split].ravel(), rcond=None)
    pdata = pin.Model.createData(model)
    rnea = np.array([pin.rnea(model, pdata, *s) for s in zip(q, qd, qdd, strict=True)])
    rnea = rnea + np.asarray(model.damping) * qd
    return {"least_squares": _rel((X @ coef)[split:], tau[split:]),
            "nominal": _rel(rnea[split:], tau[split:])}


def test_references_recomputed_independently(section, independent):
    models = section.results["models"]
    np.testing.assert_allclose(models["least_squares"]["heldout_rel_rmse"],
                               independent["least_squares"], rtol=1e-6)
    np.testing.assert_allclose(models["nominal"]["heldout_rel_rmse"], independent["nominal"],
                               rtol=1e-9)


def test_targets_are_the_ratios_of_its_errors(section, independent):
    """The targets' denominators are the least-squares reference recomputed independently."""
    identified = np.array(section.results["models"]["identified"]["heldout_rel_rmse"])
    ratio = identified / independent["least_squares"]
    median, worst = section.targets[:2]
    assert median.measured == pytest.approx(np.median(ratio), rel=1e-6)
    assert worst.measured == pytest.approx(ratio.max(), rel=1e-6)
    assert "same ingested data" in median.name


def test_checks_follow_the_results(section):
    loop = section.results["closeloop"]
    checks = {c.name: c.passed for c in section.checks}
    assert checks["closeloop_never_worse_held_out"] == bool(
        np.all(np.array(loop["error_after"]) <= np.array(loop["error_before"])))
    assert set(checks) == {"closeloop_never_worse_held_out", "closeloop_friction_named_first",
                           "identified_bodies_physically_consistent",
                           "readme_figures_reproduced_at_its_window"}
    physical = section.results["identified"]["physical"]
    assert checks["identified_bodies_physically_consistent"] == bool(
        min(physical["min_pseudo_eigenvalues"]) >= -1e-8)
    assert physical["prior"] == "nominal" and len(physical["friction"]) == 7


def test_the_identified_model_is_what_identify_fits(tmp_path):
    """The section's "identified" model is `identify --robot panda` on the ingested log (issue
    #56: it was fitted without the bodies' ellipsoids the command applies)."""
    import json

    from harness.bench.real_data.models import score_models
    from harness.cli import main
    from harness.io import write_npz

    ingested = ingest(LOG / "panda_gaz2019.csv.gz", Arm.of(ROBOT), RATE, None)
    npz, model = tmp_path / "log.npz", tmp_path / "m.json"
    write_npz(npz, **ingested.npz())
    assert main(["identify", "--data", str(npz), "--robot", ROBOT, "--holdout", str(HOLDOUT),
                 "--out", str(model)]) == 0
    a = ingested.arrays
    models, _ = score_models(Arm.of(ROBOT), a["q"], a["qd"], a["qdd"], a["tau"], HOLDOUT)
    ours = json.loads(model.read_text())["metrics"]["heldout_rel_rmse"]
    np.testing.assert_allclose(models["identified"].heldout, ours, rtol=1e-6)


def test_the_rollout_figures_are_what_predict_rollout_writes(tmp_path):
    """The section's rollout figures (its own identification, in memory) are the ones the
    documented commands give: `identify`, then `predict --rollout 0.1,0.5 --rollout-holdout
    0.25` of 'pinocchio' and of the MODEL.json (its MJCF exported to a file and read back)."""
    import json

    from harness.bench.real_data.rollout import rollout_figures
    from harness.bench.real_data.section import _models
    from harness.cli import main
    from harness.io import write_npz

    ingested, _, identification, _ = _models(None)
    section = rollout_figures(Arm.of(ROBOT), identification, ingested.arrays, HOLDOUT)
    npz, model = tmp_path / "panda.npz", tmp_path / "model.json"
    write_npz(npz, **ingested.npz())
    assert main(["identify", "--data", str(npz), "--robot", ROBOT, "--out", str(model)]) == 0
    for name, spec in (("nominal", "pinocchio"), ("identified", str(model))):
        assert main(["predict", "--model", spec, "--data", str(npz), "--rollout", "0.1,0.5",
                     "--rollout-holdout", str(HOLDOUT), "--out", str(tmp_path / "p.npz")]) == 0
        written = json.loads((tmp_path / "p.rollout.json").read_text())["windows"]
        for ours, theirs in zip(section[name]["windows"], written, strict=True):
            assert ours["windows"] == theirs["windows"] and ours["diverged"] == theirs["diverged"]
            np.testing.assert_allclose(ours["q_rms"], theirs["q_rms"], rtol=1e-6)
