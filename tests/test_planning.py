"""Planner building blocks cross-checked against independent computations."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from harness.robots.arm import Arm
from planning.formulation.clearance import link_clearances, segment_distance
from planning.formulation.kinematics import paper_arm
from planning.formulation.nlp import PlanningNLP
from planning.formulation.obstacle import LinearObstacle, predict_linear
from planning.formulation.trajectory import QuarticTrajectory
from planning.penalty.solver import Planner
from planning.types import ObstacleForecast
from tests.helpers import central_difference as _central_difference
from tests.helpers import lynx_config

RNG = np.random.default_rng(7)


def test_forward_kinematics_matches_mujoco_sites():
    model = Arm.of("lynxmotion").mujoco
    data = mujoco.MjData(model)
    geometry = paper_arm()
    for q in RNG.uniform([-1.5, 0, -3], [1.5, 3, 0], (10, 3)):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        _, shoulder, elbow, end = geometry.points(q)[0]
        for name, point in (("shoulder", shoulder), ("elbow", elbow), ("end_effector", end)):
            assert np.allclose(data.site(name).xpos, point, atol=1e-12), name


def test_segment_distance_matches_dense_sampling():
    a, b = RNG.normal(size=(50, 3)), RNG.normal(size=(50, 3))
    p = RNG.normal(size=(50, 3)) * 2
    u = np.linspace(0, 1, 20001)
    brute = [np.min(np.linalg.norm(a[i] + u[:, None] * (b[i] - a[i]) - p[i], axis=1))
             for i in range(50)]
    assert np.allclose(segment_distance(p, a, b), brute, atol=1e-7)


def test_segment_not_infinite_line():
    """Beyond the end effector the distance is to the tip, not to the extended line."""
    geometry = paper_arm()
    q = np.array([[0.0, 0.0, 0.0]])  # arm straight out along +x at shoulder height
    beyond = np.array([0.146 + 0.187 + 0.1, 0.0, 0.086])
    assert np.isclose(link_clearances(geometry, q, beyond)[0, 1], 0.1)


def test_quartic_derivatives_restriction_and_turning_points():
    trajectory = QuarticTrajectory(0.3, 1.7, RNG.normal(size=(3, 5)))
    t = np.linspace(0.4, 1.9, 9)
    q, qd, qdd = trajectory.state(t)
    h = 1e-6
    assert np.allclose(qd, (trajectory.state(t + h)[0] - trajectory.state(t - h)[0]) / (2 * h),
                       atol=1e-6)
    assert np.allclose(qdd, (trajectory.state(t + h)[1] - trajectory.state(t - h)[1]) / (2 * h),
                       atol=1e-5)
    part = trajectory.restrict(1.1, 0.9)
    assert all(np.allclose(x, y, atol=1e-12) for x, y in zip(trajectory.state(t[4:]),
                                                              part.state(t[4:]), strict=True))
    for j, times in enumerate(trajectory.turning_points()):
        inside = times[np.isfinite(times)]
        if inside.size:
            velocity = trajectory.state(0.3 + 1.7 * inside)[1][:, j]
            assert np.allclose(velocity, 0, atol=1e-9)


def test_linear_prediction_is_exact_for_a_linear_obstacle():
    obstacle = LinearObstacle((0.1, 0.4, 0.2), (0.2, -0.3, 0.3), 2.0)
    seen = obstacle.sample_times[3:5]
    future = obstacle.sample_times[5:]
    assert np.allclose(predict_linear(seen, obstacle.position(seen), future),
                       obstacle.position(future), atol=1e-14)


@pytest.fixture(scope="module")
def nlp_functions():
    model = Arm.of("lynxmotion").nominal
    config = lynx_config(obstacle_slots=8)
    planner = Planner(model, config)
    q0, goal = np.array([1.2, 0.6, -0.8]), np.array([-1.0, 1.2, -1.0])
    arm = QuarticTrajectory.from_free(0.0, 2.0, q0, np.zeros(3),
                                      RNG.normal(scale=0.3, size=(3, 3)))
    times = np.linspace(0.25, 2.0, 8)
    # obstacle centres 5 cm from the end effector: the penalty is active
    tip = config.geometry.flange_position(arm.state(times)[0])
    forecast = ObstacleForecast(times, tip + np.array([0.0, 0.05, 0.0]))
    # goal q1 on its lower limit: the goal-limit quotient rows are part of the check
    goal[0] = config.lower[0]
    p = planner.parameters(q0, np.array([0.1, -0.2, 0.3]), 2.0, goal, forecast, 0.0, arm)
    x = np.concatenate([arm.coefficients[:, 2:].ravel(), RNG.uniform(0.1, 1, 10)])
    return PlanningNLP(model, config).functions(), x, p


def test_objective_gradient_matches_finite_differences(nlp_functions):
    (objective, _, parts), x, p = nlp_functions
    assert float(parts(x, p)[1]) > 1e-3  # the obstacle penalty is part of the check
    gradient = np.asarray(objective(x, p)[1]).ravel()
    numeric = _central_difference(lambda y: objective(y, p)[0], x).ravel()
    assert np.allclose(gradient, numeric, rtol=1e-6, atol=1e-6)


def test_constraint_jacobian_matches_finite_differences(nlp_functions):
    (_, constraints, _), x, p = nlp_functions
    jacobian = np.asarray(constraints(x, p)[1])
    numeric = _central_difference(lambda y: constraints(y, p)[0], x)
    assert np.allclose(jacobian, numeric, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("order", [1, 2])
def test_goal_limit_quotient_is_polynomial_division(order):
    from planning.formulation.limits import quotient

    c = RNG.normal(size=5)
    if order == 2:  # arrive at rest: q'(1) = 0
        c[1] -= c[1] + 2 * c[2] + 3 * c[3] + 4 * c[4]
    goal = c.sum()  # q(1) = goal
    v = np.asarray(quotient(list(c), goal, -1.0, order))
    s = np.linspace(0, 0.95, 7)
    expected = -(np.polynomial.Polynomial(c)(s) - goal) / (1 - s) ** order
    assert np.allclose(np.polynomial.Polynomial(v)(s), expected, atol=1e-10)
