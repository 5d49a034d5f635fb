"""The planner's forward kinematics of any arm (planning.formulation.kinematics) against independent
implementations: the paper's eqs. (9)-(10), Pinocchio's frames, MuJoCo's joint anchors and
sites in the scene built around the arm, finite differences of its CasADi form."""

from __future__ import annotations

import casadi as ca
import mujoco
import numpy as np
import pinocchio as pin
import pytest

from harness.robots.arm import Arm
from harness.robots.registry import flange_frame
from harness.robots.scene import replay_scene
from planning.formulation.clearance import link_clearances, symbolic_link_clearances
from planning.formulation.kinematics import paper_arm
from tests.helpers import central_difference

RNG = np.random.default_rng(12)
ARMS = ("lynxmotion", "ur5", "panda")


def _random_q(robot: str, n: int) -> np.ndarray:
    lower, upper = Arm.of(robot).joint_limits
    return RNG.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi), (n, len(lower)))


def _paper_eqs_9_10(q, d1=0.086, l2=0.146, l3=0.187):
    """Elbow (eq. 10) and end effector (eq. 9) of the paper, written out."""
    q1, q2, q3 = q.T
    reach2, reach3 = l2 * np.cos(q2), l2 * np.cos(q2) + l3 * np.cos(q2 + q3)
    elbow = np.stack([reach2 * np.cos(q1), reach2 * np.sin(q1), d1 + l2 * np.sin(q2)], axis=1)
    end = np.stack([reach3 * np.cos(q1), reach3 * np.sin(q1),
                    d1 + l2 * np.sin(q2) + l3 * np.sin(q2 + q3)], axis=1)
    return elbow, end


def test_paper_arm_is_eqs_9_10_numeric_and_symbolic():
    q = _random_q("lynxmotion", 50)
    elbow, end = _paper_eqs_9_10(q)
    points = paper_arm().points(q)
    np.testing.assert_allclose(points[:, 2], elbow, atol=1e-15)
    np.testing.assert_allclose(points[:, 3], end, atol=1e-15)
    x = ca.SX.sym("q", 3)
    fk = ca.Function("fk", [x], [ca.horzcat(*paper_arm().symbolic_points(x))])
    for row in q[:5]:
        np.testing.assert_allclose(np.asarray(fk(row)).T, paper_arm().points(row)[0],
                                   atol=1e-15)
    assert paper_arm().links == ((1, 2), (2, 3))  # the base segment lies on joint 1's axis


def test_lynxmotion_model_chain_is_the_paper_arm():
    q = _random_q("lynxmotion", 20)
    np.testing.assert_allclose(Arm.of("lynxmotion").geometry.points(q), paper_arm().points(q),
                               atol=1e-15)


@pytest.mark.parametrize("robot", ARMS)
def test_points_are_pinocchio_joint_and_flange_frames(robot):
    model = Arm.of(robot).pinocchio
    data = model.createData()
    geometry = Arm.of(robot).geometry
    flange = model.getFrameId(flange_frame(model), pin.FrameType.BODY)
    for q in _random_q(robot, 10):
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacements(model, data)
        expected = [data.oMi[j].translation for j in range(1, model.njoints)]
        expected.append(data.oMf[flange].translation)
        np.testing.assert_allclose(geometry.points(q)[0], expected, atol=1e-12)


@pytest.mark.parametrize("robot", ARMS)
def test_points_are_mujoco_anchors_sites_and_capsules(robot):
    """The replay scene's joint anchors, flange site and link capsules sit on the chain."""
    model, geometry = replay_scene(Arm.of(robot)), Arm.of(robot).geometry
    data = mujoco.MjData(model)
    for q in _random_q(robot, 10):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        points = geometry.points(q)[0]
        np.testing.assert_allclose(data.xanchor[:geometry.dof], points[:-1], atol=1e-12)
        np.testing.assert_allclose(data.site("end_effector").xpos, points[-1], atol=1e-12)
        for (i, j), length in zip(geometry.links, geometry.link_lengths, strict=True):
            capsule = data.geom(f"link{i + 1}")
            axis = capsule.xmat.reshape(3, 3)[:, 2]
            middle = 0.5 * (points[i] + points[j])
            np.testing.assert_allclose(capsule.xpos, middle, atol=1e-12)
            assert abs(abs(axis @ (points[j] - points[i])) - length) < 1e-12


@pytest.mark.parametrize("robot", ARMS)
def test_links_are_the_segments_that_move(robot):
    """Every segment between consecutive points is a link unless it is a point or stays put
    (checked on random motions, independently of the axis test the chain uses)."""
    geometry = Arm.of(robot).geometry
    points = geometry.points(_random_q(robot, 30))
    for i in range(geometry.dof):
        length = np.linalg.norm(points[0, i + 1] - points[0, i])
        moves = np.ptp(points[:, [i, i + 1]], axis=0).max() > 1e-9
        assert ((i, i + 1) in geometry.links) == (length > 1e-9 and moves), (robot, i)


@pytest.mark.parametrize("robot", ARMS)
def test_fixed_points_are_the_link_ends_no_motion_moves(robot):
    """fixed_points (the axis test) are exactly the link ends that stay put on random
    motions."""
    geometry = Arm.of(robot).geometry
    points = geometry.points(_random_q(robot, 30))
    ends = sorted({i for link in geometry.links for i in link})
    still = tuple(i for i in ends if np.ptp(points[:, i], axis=0).max() < 1e-9)
    assert geometry.fixed_points == still and still, robot


@pytest.mark.parametrize("robot", ("ur5", "panda"))
def test_symbolic_points_derivatives_match_finite_differences(robot):
    geometry = Arm.of(robot).geometry
    x = ca.SX.sym("q", geometry.dof)
    points = ca.vertcat(*geometry.symbolic_points(x))
    jacobian = ca.Function("J", [x], [ca.jacobian(points, x)])
    for q in _random_q(robot, 3):
        numeric = central_difference(lambda v: geometry.points(v)[0].ravel(), q)
        np.testing.assert_allclose(np.asarray(jacobian(q)), numeric, atol=1e-8)


def test_symbolic_clearances_equal_numeric_on_ur5():
    geometry = Arm.of("ur5").geometry
    x, centre = ca.SX.sym("q", 6), ca.SX.sym("c", 3)
    f = ca.Function("d", [x, centre], [ca.vertcat(*symbolic_link_clearances(geometry, x,
                                                                            centre))])
    for q in _random_q("ur5", 5):
        c = RNG.uniform(-0.6, 0.6, 3)
        np.testing.assert_allclose(np.asarray(f(q, c)).ravel(),
                                   link_clearances(geometry, q[None], c)[0], atol=1e-13)


def test_limits_come_from_the_models():
    assert Arm.of("ur5").torque_limit == (150.0, 150.0, 150.0, 28.0, 28.0, 28.0)  # URDF effort
    assert Arm.of("lynxmotion").torque_limit == (10.0, 10.0, 10.0)  # MJCF motors' ctrlrange
    lower, upper = Arm.of("panda").joint_limits
    np.testing.assert_allclose(upper[3], -0.0698)
    scene = replay_scene(Arm.of("panda"))
    np.testing.assert_allclose(scene.actuator_ctrlrange[:, 1], Arm.of("panda").torque_limit)
