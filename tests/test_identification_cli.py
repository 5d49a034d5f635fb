"""`torquebench identify`: MODEL.json contract, methods, and one-line errors with no file."""

from __future__ import annotations

import json

import numpy as np
import pytest

from harness.cli import main
from harness.robots.arm import Arm
from identification.model import load_model
from tests.helpers import lynxmotion_motion


@pytest.fixture(scope="module")
def arrays():
    m = lynxmotion_motion(1600, seed=4)
    tau = Arm.of("lynxmotion").nominal.torque(m.q, m.qd, m.qdd)
    rng = np.random.default_rng(2)
    noisy = tau + 0.01 * tau.std(axis=0) * (rng.normal(size=tau.shape) + 0.2)
    return {"t": m.t, "q": m.q, "qd": m.qd, "qdd": m.qdd, "tau": noisy, "tau_clean": tau}


def _write(tmp_path, arrays, name="data.npz", **changes):
    path = tmp_path / name
    payload = {**arrays, **changes}
    np.savez(path, **{k: v for k, v in payload.items() if v is not None})
    return path


@pytest.mark.parametrize("method", ["auto", "per-joint"])
def test_identify_writes_the_contract(tmp_path, arrays, method, capsys):
    data, out = _write(tmp_path, arrays), tmp_path / "MODEL.json"
    assert main(["identify", "--data", str(data), "--out", str(out), "--method", method]) == 0
    payload = json.loads(out.read_text())
    assert payload["dof"] == 3 and len(payload["joints"]) == 3
    assert payload["method"] == ("coupled" if method == "auto" else "per-joint")
    for joint in payload["joints"]:
        assert len(joint["terms"]) == len(joint["coefficients"]) > 0
    metrics = payload["metrics"]
    for key in ("heldout_rel_rmse", "heldout_mse", "library_size", "library_condition"):
        assert key in metrics
    assert len(metrics["heldout_rel_rmse"]) == 3 and max(metrics["heldout_rel_rmse"]) < 0.01
    assert ("lagrangian" in payload) == (method == "auto")
    # the held-out error is the model's, recomputed independently on the last 25 %
    model = load_model(out)
    rows = slice(1200, None)
    pred = model.torque(arrays["q"][rows], arrays["qd"][rows], arrays["qdd"][rows])
    truth = arrays["tau_clean"][rows]
    np.testing.assert_allclose(metrics["heldout_rel_rmse"],
                               np.linalg.norm(pred - truth, axis=0) / np.linalg.norm(truth, axis=0))
    assert "wrote" in capsys.readouterr().out


def _bad_cases(arrays):
    nan = arrays["tau"].copy()
    nan[3, 1] = np.nan
    return {
        "nan": ({"tau": nan}, [], "NaN"),
        "missing": ({"qdd": None}, [], "missing keys qdd"),
        "shape": ({"q": arrays["q"][:-1]}, [], "shape mismatch"),
        "few": ({k: arrays[k][:20] for k in ("q", "qd", "qdd", "tau", "tau_clean")}, [], "more samples"),
        "holdout": ({}, ["--holdout", "1.5"], "holdout"),
        "holdout0": ({}, ["--holdout", "0"], "--holdout must be in (0, 1), got 0.0"),
        "holdout1": ({}, ["--holdout", "1"], "--holdout must be in (0, 1)"),
        "holdoutneg": ({}, ["--holdout", "-0.1"], "--holdout must be in (0, 1)"),
        "method": ({}, ["--library", "paper", "--method", "coupled"], "no Lagrangian atoms"),
        "metric": ({}, ["--prior", "none", "--prior-metric", "entropic"], "--prior nominal"),
    }


@pytest.mark.parametrize("case", ["nan", "missing", "shape", "few", "holdout", "holdout0",
                                  "holdout1", "holdoutneg", "method", "metric", "nofile"])
