"""`identify --prior`: the nominal prior by default on measured logs and the sparse fast path
on generated data; the consistent model's MODEL.json says what was imposed, and predict and
the planner's symbolic torque read it back."""

from __future__ import annotations

import json

import casadi as ca
import numpy as np
import pytest

from harness.cli import main
from harness.data.generate import generate
from harness.io import write_npz
from harness.robots.arm import Arm
from harness.robots.torque_models import load_torque_model


def _log(tmp_path, measured: bool):
    d = generate(Arm.of("ur5"), 1500, 0.05, 11, "inverse")
    arrays = d.arrays()
    if measured:  # as `ingest` writes it: no clean torque, the mode named
        arrays.pop("tau_clean")
        meta = json.loads(str(arrays["meta"]))
        arrays["meta"] = np.array(json.dumps({**meta, "mode": "measured log"}))
    path = tmp_path / ("log.npz" if measured else "generated.npz")
    write_npz(path, **arrays)
    return path


@pytest.mark.parametrize("measured, prior, expected", [
    (True, "auto", "nominal"), (False, "auto", None), (False, "flat", "flat"), (True, "none", None)])
def test_the_prior_by_data_kind(tmp_path, capsys, measured, prior, expected):
    data, out = _log(tmp_path, measured), tmp_path / "m.json"
    assert main(["identify", "--data", str(data), "--robot", "ur5", "--prior", prior,
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    metrics = json.loads(out.read_text())["metrics"]
    if expected is None:
        assert "physical" not in metrics and "consistency not imposed" in printed
        return
    physical = metrics["physical"]
    assert physical["prior"] == expected and physical["consistent"] is True
    assert min(physical["min_pseudo_eigenvalues"]) >= -1e-8
    assert f"prior {expected}" in printed and "physically consistent: yes" in printed
    assert all(v >= 0 for k in ("armature", "viscous", "coulomb")
               for v in physical["joint_parameters"][k])
    pred = tmp_path / "p.npz"
    assert main(["predict", "--model", str(out), "--data", str(data), "--out", str(pred)]) == 0
    d, p = np.load(data), np.load(pred)
    assert np.all(np.sqrt(np.mean((p["tau"] - d["tau"]) ** 2, axis=0)) < 0.1 * d["tau"].std(axis=0))


def test_the_prior_needs_the_robots_atoms(tmp_path, capsys):
    d = generate(Arm.of("lynxmotion"), 800, 0.02, 3, "inverse")
    write_npz(tmp_path / "d.npz", **d.arrays())
    out = tmp_path / "m.json"
    assert main(["identify", "--data", str(tmp_path / "d.npz"), "--prior", "nominal",
                 "--library", "prior", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--library kinematic" in err and not out.exists()


def test_a_consistent_model_with_a_friction_law_is_what_the_planner_differentiates(tmp_path):
    """A sigmoid law forced on joint 2 (as the data would choose it): the model read back from
    MODEL.json gives the same torque in numpy and in CasADi, and its Jacobian in qd is the
    finite difference of its torque."""
    from identification.friction import FrictionLaw

    data, out = _log(tmp_path, True), tmp_path / "m.json"
    assert main(["identify", "--data", str(data), "--robot", "ur5", "--out", str(out)]) == 0
    payload = json.loads(out.read_text())
    payload["friction"] = [FrictionLaw().to_dict()] * 6
    payload["friction"][1] = FrictionLaw("sigmoid", (10.0, 0.03)).to_dict()
    payload["joints"][1]["terms"].append("sigmoid2")
    payload["joints"][1]["coefficients"].append(0.7)
    out.write_text(json.dumps(payload))
    model = load_torque_model(str(out), Arm.of("ur5"))
    rng = np.random.default_rng(0)
    q, qd, qdd = (rng.normal(size=6) for _ in range(3))
    x = [ca.SX.sym(s, 6) for s in ("q", "qd", "qdd")]
    expr = model.symbolic_torque(*x)
    f = ca.Function("f", x, [expr, ca.jacobian(expr, x[1])])
    tau, jac = (np.asarray(v) for v in f(q, qd, qdd))
    np.testing.assert_allclose(tau.ravel(), model.torque(q[None], qd[None], qdd[None])[0], atol=1e-10)
    h = 1e-6
    fd = np.column_stack([(model.torque(q[None], (qd + h * e)[None], qdd[None])[0]
                           - model.torque(q[None], (qd - h * e)[None], qdd[None])[0]) / (2 * h)
                          for e in np.eye(6)])
    np.testing.assert_allclose(jac, fd, atol=1e-5)
