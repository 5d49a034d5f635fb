"""A payload on the last body in the measured loop (`closeloop --data`, issue #54).

Fast: the last body's regressor against Pinocchio's, the consistent fit (exact on clean data,
its centre of mass held within reach, its pseudo-inertia PSD), the model.json round trip.
Slow: simulated UR5 and Panda plants carrying a 2.7 kg load off the flange, generated in
inverse mode at 5 % torque noise: the payload named within 3 % of its mass and 1 cm of its
centre of mass, none on the plant without it, predict reproducing the reported errors.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from harness.robots.arm import Arm
from harness.robots.bodies import last_body
from identification.closeloop.candidates.payload import (
    consistent_fit,
    describe,
    standard,
)
from identification.physical import min_pseudo_eigenvalues

LOAD = dict(payload=2.7, payload_offset=(0.03, -0.02, 0.08),
            payload_inertia=(0.01, 0.012, 0.008))


def _states(dof: int, n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    return tuple(rng.uniform(-s, s, (n, dof)) for s in (2.0, 1.5, 4.0))


def test_the_last_body_regressor_is_pinocchios():
    arm = Arm.of("ur5")
    body = last_body(arm)
    model, q, qd, qdd = arm.pinocchio, *_states(arm.dof, 5)
    data = model.createData()
    ours = body(q, qd, qdd)
    for k in range(len(q)):
        theirs = pin.computeJointTorqueRegressor(model, data, q[k], qd[k], qdd[k])[:, -10:]
        assert np.allclose(ours[k], theirs, atol=1e-10)
    assert body.name == "wrist_3_link"


def test_describe_and_standard_are_inverse():
    p = standard(2.7, [0.03, 0.16, 0.02], [0.01, 0.001, 0.012, -0.002, 0.0005, 0.008])
    m, c, inertia = describe(p)
    assert m == pytest.approx(2.7) and np.allclose(c, [0.03, 0.16, 0.02])
    assert np.allclose(inertia, [0.01, 0.001, 0.012, -0.002, 0.0005, 0.008])


def _problem(params, reach=0.4, n=400, noise=0.0):
    arm = Arm.of("ur5")
    states = _states(arm.dof, n)
    y = last_body(arm)(*states)
    offsets = np.array([0.3, -0.2, 0.1, 0.0, 0.05, -0.01])
    rng = np.random.default_rng(1)
    tau = y @ params + offsets + noise * rng.standard_normal((n, arm.dof))
    base = np.broadcast_to(np.eye(arm.dof), (n, arm.dof, arm.dof))
    return consistent_fit(base, tau, np.zeros((n, arm.dof, 0)), y, np.ones(arm.dof), reach)


def test_the_consistent_fit_recovers_a_payload_and_its_offsets():
    truth = standard(2.7, [0.03, 0.16, 0.02], [0.01, 0.0, 0.012, 0.0, 0.0, 0.008])
    offsets, _, params = _problem(truth)
    assert np.allclose(offsets, [0.3, -0.2, 0.1, 0.0, 0.05, -0.01], atol=1e-4)
    m, c, _ = describe(params)
    assert m == pytest.approx(2.7, rel=1e-4) and np.allclose(c, [0.03, 0.16, 0.02], atol=1e-4)


def test_the_fit_stays_consistent_and_within_reach():
    """A torque that reads as a mass 0.6 m out, or as a negative inertia, is fitted within the
    bounds: |c| <= reach and the pseudo-inertia positive semidefinite."""
    far = standard(1.0, [0.6, 0.0, 0.0], [0.0] * 6)
    _, _, params = _problem(far, reach=0.4)
    m, c, _ = describe(params)
    assert np.linalg.norm(c) <= 0.4 + 1e-4
    bad = np.array([1.0, 0.0, 0.0, 0.0, -0.05, 0.0, 0.02, 0.0, 0.0, 0.02])  # Ixx < 0
    _, _, params = _problem(bad, noise=0.01)
    assert min_pseudo_eigenvalues(params)[0] >= -1e-7


def test_a_payload_entry_of_model_json_reads_back():
    from harness.robots.closed_model import _term
    from identification.closeloop.candidates.effects import EffectTerm

    params = standard(2.7, [0.03, 0.16, 0.02], [0.01, 0.001, 0.012, -0.002, 0.0005, 0.008])
    term = EffectTerm("payload", 6, 2.7, params=tuple(params), body="wrist_3_link")
    entry = json.loads(json.dumps(term.to_json()))
    assert entry["mass"] == pytest.approx(2.7) and entry["body"] == "wrist_3_link"
    back = _term(entry)
    assert np.allclose(back.params, params, atol=1e-14) and back.body == "wrist_3_link"


# --- simulated plants, slow --------------------------------------------------------------

def _plants(robot: str, directory):
    from harness.closeloop.arm_plants import LoadedVariant, write_arm_variant

    arm = Arm.of(robot)
    loaded = write_arm_variant(arm, LoadedVariant(**LOAD, name="loaded"), directory)
    control = write_arm_variant(arm, LoadedVariant(name="control"), directory)
    return arm, loaded, control


def _truth(arm: Arm, plant) -> tuple[float, np.ndarray]:
    """The load as the plant carries it: its last joint's inertia minus the arm's."""
    extra = (Arm.of(str(plant)).pinocchio.inertias[-1].toDynamicParameters()
             - arm.pinocchio.inertias[-1].toDynamicParameters())
    m, c, _ = describe(extra)
    return m, c


def _generate(plant, seed: int, out) -> str:
    from harness.cli import main

    assert main(["generate", "--plant", str(plant), "--samples", "3000", "--noise", "0.05",
                 "--seed", str(seed), "--mode", "inverse", "--bias", "0", "--out",
                 str(out)]) == 0
    return str(out)


def _closeloop(robot, files, out) -> dict:
    from harness.cli import main

    assert main(["closeloop", "--data", ",".join(files), "--robot", robot, "--out",
                 str(out)]) == 0
    return json.loads((out / "closeloop.json").read_text())


def _predict_reproduces(tmp_path, data: str, result: dict) -> None:
    """predict on the loop's model.json gives the held-out errors the loop reports."""
    from harness.cli import main
    from identification.metrics import rel_error

    pred = tmp_path / "pred.npz"
    assert main(["predict", "--model", str(tmp_path / "cl" / "model.json"), "--data", data,
                 "--out", str(pred)]) == 0
    tau, measured = np.load(pred)["tau"], np.load(data)["tau"]
    held = slice(int(round(len(tau) * 0.75)), None)
    assert np.allclose(rel_error(tau[held], measured[held]), result["error_after"], atol=1e-3)


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["ur5", "panda"])
def test_a_loaded_plant_names_its_payload_and_predict_reproduces_it(tmp_path, robot):

    arm, loaded, control = _plants(robot, tmp_path)
    mass, com = _truth(arm, loaded)
    assert mass == pytest.approx(2.7)
    data = _generate(loaded, 1, tmp_path / "loaded.npz")
    result = _closeloop(robot, [data], tmp_path / "cl")
    (payload,) = [e for e in result["effects"] if e["effect"] == "payload"]
    assert payload["mass"] == pytest.approx(mass, rel=0.03)
    assert np.linalg.norm(np.array(payload["com"]) - com) < 0.01
    assert payload["coefficient"] == payload["mass"] and payload["joint"] == arm.dof
    assert np.all(np.array(result["error_after"]) < np.array(result["error_before"]))
    _predict_reproduces(tmp_path, data, result)
    clean = _generate(control, 1, tmp_path / "control.npz")
    control_result = _closeloop(robot, [clean], tmp_path / "cl_control")
    assert not [e for e in control_result["effects"] if e["effect"] in ("payload", "inertial")]