def test_bad_input_exits_2_with_one_line_and_no_file(tmp_path, arrays, case, capsys):
    out = tmp_path / "MODEL.json"
    if case == "nofile":
        data, extra, match = tmp_path / "absent.npz", [], "not found"
    else:
        changes, extra, match = _bad_cases(arrays)[case]
        data = _write(tmp_path, arrays, **changes)
    assert main(["identify", "--data", str(data), "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("torquebench identify: error:") and match in err[0]
    assert not out.exists() and not list(tmp_path.glob(".MODEL.json*"))


def test_identify_general_library_drops_the_symmetry_assumption(tmp_path, arrays):
    """--library prior-general: the atoms of general links; on this symmetric arm it keeps
    the symmetric fit's atoms and predicts the same torque (up to the noise weights, which
    are estimated on each set's own candidate atoms)."""
    data, models = _write(tmp_path, arrays), {}
    for library in ("prior", "prior-general"):
        out = tmp_path / f"{library}.json"
        assert main(["identify", "--data", str(data), "--out", str(out), "--library", library]) == 0
        models[library] = json.loads(out.read_text())
    assert models["prior"]["library"] == "prior-3dof"
    assert models["prior-general"]["library"] == "prior-3dof-general"
    assert set(models["prior-general"]["lagrangian"]["atoms"]) == set(models["prior"]["lagrangian"]["atoms"])
    m = lynxmotion_motion(200, seed=9)
    general, symmetric = (load_model(tmp_path / f"{k}.json") for k in ("prior-general", "prior"))
    np.testing.assert_allclose(general.torque(m.q, m.qd, m.qdd), symmetric.torque(m.q, m.qd, m.qdd),
                               rtol=1e-4, atol=1e-6)


def test_library_holdout_zero_reports_no_heldout_error(arrays):
    """identify(..., holdout=0) (the closed loop's final fit) fits on everything and scores
    nothing: no training error under the held-out name; a holdout that rounds to no sample
    is an error."""
    from identification.errors import IdentificationError
    from identification.identify import identify
    from identification.library.prior_knowledge import prior_knowledge_library

    lib = prior_knowledge_library(3)
    args = (arrays["q"], arrays["qd"], arrays["qdd"], arrays["tau"], lib)
    r = identify(*args, 0.0, arrays["tau_clean"])
    assert np.all(np.isnan(r.heldout_rel_rmse)) and np.all(np.isnan(r.heldout_mse))
    metrics = r.metrics()
    assert metrics["heldout_rel_rmse"] == [None] * 3 and metrics["heldout_mse"] == [None] * 3
    json.dumps(metrics, allow_nan=False)
    with pytest.raises(IdentificationError, match="no held-out sample"):
        identify(*args, 1e-5, arrays["tau_clean"])


def test_every_warning_of_the_identification_reaches_the_user(tmp_path, arrays, capsys,
                                                               monkeypatch):
    """A warning raised while identifying (here a RuntimeWarning, as numpy or scikit-learn
    raise them) is printed on stderr, once; only the library's rank warning reached the user
    before."""
    import warnings

    import harness.commands.identify as command

    real = command.identify

    def noisy(*args, **kwargs):
        for _ in range(3):
            warnings.warn("objective did not converge", RuntimeWarning, stacklevel=1)
        return real(*args, **kwargs)

    monkeypatch.setattr(command, "identify", noisy)
    data = _write(tmp_path, arrays)
    assert main(["identify", "--data", str(data), "--out", str(tmp_path / "m.json")]) == 0
    err = capsys.readouterr().err
    assert err.count("torquebench identify: warning: RuntimeWarning: objective did not "
                     "converge") == 1


def _generated(tmp_path, name, seed, noise=0.05, clean=True, bias=0.2):
    from harness.data.generate import generate
    from harness.io import write_npz

    d = generate(Arm.of("ur5"), 1500, noise, seed, "inverse", bias=bias)
    arrays = d.arrays()
    if not clean:  # as a measured log: no clean torque
        arrays.pop("tau_clean")
    path = tmp_path / name
    write_npz(path, **arrays)
    return path


def test_several_runs_in_another_out(tmp_path):
    """identify --data A,B --validate C: fitted on A and B only, scored on C, and MODEL.json
    names what was held out; the score is the model's own error on C, recomputed here."""
    from harness.robots.torque_models import load_torque_model
    from identification.metrics import rel_error

    a, b, c = (_generated(tmp_path, f"{k}.npz", s) for k, s in (("a", 1), ("b", 2), ("c", 3)))
    out = tmp_path / "m.json"
    assert main(["identify", "--data", f"{a},{b}", "--validate", str(c), "--out", str(out)]) == 0
    metrics = json.loads(out.read_text())["metrics"]
    assert metrics["heldout"] == {"kind": "logs", "logs": [str(c)], "fitted_on": [str(a), str(b)],
                                  "samples": 1500}
    assert metrics["scored_against"] == "tau_clean"
    model, judge = load_torque_model(str(out), Arm.of("ur5")), np.load(c)
    mine = rel_error(model.torque(judge["q"], judge["qd"], judge["qdd"]), judge["tau_clean"])
    np.testing.assert_allclose(metrics["heldout_rel_rmse"], mine, rtol=1e-9)
    # the same model fitted on A alone differs: B was used in fitting
    alone = tmp_path / "alone.json"
    assert main(["identify", "--data", str(a), "--validate", str(c), "--out", str(alone)]) == 0
    assert json.loads(alone.read_text())["joints"] != json.loads(out.read_text())["joints"]
    # and C was not: validated on another log (D), the model is the same, term for term
    d = _generated(tmp_path, "d.npz", 4)
    other = tmp_path / "other.json"
    assert main(["identify", "--data", f"{a},{b}", "--validate", str(d), "--out", str(other)]) == 0
    assert json.loads(other.read_text())["joints"] == json.loads(out.read_text())["joints"]


@pytest.mark.parametrize("prior", ["none", pytest.param("nominal", marks=pytest.mark.slow)])
def test_two_runs_predict_a_third_no_worse_than_one(tmp_path, prior):
    """Issue #42: two runs of different excitations whose sensors read different offsets (as
    two sessions do) predict a third run at least as well as the first alone, at the median
    over joints: each run is fitted with its own offset (one offset made the step between
    the runs dynamics: 14x worse on the Panda)."""
    a = _generated(tmp_path, "a.npz", 1, bias=3.0)
    b = _generated(tmp_path, "b.npz", 2, bias=-3.0)
    c = _generated(tmp_path, "c.npz", 3, noise=0.0)
    errors = {}
    for name, data in (("one", str(a)), ("two", f"{a},{b}")):
        out = tmp_path / f"{name}.json"
        assert main(["identify", "--data", data, "--validate", str(c), "--prior", prior,
                     "--out", str(out)]) == 0
        errors[name] = np.median(json.loads(out.read_text())["metrics"]["heldout_rel_rmse"])
    assert errors["two"] <= errors["one"], errors


def test_runs_of_different_robots_are_one_line_exit_2(tmp_path, arrays, capsys):
    a = _generated(tmp_path, "a.npz", 1)
    b = _write(tmp_path, arrays)
    out = tmp_path / "m.json"
    assert main(["identify", "--data", f"{a},{b}", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and not out.exists()


def test_predict_on_a_measured_log_reads_like_its_sensor(tmp_path):
    """A log without tau_clean (biased sensor noise): predict adds the model's fitted offset,
    also stored apart, and so reads the measured torque better than without it."""
    log = _generated(tmp_path, "log.npz", 4, clean=False)
    model, pred = tmp_path / "m.json", tmp_path / "p.npz"
    assert main(["identify", "--data", str(log), "--out", str(model)]) == 0
    assert main(["predict", "--model", str(model), "--data", str(log), "--out", str(pred)]) == 0
    p, d = np.load(pred), np.load(log)
    offset = p["offset"][0]
    assert np.all(p["offset"] == offset) and np.any(np.abs(offset) > 1e-3)
    with_offset = np.abs(np.mean(p["tau"] - d["tau"], axis=0))
    without = np.abs(np.mean(p["tau"] - offset - d["tau"], axis=0))
    assert np.all(with_offset < without)
    # on simulated data (tau_clean present) the clean torque, no offset added
    clean = _generated(tmp_path, "clean.npz", 4)
    assert main(["predict", "--model", str(model), "--data", str(clean), "--out",
                 str(tmp_path / "q.npz")]) == 0
    np.testing.assert_allclose(np.load(tmp_path / "q.npz")["tau"], p["tau"] - offset)


def test_predict_takes_the_robot_the_data_record_and_refuses_another_robots_model(tmp_path, capsys,
                                                                                  arrays):
    """Without --robot, predict works on the robot the log records (a 6-joint UR5 log: not
    the 3-joint default arm); a model identified for the Lynxmotion is one error line on it
    naming the log's robot, exit 2, no file. Its error against the log's torque is Pinocchio's
    RNEA written out."""
    import pinocchio as pin

    model = Arm.of("ur5").pinocchio
    data = pin.Model.createData(model)
    rng = np.random.default_rng(3)
    q, qd, qdd = (rng.uniform(-1, 1, (40, 6)) for _ in range(3))
    rnea = np.array([pin.rnea(model, data, *s) for s in zip(q, qd, qdd, strict=True)])
    tau = rnea * (1 + 0.1 * rng.uniform(size=(40, 1)))
    log = tmp_path / "ur5.npz"
    np.savez(log, q=q, qd=qd, qdd=qdd, tau=tau, meta=json.dumps({"robot": "ur5"}))
    pred = tmp_path / "p.npz"
    assert main(["predict", "--model", "pinocchio", "--data", str(log), "--out", str(pred)]) == 0
    out = np.load(pred)
    np.testing.assert_allclose(out["tau"], rnea, atol=1e-9)
    expected = np.sqrt(((rnea - tau) ** 2).sum(axis=0) / (tau ** 2).sum(axis=0))
    np.testing.assert_allclose(out["rel_error"], expected, rtol=1e-12)
    lynx = _write(tmp_path, arrays, "lynx.npz")
    lynx_model = tmp_path / "m.json"
    assert main(["identify", "--data", str(lynx), "--out", str(lynx_model)]) == 0
    capsys.readouterr()
    bad = tmp_path / "bad.npz"
    assert main(["predict", "--model", str(lynx_model), "--data", str(log), "--out", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "records robot 'ur5'" in err and "'lynxmotion'" in err
    assert not bad.exists()


def test_data_or_a_model_of_another_robot_is_one_line_naming_it(tmp_path, capsys):
    """identify --robot panda on a UR5's data, and predict with a UR5's model on a Panda's
    data: exit 2, one line naming the robot the data record (not only a joint count that
    does not fit), no file."""
    ur5 = _generated(tmp_path, "ur5.npz", 1)
    panda, model = tmp_path / "panda.npz", tmp_path / "ur5.json"
    assert main(["generate", "--robot", "panda", "--samples", "300", "--out", str(panda)]) == 0
    assert main(["identify", "--data", str(ur5), "--out", str(model)]) == 0
    capsys.readouterr()
    out = tmp_path / "m.json"
    assert main(["identify", "--data", str(ur5), "--robot", "panda", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "records robot 'ur5'" in err[0] and "'panda'" in err[0], err
    assert not out.exists()
    pred = tmp_path / "p.npz"
    assert main(["predict", "--model", str(model), "--data", str(panda), "--out", str(pred)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "records robot 'panda'" in err[0] and "'ur5'" in err[0], err
    assert not pred.exists()


@pytest.mark.parametrize("flag", ["--rigid-body", "--no-rigid-body"])
def test_identify_says_whether_the_fit_was_held_to_the_rigid_body(tmp_path, arrays, flag):
    """--rigid-body: MODEL.json's metrics.rigid_body records the hold (the data, generated
    from the robot's own rigid body, bear it out); --no-rigid-body: the fit is left free and
    no such record is written. Both keep the model's keys."""
    data, out = _write(tmp_path, arrays), tmp_path / "MODEL.json"
    assert main(["identify", "--data", str(data), "--out", str(out), flag]) == 0
    payload = json.loads(out.read_text())
    held = payload["metrics"].get("rigid_body")
    if flag == "--rigid-body":
        assert held["held"] and 0 < held["directions"] < held["atoms"]
        assert held["pvalue"] >= 0.01
    else:
        assert held is None
    assert payload["method"] == "coupled" and len(payload["joints"]) == 3
