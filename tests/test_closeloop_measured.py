"""Closing the loop on given data (`closeloop --data`): a log with known joint effects.

The Lynxmotion's rigid body (Pinocchio RNEA) plus Gaz et al.'s sigmoid friction on joint 1,
viscous friction on joint 2, a cogging torque no candidate spans on joint 3 (sin 12 q3), a
sensor offset, and white torque noise: the loop must name the sigmoid (coefficient and
shape) and the viscous term, nothing else, and call joint 3 unexplained.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from harness.cli import main
from harness.closeloop.one_log import rigid_library
from harness.robots.arm import Arm
from identification.closeloop.selection.one_log import close_loop_measured
from identification.friction import sigmoid_friction
from tests.helpers import lynxmotion_motion

SIGMOID = (0.08, 15.0, 0.03)  # phi1 N m, phi2 s/rad, phi3 rad/s on joint 1
VISCOUS = 0.05  # N m s/rad on joint 2
COGGING = 0.02  # N m, sin(12 q3) on joint 3
LYNX = Arm.of("lynxmotion")


def _log(cogging: float = COGGING, seed: int = 0):
    m = lynxmotion_motion(2400, seed=seed)
    tau = LYNX.nominal.torque(m.q, m.qd, m.qdd)
    tau[:, 0] += SIGMOID[0] * sigmoid_friction(m.qd[:, 0], *SIGMOID[1:])
    tau[:, 1] += VISCOUS * m.qd[:, 1]
    tau[:, 2] += cogging * np.sin(12 * m.q[:, 2])
    rng = np.random.default_rng(seed)
    noisy = tau + 0.005 * rng.normal(size=tau.shape) + np.array([0.01, -0.02, 0.005])
    return m, noisy, tau


@pytest.fixture(scope="module")
def loop():
    m, tau, _ = _log()
    return close_loop_measured(rigid_library(LYNX), m.q, m.qd, m.qdd, tau)


def test_the_true_effects_are_named_with_their_coefficients(loop):
    named = {(t.effect, t.joint): t for t in loop.terms}
    assert set(named) == {("sigmoid", 1), ("viscous", 2)}, named
    sig = named["sigmoid", 1]
    assert sig.coefficient == pytest.approx(SIGMOID[0], rel=0.1)
    assert sig.steepness == pytest.approx(SIGMOID[1], rel=0.2)
    assert sig.shift == pytest.approx(SIGMOID[2], abs=0.01)
    assert named["viscous", 2].coefficient == pytest.approx(VISCOUS, rel=0.1)


def test_structure_outside_the_dictionary_is_unexplained(loop):
    assert loop.unexplained_joints == (3,)
    assert np.all(loop.error_after[:2] < 0.5 * loop.error_before[:2])


def test_a_log_with_only_dictionary_effects_is_fully_explained():
    m, tau, clean = _log(cogging=0.0, seed=1)
    r = close_loop_measured(rigid_library(LYNX), m.q, m.qd, m.qdd, tau)
    assert not r.unexplained
    # after: the held-out error against the measured torque is the noise's
    held = slice(r.split, None)
    noise_only = np.linalg.norm(tau[held] - clean[held] - r.model.declared.bias, axis=0)
    assert np.all(r.error_after <= 1.1 * noise_only / np.linalg.norm(tau[held], axis=0))


def test_cli_closeloop_data_writes_the_contract(tmp_path, capsys):
    m, tau, clean = _log()
    data = tmp_path / "d.npz"
    np.savez(data, t=m.t, q=m.q, qd=m.qd, qdd=m.qdd, tau=tau,
             meta=np.array(json.dumps({"robot": "lynxmotion"})))
    out = tmp_path / "cl"
    capsys.readouterr()
    assert main(["closeloop", "--data", str(data), "--out", str(out)]) == 0
    first = capsys.readouterr().out.splitlines()[0]  # which model the residual is against
    assert first.startswith("closeloop: declared model: the robot file's nominal model")
    payload = json.loads((out / "closeloop.json").read_text())
    for key in ("effects", "error_before", "error_after", "unexplained"):
        assert key in payload
    assert payload["unexplained"] is True and payload["unexplained_joints"] == [3]
    # against the declared (nominal) model, dry friction goes by the contract's one name
    assert {(e["effect"], e["joint"]) for e in payload["effects"]} == {("coulomb", 1), ("viscous", 2)}
    assert (out / "model.json").is_file() and "heldout" not in payload
    assert len(payload["error_before"]) == 3 and "error_before_clean" not in payload


@pytest.mark.parametrize("args, message", [
    (["--plant", "x.xml", "--data", "d.npz"], "exactly one of"),
    ([], "exactly one of"),
    (["--data", "missing.npz"], "not found"),
    (["--plant", "x.xml", "--validate", "d.npz"], "--validate applies to --data"),
    (["--data", "d.npz", "--robot", "panda"], "robot panda has 7"),
    (["--data", "d.npz", "--validate", "d.npz", "--declared", "identified"],
     "takes one --data log"),
])
def test_closeloop_data_errors_are_one_line(tmp_path, capsys, monkeypatch, args, message):
    monkeypatch.chdir(tmp_path)
    m, tau, _ = _log()
    np.savez(tmp_path / "d.npz", t=m.t, q=m.q, qd=m.qd, qdd=m.qdd, tau=tau)
    assert main(["closeloop", *args, "--out", "cl"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "cl" / "closeloop.json").exists()


def test_a_mujoco_friction_plant_log_names_its_true_effects():
    """Measured data simulated by MuJoCo on the Lynxmotion friction plant (damping 0.01 and
    0.02 N m s/rad on joints 1 and 3, frictionloss 0.05 N m on joint 2, read from its MJCF
    here only to score): the loop on the data alone names exactly those, within 5 %."""
    from harness.closeloop.plants import true_effects
    from harness.data.generate import generate
    from models import MODELS

    plant = Arm.of(MODELS / "lynxmotion" / "lynxmotion_friction.xml")
    d = generate(plant, 4000, 0.05, 0, "measured", 0.0)
    r = close_loop_measured(rigid_library(LYNX), d.q, d.qd, d.qdd, d.tau)
    truth = {(t.effect, t.joint): t.coefficient
             for t in true_effects(plant.mujoco, LYNX.mujoco)[0]}
    named = {(t.effect, t.joint): t.coefficient for t in r.terms}
    assert set(named) == set(truth) == {("viscous", 1), ("coulomb", 2), ("viscous", 3)}
    for key, value in truth.items():
        assert named[key] == pytest.approx(value, rel=0.05), key
    assert not r.unexplained


def test_the_extended_model_symbolic_form_equals_its_torque(loop):
    """The planner's CasADi form of the closed-loop model (sigmoid friction included)."""
    import casadi as ca

    rng = np.random.default_rng(3)
    states = [rng.normal(size=(5, 3)) for _ in range(3)]
    sym = [ca.SX.sym(n, 3) for n in ("q", "qd", "qdd")]
    f = ca.Function("tau", sym, [loop.model.symbolic_torque(*sym)])
    symbolic = np.array([np.asarray(f(*(s[i] for s in states))).ravel() for i in range(5)])
    np.testing.assert_allclose(symbolic, loop.model.torque(*states), atol=1e-10)