@pytest.mark.slow
def test_two_loaded_runs_report_the_mass_of_each(tmp_path, capsys):
    arm, loaded, _ = _plants("ur5", tmp_path)
    mass, com = _truth(arm, loaded)
    files = [_generate(loaded, s, tmp_path / f"loaded{s}.npz") for s in (1, 2)]
    result = _closeloop("ur5", files, tmp_path / "cl")
    (payload,) = [e for e in result["effects"] if e["effect"] == "payload"]
    assert len(payload["per_run_mass"]) == 2
    assert np.allclose(payload["per_run_mass"], mass, rtol=0.03)
    assert np.all(np.linalg.norm(np.array(payload["per_run_com"]) - com, axis=1) < 0.01)
    assert "com_agrees" in payload and "mass per run" in capsys.readouterr().out


def _so101():
    """example-robot-data's SO-101: five arm joints and a revolute gripper jaw, the last."""
    from harness.robots.registry import erd_robots_dir

    return Arm.of(str(erd_robots_dir() / "so_arm_description" / "urdf" / "so101.urdf"))


def test_a_payload_rides_on_the_body_the_jaw_turns_on_or_the_link_named():
    """On an arm whose last joint is a gripper's jaw the payload's body is the one before
    (what the gripper holds), its regressor Pinocchio's columns of that joint; a link named
    is taken whatever the last joint is (a fixed one on its joint's body), and a link the arm
    lacks is one error naming the arm's links."""
    from harness.errors import UserError

    arm = _so101()
    body = last_body(arm)
    assert body.name == "gripper_link" and body.joint == arm.dof - 1
    model, q, qd, qdd = arm.pinocchio, *_states(arm.dof, 4, seed=2)
    data = model.createData()
    ours = body(q, qd, qdd)
    columns = slice(10 * (arm.dof - 2), 10 * (arm.dof - 1))
    for k in range(len(q)):
        theirs = pin.computeJointTorqueRegressor(model, data, q[k], qd[k], qdd[k])[:, columns]
        assert np.allclose(ours[k], theirs, atol=1e-10)
    assert last_body(arm, "gripper_frame_link").joint == arm.dof - 1
    assert last_body(arm, "moving_jaw_so101_v1_link").joint == 0  # the last joint's
    ur5 = Arm.of("ur5")
    assert last_body(ur5, "forearm_link").joint == 3
    with pytest.raises(UserError, match="wrist_3_link"):
        last_body(ur5, "no_such_link")


