"""The robot models: MuJoCo and Pinocchio agree, and match the paper's kinematics."""

from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from harness.robots.arm import Arm
from harness.robots.registry import MODELS, ROBOTS, get_robot

D1, L2, L3 = 0.086, 0.146, 0.187


def random_states(model: mujoco.MjModel, n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    ids = model.dof_jntid
    limited = model.jnt_limited[ids].astype(bool)
    lo = np.where(limited, model.jnt_range[ids, 0], -np.pi)
    hi = np.where(limited, model.jnt_range[ids, 1], np.pi)
    q = rng.uniform(lo, hi, size=(n, model.nv))
    return q, rng.normal(scale=2.0, size=q.shape), rng.normal(scale=10.0, size=q.shape)


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_mj_inverse_matches_pinocchio_rnea(name):
    """mj_inverse (MJCF or URDF in MuJoCo) vs RNEA (+ URDF damping) on the URDF."""
    model = Arm.of(name).mujoco
    data = mujoco.MjData(model)
    baseline = Arm.of(name).nominal
    q, qd, qdd = random_states(model, 1000)
    tau_mj = np.empty_like(q)
    for k in range(len(q)):
        data.qpos[:], data.qvel[:], data.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(model, data)
        tau_mj[k] = data.qfrc_inverse
    tau_pin = baseline.torque(q, qd, qdd)
    assert np.abs(tau_mj).max() > 0.1  # the comparison is not vacuous
    assert np.abs(tau_mj - tau_pin).max() < 1e-9


def paper_positions(q):
    """Elbow P2 and end effector P3 from the paper's eqs. (10) and (9)."""
    q1, q2, q3 = q
    reach = L3 * np.cos(q2 + q3) + L2 * np.cos(q2)
    p3 = np.array([np.cos(q1) * reach, np.sin(q1) * reach,
                   L2 * np.sin(q2) + L3 * np.sin(q2 + q3) + D1])
    p2 = np.array([L2 * np.cos(q1) * np.cos(q2), L2 * np.cos(q2) * np.sin(q1),
                   L2 * np.sin(q2) + D1])
    return p2, p3


def test_lynxmotion_kinematics_match_paper_eqs_9_10():
    model = Arm.of("lynxmotion").mujoco
    data = mujoco.MjData(model)
    pmodel = Arm.of("lynxmotion").pinocchio
    pdata = pmodel.createData()
    ee = pmodel.getFrameId("end_effector", pin.FrameType.BODY)
    q_all, _, _ = random_states(model, 500, seed=1)
    for q in q_all:
        p2, p3 = paper_positions(q)
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        assert np.abs(data.site("elbow").xpos - p2).max() < 1e-12
        assert np.abs(data.site("end_effector").xpos - p3).max() < 1e-12
        assert np.abs(data.site("shoulder").xpos - [0, 0, D1]).max() < 1e-12
        pin.forwardKinematics(pmodel, pdata, q)
        pin.updateFramePlacements(pmodel, pdata)
        assert np.abs(pdata.oMi[3].translation - p2).max() < 1e-12
        assert np.abs(pdata.oMf[ee].translation - p3).max() < 1e-12


def test_lynxmotion_parameters_are_the_papers():
    model = Arm.of("lynxmotion").mujoco
    assert model.body("link1").mass[0] == pytest.approx(0.3)
    assert model.body("link2").mass[0] == pytest.approx(0.2)
    assert model.body("link3").mass[0] == pytest.approx(0.5)
    np.testing.assert_allclose(model.body("link2").ipos, [L2 / 2, 0, 0])
    np.testing.assert_allclose(model.body("link3").ipos, [L3 / 2, 0, 0])
    np.testing.assert_allclose(model.jnt_range, [[-np.pi / 2, np.pi / 2], [0, np.pi], [-np.pi, 0]])
    assert model.body("link1").inertia[2] == pytest.approx(2.77e-4)
    for body in ("link1", "link2", "link3"):  # physically valid: triangle inequality
        a, b, c = model.body(body).inertia
        assert a + b >= c and b + c >= a and a + c >= b and min(a, b, c) > 0


def scene_files() -> list[Path]:
    return sorted(MODELS.glob("*/*.xml"))


@pytest.mark.parametrize("target", [str(p) for p in scene_files()] + sorted(ROBOTS))
def test_every_scene_simulates_one_second_without_warning(target, capfd):
    model = Arm.of(target).mujoco
    data = mujoco.MjData(model)
    if model.nkey:
        mujoco.mj_resetDataKeyframe(model, data, 0)
    while data.time < 1.0:
        mujoco.mj_step(model, data)
    assert np.all(np.isfinite(data.qpos))
    assert all(w.number == 0 for w in data.warning), [w.number for w in data.warning]
    assert "WARNING" not in capfd.readouterr().err


def test_registry_paths_exist():
    for name in ROBOTS:
        robot = get_robot(name)
        assert robot.urdf.is_file()
        for path in (robot.mjcf, robot.scene):
            assert path is None or path.is_file()


def test_a_urdf_path_loads_like_the_registered_robot_and_leaves_no_mujoco_log(tmp_path, monkeypatch):
    """A user's URDF path goes through the same normalization as a registered one: meshes
    dropped, ROS's lower = upper = 0 'no limit' removed, so MuJoCo warns about nothing
    (a warning would write MUJOCO_LOG.TXT into the working directory)."""
    monkeypatch.chdir(tmp_path)
    urdf = get_robot("double_pendulum").urdf
    by_path, by_name = Arm.of(urdf).mujoco, Arm.of("double_pendulum").mujoco
    assert by_path.nv == by_name.nv == 2
    np.testing.assert_array_equal(by_path.body_mass, by_name.body_mass)
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()
