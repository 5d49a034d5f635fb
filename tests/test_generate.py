"""`torquebench generate`: data from MuJoCo, cross-checked against Pinocchio."""

import contextlib
import io
import json
import subprocess
import sys

import numpy as np
import pytest

from harness.cli import main
from harness.data.generate import generate
from harness.robots.arm import Arm
from identification.excitation.fourier import random_excitation


def run_process(*args):
    """The command as a user runs it: `python -m harness`, in a process of its own."""
    return subprocess.run([sys.executable, "-m", "harness", *args], capture_output=True,
                          text=True)


def run_cli(*args):
    """The command in this process (harness.cli.main, as the entry point calls it): its exit
    status and what it printed, without paying a new interpreter's imports."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(args))
    return subprocess.CompletedProcess(args, code, out.getvalue(), err.getvalue())


def test_excitation_derivatives_match_finite_differences():
    exc = random_excitation(np.array([-1.0, 0.0]), np.array([1.0, 3.0]), np.random.default_rng(3))
    t, h = np.linspace(0, 20, 50), 1e-5
    q, qd, qdd = exc.evaluate(t)
    qp, qdp, _ = exc.evaluate(t + h)
    qm, qdm, _ = exc.evaluate(t - h)
    np.testing.assert_allclose(qd, (qp - qm) / (2 * h), atol=1e-7)
    np.testing.assert_allclose(qdd, (qdp - qdm) / (2 * h), atol=1e-6)
    q_period, _, _ = exc.evaluate(np.linspace(0, exc.period, 2001))
    np.testing.assert_allclose(q_period.min(axis=0), [-0.9, 0.15], atol=1e-3)
    np.testing.assert_allclose(q_period.max(axis=0), [0.9, 2.85], atol=1e-3)


def test_inverse_mode_torques_are_pinocchio_rnea_and_noise_is_as_declared():
    ds = generate(Arm.of("lynxmotion"), samples=4000, noise=0.05, seed=0, mode="inverse", bias=0.2)
    baseline = Arm.of("lynxmotion").nominal
    np.testing.assert_allclose(ds.tau_clean, baseline.torque(ds.q, ds.qd, ds.qdd), atol=1e-9)
    noise = ds.tau - ds.tau_clean
    sigma = 0.05 * ds.tau_clean.std(axis=0)
    np.testing.assert_allclose(noise.std(axis=0), sigma, rtol=0.05)
    assert np.all(np.abs(noise.mean(axis=0) - 0.2 * sigma) < 4 * sigma / np.sqrt(4000))
    lo, hi = np.array([-np.pi / 2, 0, -np.pi]), np.array([np.pi / 2, np.pi, 0])
    assert np.all(ds.q > lo) and np.all(ds.q < hi)
    # the default dataset makes the paper's 75-feature library full rank
    assert ds.meta["library_rank"] == ds.meta["library_size"] == 75
    assert np.isfinite(ds.meta["library_condition"])


def test_measured_mode_estimates_states_well_enough_for_torque():
    ds = generate(Arm.of("lynxmotion"), samples=2000, noise=0.05, seed=1, mode="measured")
    assert set(ds.truth) == {"q", "qd", "qdd"}
    # independent recomputation of the acceptance figure from the returned arrays
    baseline = Arm.of("lynxmotion").nominal
    tau_est = baseline.torque(ds.q, ds.qd, ds.qdd)
    tau_true = baseline.torque(ds.truth["q"], ds.truth["qd"], ds.truth["qdd"])
    err = np.linalg.norm(tau_est - tau_true, axis=0) / np.linalg.norm(tau_true, axis=0)
    np.testing.assert_allclose(err, ds.meta["tau_from_states_rel_rmse"], rtol=1e-9)
    assert np.all(err <= 0.02)
    # what the motor applied is what the rigid body needs at the true states
    np.testing.assert_allclose(ds.tau_clean, tau_true, atol=1e-6 * np.abs(tau_true).max())
    assert 0 < max(ds.meta["qdd_rel_rmse"]) < 0.05  # estimated, not copied from the simulator


def test_generate_cli_writes_the_contract(tmp_path):
    out = tmp_path / "d.npz"
    res = run_process("generate", "--samples", "300", "--noise", "0.01", "--seed", "4", "--out", str(out))
    assert res.returncode == 0, res.stderr
    with np.load(out) as npz:
        assert {"t", "q", "qd", "qdd", "tau", "tau_clean", "meta"} <= set(npz.files)
        meta = json.loads(str(npz["meta"]))
        assert npz["tau"].shape == (300, 3)
    assert meta["plant"] == "lynxmotion" and meta["mode"] == "inverse" and meta["dof"] == 3
    assert meta["robot_hash"] == Arm.of("lynxmotion").record["hash"]
    assert meta["noise"] == 0.01 and meta["seed"] == 4 and "library_condition" in meta
    assert "condition" in res.stdout


@pytest.mark.parametrize("args, message", [
    (["--plant", "missing.xml"], "robot file not found: missing.xml"),
    (["--plant", "no_such_robot"], "unknown robot"),
    (["--plant", "BAD"], "invalid MJCF"),
    (["--noise", "-0.1"], "--noise"),
    (["--samples", "9"], "at least 10"),
])
def test_generate_bad_input_is_one_line_and_no_file(tmp_path, args, message):
    bad = tmp_path / "bad.xml"
    bad.write_text("<mujoco><worldbody><body></mujoco>")
    args = [str(bad) if a == "BAD" else a for a in args]
    out = tmp_path / "out.npz"
    res = run_cli("generate", *args, "--out", str(out))
    assert res.returncode == 2
    assert message in res.stderr and len(res.stderr.strip().splitlines()) == 1
    assert not out.exists() and list(tmp_path.iterdir()) == [bad]


def test_predict_pinocchio_reproduces_clean_torque(tmp_path):
    data, pred = tmp_path / "d.npz", tmp_path / "p.npz"
    assert run_cli("generate", "--samples", "200", "--out", str(data)).returncode == 0
    res = run_cli("predict", "--model", "pinocchio", "--data", str(data), "--out", str(pred))
    assert res.returncode == 0, res.stderr
    with np.load(data) as d, np.load(pred) as p:
        np.testing.assert_allclose(p["tau"], d["tau_clean"], atol=1e-12)


def test_predict_rejects_nan_states(tmp_path):
    data, pred = tmp_path / "d.npz", tmp_path / "p.npz"
    q = np.zeros((20, 3))
    q[3, 1] = np.nan
    np.savez(data, q=q, qd=np.zeros((20, 3)), qdd=np.zeros((20, 3)))
    res = run_cli("predict", "--model", "pinocchio", "--data", str(data), "--out", str(pred))
    assert res.returncode == 2 and "NaN" in res.stderr and not pred.exists()


def test_output_path_errors_are_one_line(tmp_path):
    a_file = tmp_path / "afile"
    a_file.write_text("")
    (tmp_path / "adir").mkdir()
    for args, message in [
        (["generate", "--samples", "20", "--out", str(tmp_path / "adir")], "is a directory"),
        (["generate", "--samples", "20", "--out", str(a_file / "x.npz")], "a file of that name"),
        (["closeloop", "--plant", "lynxmotion", "--out", str(a_file)], "existing file"),
    ]:
        res = run_cli(*args)
        assert res.returncode == 2, res.stderr
        assert message in res.stderr and len(res.stderr.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir", "afile"]
    assert list((tmp_path / "adir").iterdir()) == []


def test_library_condition_is_reported_for_other_robots():
    ds = generate(Arm.of("double_pendulum"), samples=4000, noise=0.0, seed=0)
    assert ds.meta["library"].startswith("kinematic-")  # base atoms of its kinematics
    assert np.isfinite(ds.meta["library_condition"])
    assert ds.meta["library_rank"] == ds.meta["library_size"]


def test_malformed_data_names_the_bad_array(tmp_path):
    data = tmp_path / "d.npz"
    np.savez(data, q=np.zeros((5, 2)), qd=np.zeros((5, 3)), qdd=np.zeros((5, 3)))
    res = run_cli("predict", "--model", "pinocchio", "--data", str(data), "--out", str(tmp_path / "p.npz"))
    assert res.returncode == 2 and "q (5, 2), qd (5, 3)" in res.stderr
    text = tmp_path / "t.npz"
    text.write_text("hello")
    res = run_cli("predict", "--model", "pinocchio", "--data", str(text), "--out", str(tmp_path / "p.npz"))
    assert res.returncode == 2 and "not an .npz archive" in res.stderr


def test_a_robot_file_that_is_not_xml_is_one_line_naming_it(tmp_path, capsys):
    """--robot given a file that is no robot description (a MODEL.json, a log) is refused
    before any engine reads it: one line naming the file and what --robot takes, exit 2,
    nothing written."""
    from harness.cli import main

    model = tmp_path / "MODEL.json"
    model.write_text("{}")
    out = tmp_path / "d.npz"
    assert main(["generate", "--robot", str(model), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is not XML (a .json file)" in err[0] and "MJCF" in err[0], err
    assert "model_" not in err[0] and not out.exists()