@pytest.mark.slow
def test_a_part_held_by_a_jaw_gripper_is_named_on_the_gripper(tmp_path):
    """A 0.15 kg part fixed to the SO-101's gripper body (its jaw, the last joint, free): the
    loop names it there, within 3 % of its mass and 5 mm of its centre of mass, and predict on
    the loop's model.json (the payload's body read back) reproduces the error it reports."""
    from harness.cli import main

    arm = _so101()
    part = ('<link name="held_part"><inertial><origin xyz="0 0 0"/><mass value="0.15"/>'
            '<inertia ixx="2e-5" ixy="0" ixz="0" iyy="2e-5" iyz="0" izz="2e-5"/></inertial>'
            '</link><joint name="held_part_joint" type="fixed"><parent link="gripper_link"/>'
            '<child link="held_part"/><origin xyz="0.01 0 -0.09"/></joint></robot>')
    loaded = tmp_path / "so101_loaded.urdf"
    loaded.write_text(Path(arm.reference).read_text().replace("</robot>", part))
    data = str(tmp_path / "loaded.npz")
    assert main(["generate", "--robot", str(loaded), "--samples", "3000", "--noise", "0.05",
                 "--seed", "4", "--mode", "inverse", "--bias", "0", "--out", data]) == 0
    result = _closeloop(arm.reference, [data], tmp_path / "cl")
    (payload,) = [e for e in result["effects"] if e["effect"] == "payload"]
    assert payload["body"] == "gripper_link" and payload["joint"] == arm.dof - 1
    assert payload["mass"] == pytest.approx(0.15, rel=0.03)
    assert np.linalg.norm(np.array(payload["com"]) - [0.01, 0.0, -0.09]) < 0.005
    _predict_reproduces(tmp_path, data, result)