# --- several runs against the declared model (closeloop --data A,B --validate C) ---------

REST = 60  # samples at rest before a run's motion (a real log's start)


def _run_file(path, seed: int, viscous: float = VISCOUS, samples: int = 1200, robot="lynxmotion",
              offset=(0.01, 0.0, 0.0), rest: int = REST):
    """A run of the Lynxmotion with viscous friction on joint 2, white noise and a sensor
    offset of its own, its first `rest` samples held at the motion's start."""
    m = lynxmotion_motion(samples, seed=seed)
    still = np.zeros((rest, 3))
    q, qd, qdd = (np.concatenate([np.repeat(m.q[:1], rest, axis=0), m.q]),
                  np.concatenate([still, m.qd]), np.concatenate([still, m.qdd]))
    tau = LYNX.nominal.torque(q, qd, qdd)
    tau[:, 1] += viscous * qd[:, 1]
    tau += 0.005 * np.random.default_rng(seed).normal(size=tau.shape) + np.asarray(offset)
    t = np.arange(len(q)) * (m.t[1] - m.t[0])
    np.savez(path, t=t, q=q, qd=qd, qdd=qdd, tau=tau, meta=np.array(json.dumps({"robot": robot})))
    return m, tau


def test_runs_and_validate_write_heldout_and_a_model_predict_reads(tmp_path, capsys):
    """The held-out run is scored with the training runs' offset (the closed model's mean
    residual on their samples), never refitted on the samples scored nor read from its rest;
    `predict` with the written model reproduces the scores, `--offset-from-rest` reads the
    rest."""
    files = [tmp_path / f"r{i}.npz" for i in range(3)]
    for i, f in enumerate(files):
        _run_file(f, seed=10 + i, offset=(0.01, -0.02 * i, 0.03 * i))
    out = tmp_path / "cl"
    assert main(["closeloop", "--data", f"{files[0]},{files[1]}", "--validate", str(files[2]),
                 "--out", str(out)]) == 0
    payload = json.loads((out / "closeloop.json").read_text())
    assert payload["heldout"]["files"] == [str(files[2])]
    assert payload["heldout"]["after"] == payload["error_after"]
    held = payload["heldout_runs"][0]
    assert held["offset_samples"] == 2 * (REST + 1200) and held["scored_samples"] == REST + 1200
    assert held["offset_rule"] == "training runs" and "training runs" in held["offset_from"]
    named = {(e["effect"], e["joint"]): e for e in payload["effects"]}
    assert set(named) == {("viscous", 2)}, named
    assert named["viscous", 2]["unit"] == "N m s/rad" and len(named["viscous", 2]["per_run"]) == 2
    assert named["viscous", 2]["coefficient"] == pytest.approx(VISCOUS, rel=0.05)
    assert all(a <= b for a, b in zip(payload["error_after"], payload["error_before"],
                                      strict=True))
    np.testing.assert_allclose(payload["heldout_sensor_offsets"][0], [0.01, -0.01, 0.015],
                               atol=0.003)  # the training runs' mean, not the run's own
    assert main(["predict", "--model", str(out / "model.json"), "--data", str(files[2]),
                 "--out", str(tmp_path / "p.npz")]) == 0
    predicted = np.load(tmp_path / "p.npz")
    np.testing.assert_allclose(predicted["offset"][0], payload["heldout_sensor_offsets"][0],
                               atol=1e-12)
    np.testing.assert_allclose(predicted["rel_error"], payload["heldout"]["after"], rtol=1e-9)
    assert main(["predict", "--model", str(out / "model.json"), "--data", str(files[2]),
                 "--offset-from-rest", "--out", str(tmp_path / "rest.npz")]) == 0
    rest = np.load(tmp_path / "rest.npz")
    assert int(rest["rest_samples"]) == REST
    np.testing.assert_allclose(rest["offset"][0], [0.01, -0.04, 0.06], atol=0.003)
    model = json.loads((out / "model.json").read_text())
    assert model["offsets"] == [0.0] * 3 and len(model["sensor_offsets"]["heldout"]) == 1
    assert model["sensor_offsets"]["new_run"] == payload["heldout_sensor_offsets"][0]


def test_a_run_scored_whole_without_a_rest_takes_the_training_runs_offset(tmp_path):
    """No offset is fitted on the samples scored: a held-out run without a rest before its
    motion is scored with the training runs' offset, and a --holdout tail takes its run's
    offset from the run's trained part."""
    from harness.closeloop.runs import read_runs, run_runs

    files = [tmp_path / f"r{i}.npz" for i in range(3)]
    for i, f in enumerate(files):
        _run_file(f, seed=20 + i, offset=(0.05, 0.0, 0.0), rest=0)
    train, validate = read_runs(f"{files[0]},{files[1]}", str(files[2]))
    whole = run_runs(train, LYNX, validate=validate)
    assert [r.to_json()["offset_rule"] for r in whole.scored] == ["training runs"]
    np.testing.assert_allclose(whole.heldout_offsets[:, 0], 0.05, atol=0.005)
    tails = run_runs(train, LYNX, holdout=0.25)
    assert all("trained samples" in r.source for r in tails.scored)
    np.testing.assert_allclose(tails.heldout_offsets[:, 0], 0.05, atol=0.005)


def test_first_rest_counts_the_still_samples_before_the_motion():
    from identification.closeloop.closed.offsets import MIN_REST, REST_SPEED, first_rest

    qd = np.zeros((50, 2))
    qd[30:, 1] = 2 * REST_SPEED
    assert first_rest(qd) == 30
    qd[MIN_REST - 1:, 0] = 2 * REST_SPEED
    assert first_rest(qd) == 0  # too short a stillness to calibrate on
    assert first_rest(np.zeros((MIN_REST, 2))) == MIN_REST