def _lynx_runs(coms, mass: float = 0.3, n: int = 300):
    """Two runs of the Lynxmotion (its RNEA, 0.002 N m noise), each carrying mass kg on its
    last body with the centre of mass given for it."""
    from identification.closeloop.candidates.payload import BodyTorque
    from tests.helpers import lynxmotion_motion

    arm = Arm.of("lynxmotion")
    runs = []
    for seed, com in zip((3, 4), coms, strict=True):
        m = lynxmotion_motion(n, seed=seed)
        load = standard(mass, com, [2e-4, 0.0, 3e-4, 0.0, 0.0, 2e-4])
        tau = arm.nominal.torque(m.q, m.qd, m.qdd) + BodyTorque(last_body(arm), load).torque(
            m.q, m.qd, m.qdd)
        runs.append((m.q, m.qd, m.qdd,
                     tau + 0.002 * np.random.default_rng(seed).normal(size=tau.shape)))
    return arm, runs


@pytest.mark.parametrize("second, agree", [((0.05, -0.01, 0.03), True),
                                           ((0.05, -0.008, 0.03), False)])
def test_the_runs_centres_of_mass_agree_only_when_they_do(monkeypatch, second, agree):
    """Two runs carrying one 0.3 kg load, its centre of mass (0.05, -0.01, 0.03) m in both, or
    moved 2 mm in the second (18 of the runs' combined standard errors, about 0.1 mm; 2 at
    most in the first): the named payload says the runs' centres of mass agree in the first
    case only.
    (The coefficients' jackknife intervals, not read here, are left out: they take 3/4 of
    the loop's time.)"""
    from identification.closeloop.selection import runs as loop_runs

    monkeypatch.setattr(loop_runs, "jackknife", lambda fit, rows: (
        None, np.full_like(fit(np.concatenate(rows)), np.nan)))
    arm, runs = _lynx_runs([(0.05, -0.01, 0.03), second])
    loop = loop_runs.close_loop_runs(arm.nominal, runs, body=last_body(arm))
    (payload,) = [n.to_json() for n in loop.named if n.term.effect == "payload"]
    assert payload["com_agrees"] is agree, (payload["per_run_com"], payload["per_run_com_std"])


def test_a_payload_s_centre_of_mass_is_where_the_mass_was_put():
    """A 1.5 kg point mass added in Pinocchio to the UR5's last body at (0.03, -0.02, 0.08) m
    in its frame: the body's parameters minus the arm's read back (describe, and the payload's
    entry in closeloop.json and model.json, as the bench's payload case reads its truth) as
    1.5 kg at that point, with no rotational inertia about it."""
    from identification.closeloop.candidates.effects import EffectTerm

    arm, put = Arm.of("ur5"), np.array([0.03, -0.02, 0.08])
    loaded = arm.pinocchio.copy()
    last = loaded.njoints - 1
    loaded.inertias[last] = loaded.inertias[last] + pin.Inertia(1.5, put, np.zeros((3, 3)))
    extra = (loaded.inertias[last].toDynamicParameters()
             - arm.pinocchio.inertias[last].toDynamicParameters())
    mass, com, inertia = describe(extra)
    assert mass == pytest.approx(1.5)
    np.testing.assert_allclose(com, put, atol=1e-12)
    np.testing.assert_allclose(inertia, 0.0, atol=1e-12)
    entry = EffectTerm("payload", arm.dof, 1.5, params=tuple(extra), body="wrist_3_link").to_json()
    np.testing.assert_allclose(entry["com"], put, atol=1e-12)