def test_an_effect_of_one_run_only_is_not_named_with_two():
    from identification.closeloop.selection.runs import close_loop_runs

    declared = LYNX.nominal
    runs = []
    for seed, viscous in ((20, 0.05), (21, 0.0)):
        m = lynxmotion_motion(1200, seed=seed)
        tau = declared.torque(m.q, m.qd, m.qdd)
        tau[:, 1] += viscous * m.qd[:, 1]
        runs.append((m.q, m.qd, m.qdd, tau + 0.005 * np.random.default_rng(seed).normal(
            size=tau.shape)))
    assert ("viscous", 2) in {(t.effect, t.joint) for t in close_loop_runs(declared,
                                                                           runs[:1]).terms}
    assert close_loop_runs(declared, runs).terms == ()


def test_a_mujoco_friction_plant_at_two_seeds_names_its_effects_on_both():
    """The Lynxmotion friction plant (damping on joints 1 and 3, frictionloss on joint 2)
    generated at two seeds: each run alone and both together name exactly those, within 10 %."""
    from harness.closeloop.plants import true_effects
    from harness.data.generate import generate
    from identification.closeloop.selection.runs import close_loop_runs
    from models import MODELS

    plant = Arm.of(MODELS / "lynxmotion" / "lynxmotion_friction.xml")
    runs = [generate(plant, 3000, 0.05, seed, "measured", 0.0) for seed in (0, 1)]
    runs = [(d.q, d.qd, d.qdd, d.tau) for d in runs]
    truth = {(t.effect, t.joint): t.coefficient
             for t in true_effects(plant.mujoco, LYNX.mujoco)[0]}
    declared = LYNX.nominal
    for subset in (runs[:1], runs[1:], runs):
        named = {(t.effect, t.joint): t.coefficient
                 for t in close_loop_runs(declared, subset).terms}
        assert set(named) == set(truth), named
        for key, value in truth.items():
            assert named[key] == pytest.approx(value, rel=0.1), key


def _generated(tmp_path, plant: str, seeds=(1, 2)) -> list[str]:
    """Two runs of plant at the default sensor bias and a noise-free one (last)."""
    from harness.data.generate import generate

    files = []
    for seed, noise in ((seeds[0], 0.05), (seeds[1], 0.05), (9, 0.0)):
        files.append(str(tmp_path / f"{Path(plant).stem}{seed}.npz"))
        mode = "measured" if plant.endswith(".xml") else "inverse"
        np.savez(files[-1], **generate(Arm.of(plant), 1000, noise, seed, mode, 0.2).arrays())
    return files


def test_training_runs_sensor_offsets_are_not_carried_into_a_new_run(tmp_path):
    """Runs of the declared robot itself, each with its own sensor offset: nothing is named,
    and the new run's error is not made worse by the training runs' offsets."""
    from harness.closeloop.runs import read_runs, run_runs

    files = _generated(tmp_path, "lynxmotion")
    train, held = read_runs(",".join(files[:2]), files[2])
    r = run_runs(train, LYNX, validate=held)
    assert r.loop.terms == () and not r.left.unexplained_joints
    assert np.all(r.error_after <= r.error_before + 1e-6), (r.error_before, r.error_after)
    assert r.model_json["offsets"] == [0.0] * 3
    np.testing.assert_allclose(r.model_json["sensor_offsets"]["training"], r.loop.run_offsets)
    assert len(r.loop.run_offsets) == 2


def test_a_friction_plant_with_sensor_offsets_still_names_its_effects(tmp_path):
    from harness.closeloop.runs import read_runs, run_runs
    from models import MODELS

    files = _generated(tmp_path, str(MODELS / "lynxmotion" / "lynxmotion_friction.xml"))
    train, held = read_runs(",".join(files[:2]), files[2])
    r = run_runs(train, LYNX, validate=held)
    named = {(t.effect, t.joint) for t in r.loop.terms}
    assert {("viscous", 1), ("coulomb", 2), ("viscous", 3)} <= named, named
    assert np.all(r.error_after < 0.5 * r.error_before), (r.error_before, r.error_after)


@pytest.mark.parametrize("args, message", [
    (["--data", "a.npz,missing.npz"], "not found"),
    (["--data", "a.npz,b.npz"], "b.npz records robot 'panda'"),
    (["--data", "a.npz", "--validate", "b.npz"], "b.npz records robot 'panda'"),
    (["--data", "a.npz", "--declared", "other.json"], "identified for robot"),
    (["--data", "a.npz,a.npz", "--declared", "identified"], "takes one --data log"),
])
def test_closeloop_runs_errors_are_one_line(tmp_path, capsys, monkeypatch, args, message):
    monkeypatch.chdir(tmp_path)
    _run_file(tmp_path / "a.npz", 1, samples=200)
    _run_file(tmp_path / "b.npz", 2, samples=200, robot="panda")
    (tmp_path / "other.json").write_text(json.dumps(
        {"kind": "closeloop", "dof": 3, "robot": {"name": "panda", "hash": "x"},
         "declared": "pinocchio", "inertial": None, "offsets": [0, 0, 0], "effects": []}))
    assert main(["closeloop", *args, "--out", "cl"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "cl" / "closeloop.json").exists()


@pytest.mark.parametrize("declared", ["pinocchio", "identified"])
def test_data_of_another_robot_is_refused_in_one_line(tmp_path, capsys, declared):
    """UR5 data closed on the Panda: the data's record (robot and kinematics) refuses it
    before anything runs, whatever the declared model."""
    from harness.data.generate import generate

    data = tmp_path / "ur5.npz"
    np.savez(data, **generate(Arm.of("ur5"), 200, 0.05, 0, "inverse", 0.0).arrays())
    out = tmp_path / "cl"
    assert main(["closeloop", "--data", str(data), "--robot", "panda", "--declared", declared,
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "records robot 'ur5'" in err[0] and "not 'panda'" in err[0], err
    assert not (out / "closeloop.json").exists()


# --- a scored run's offset comes from samples the score does not count ---------------------

STEP = 0.05  # N m on joint 1: the sensor's offset jumps by this once the motion starts


def _stepped(seed: int, rest: int, step_at: int, samples: int = 800):
    """A run of the declared Lynxmotion (its RNEA, 0.005 N m noise) with `rest` samples held
    still before the motion, offset 0.01 N m on joint 1 until sample step_at, STEP more from
    there: (q, qd, qdd, tau), its times."""
    m = lynxmotion_motion(samples, seed=seed)
    still = np.zeros((rest, 3))
    q, qd, qdd = (np.concatenate([np.repeat(m.q[:1], rest, axis=0), m.q]),
                  np.concatenate([still, m.qd]), np.concatenate([still, m.qdd]))
    tau = LYNX.nominal.torque(q, qd, qdd) + 0.005 * np.random.default_rng(seed).normal(
        size=q.shape)
    tau[:, 0] += 0.01
    tau[step_at:, 0] += STEP
    return (q, qd, qdd, tau), np.arange(len(q)) * (m.t[1] - m.t[0])


def _step_floor(tau_scored: np.ndarray) -> float:
    """The relative error on joint 1 a step of STEP leaves on these samples, less a margin
    (the noise adds to it, the model's error too): what a score that does not absorb it
    shows at least."""
    return 0.9 * STEP / np.sqrt(np.mean(tau_scored[:, 0] ** 2))


@pytest.mark.parametrize("held", ["validate", "holdout"])
def test_a_step_in_a_scored_run_s_offset_shows_in_its_error(held):
    """The loop's score on runs of the declared robot whose sensor offset jumps once the
    scored part begins: --validate, a run with a rest (offset 0.01 N m) whose motion reads
    STEP more; --holdout, a run without rest whose last quarter reads STEP more. The offset
    comes from the rest or the trained part, which do not know the step: the error on joint 1
    shows it (an offset fitted on the scored samples would absorb it: noise only)."""
    from identification.closeloop.pipeline import close_the_loop

    if held == "validate":
        train, times = _stepped(30, 0, 10**6)  # no step
        run, run_times = _stepped(31, REST, REST)
        out = close_the_loop(LYNX.nominal, [train], [times], [run], [run_times], detect=False)
        scored = run[3][REST:]
    else:
        run, run_times = _stepped(31, 0, 600)
        out = close_the_loop(LYNX.nominal, [run], [run_times], holdout=0.25, detect=False)
        scored = run[3][600:]
    assert out.error_after[0] >= _step_floor(scored), (out.error_after, _step_floor(scored))
    assert out.heldout_offsets[0, 0] == pytest.approx(0.01, abs=0.004)


def test_predict_offset_from_rest_shows_a_step_after_the_rest(tmp_path):
    """`predict --offset-from-rest` with the robot's own model on a log whose offset jumps by
    STEP once the motion starts: the offset is the rest's (0.01 N m), the error on joint 1
    shows the step."""
    (q, qd, qdd, tau), t = _stepped(32, REST, REST)
    data = tmp_path / "log.npz"
    np.savez(data, t=t, q=q, qd=qd, qdd=qdd, tau=tau,
             meta=np.array(json.dumps({"robot": "lynxmotion"})))
    assert main(["predict", "--model", "pinocchio", "--data", str(data), "--offset-from-rest",
                 "--out", str(tmp_path / "p.npz")]) == 0
    predicted = np.load(tmp_path / "p.npz")
    assert predicted["offset"][0, 0] == pytest.approx(0.01, abs=0.004)
    assert predicted["rel_error"][0] >= _step_floor(tau[REST:])


def test_identify_s_held_out_score_shows_a_step_in_the_held_out_offset():
    """identify on a measured log (no clean torque) whose sensor offset jumps by STEP at the
    held-out part's start: the held-out score uses the offset fitted on the training part,
    and shows the step on joint 1."""
    from identification.identify import identify
    from identification.library.prior_knowledge import prior_knowledge_library

    (q, qd, qdd, tau), _ = _stepped(33, 0, 1500, samples=2000)
    result = identify(q, qd, qdd, tau, prior_knowledge_library(3), holdout=0.25)
    assert result.heldout_rel_rmse[0] >= _step_floor(tau[1500:])
