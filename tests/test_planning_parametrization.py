"""Higher-degree polynomials, dense energy quadrature, the net-work bound, swaying obstacle."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import quad

from harness.paper.planning.baselines import MinimumJerk
from harness.robots.arm import Arm
from harness.robots.baseline import PinocchioModel
from planning.formulation.energy import absolute_energy, net_work, power
from planning.formulation.obstacle import SwayingObstacle, predict_linear
from planning.formulation.quadrature import energy_nodes
from planning.formulation.trajectory import (
    PolynomialTrajectory,
    hermite,
    stationary_points,
    stationary_points_rows,
)
from planning.penalty.solver import Planner
from planning.result import executed_energy, sample_execution
from planning.types import ObstacleForecast, Segment
from tests.helpers import central_difference as _central_difference
from tests.helpers import lynx_config

RNG = np.random.default_rng(7)
Q0, GOAL = np.array([1.2, 0.6, -0.8]), np.array([-1.0, 1.2, -1.0])


@pytest.fixture(scope="module")
def pin_model():
    return Arm.of("lynxmotion").pinocchio


@pytest.fixture(scope="module")
def baseline(pin_model):
    return PinocchioModel(pin_model)


@pytest.mark.parametrize("smoothing", [0.0, 1e-3])
def test_degree_seven_gradients_match_finite_differences(baseline, smoothing):
    config = lynx_config(degree=7, energy_quadrature="gauss", energy_samples=12,
                           obstacle_slots=6, power_smoothing=smoothing)
    planner = Planner(baseline, config)
    arm = PolynomialTrajectory.from_free(0.0, 2.0, Q0, np.zeros(3),
                                         RNG.normal(scale=0.3, size=(3, 6)))
    times = np.linspace(0.3, 2.0, 6)
    tip = config.geometry.flange_position(arm.state(times)[0])
    forecast = ObstacleForecast(times, tip + np.array([0.0, 0.05, 0.0]))
    p = planner.parameters(Q0, np.array([0.1, -0.2, 0.3]), 2.0, GOAL, forecast, 0.0, arm)
    slacks = RNG.uniform(0.1, 1, 0 if smoothing else 12)
    x = np.concatenate([arm.coefficients[:, 2:].ravel(), slacks])
    objective, constraints, parts = planner.nlp.functions()
    assert float(parts(x, p)[1]) > 1e-3  # the obstacle penalty is part of the check
    assert np.allclose(np.asarray(objective(x, p)[1]).ravel(),
                       _central_difference(lambda y: objective(y, p)[0], x).ravel(),
                       rtol=1e-6, atol=1e-6)
    assert np.allclose(np.asarray(constraints(x, p)[1]),
                       _central_difference(lambda y: constraints(y, p)[0], x),
                       rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("degree", range(4, 10))
def test_boundary_conditions_hold_for_every_degree(baseline, degree):
    config = lynx_config(degree=degree, energy_quadrature="gauss", energy_samples=8,
                           rest_at_goal=True)
    qd0 = np.array([0.2, -0.1, 0.3])
    plan = Planner(baseline, config).solve(Segment(Q0, qd0, 0.5, 1.5, GOAL))
    assert plan.success
    trajectory = plan.trajectory
    assert trajectory.coefficients.shape == (3, degree + 1)
    q, qd, _ = trajectory.state([0.5, 2.0])
    assert np.allclose(q[0], Q0, atol=1e-12) and np.allclose(qd[0], qd0, atol=1e-12)
    assert np.allclose(q[1], GOAL, atol=1e-9) and np.allclose(qd[1], 0.0, atol=1e-9)


def test_degree_seven_restriction_and_turning_points():
    trajectory = PolynomialTrajectory(0.3, 1.7, RNG.normal(size=(3, 8)))
    t = np.linspace(1.1, 2.0, 7)
    part = trajectory.restrict(1.1, 0.9)
    assert all(np.allclose(a, b, atol=1e-11) for a, b in zip(trajectory.state(t), part.state(t),
                                                             strict=True))
    turning = trajectory.turning_points()
    assert turning.shape == (3, 6)
    for row, c in zip(turning, trajectory.coefficients, strict=True):
        assert np.allclose(row[np.isfinite(row)], stationary_points(c), atol=1e-9)


@pytest.mark.parametrize("degree", [2, 3, 4, 5, 7, 9])
def test_compiled_turning_points_are_numpys_roots(degree):
    # the compiled bracketing against np.roots' companion eigenvalues, rows of three scales
    c = RNG.normal(size=(2000, degree + 1)) * RNG.choice([1e-3, 1.0, 1e3], size=(2000, 1))
    c[:50, -1] = 0.0  # a lower degree than the array's
    rows = stationary_points_rows(c)
    assert rows.shape == (2000, max(degree - 1, 0))
    for row, coefficients in zip(rows, c, strict=True):
        expected = stationary_points(coefficients)
        found = row[np.isfinite(row)]
        assert len(found) == len(expected)
        assert np.allclose(found, expected, atol=1e-9)
    assert np.sum(np.isfinite(rows)) > 500  # the rows have turning points to find


def test_degree_five_rest_to_rest_is_minimum_jerk():
    c = hermite(np.stack([Q0, np.zeros(3), np.zeros(3)], axis=1),
                np.stack([GOAL, np.zeros(3), np.zeros(3)], axis=1), 5)
    quintic = PolynomialTrajectory(0.0, 2.0, c)
    jerk = MinimumJerk(Q0, GOAL, 2.0)
    t = np.linspace(0.0, 2.0, 21)
    assert all(np.allclose(a, b, atol=1e-12) for a, b in zip(quintic.state(t), jerk.state(t),
                                                             strict=True))
    # the planner's degree-5 NLP with rest at the goal: minimum jerk satisfies its equalities
    config = lynx_config(degree=5, energy_quadrature="gauss", energy_samples=6,
                           rest_at_goal=True, power_smoothing=1e-3)
    planner = Planner(Arm.of("lynxmotion").nominal, config)
    _, constraints, _ = planner.nlp.functions()
    g = np.asarray(constraints(c[:, 2:].ravel(), planner.parameters(
        Q0, np.zeros(3), 2.0, GOAL, None))[0]).ravel()
    assert np.allclose(g[:6], 0.0, atol=1e-12)  # goal position and goal velocity rows


@pytest.mark.parametrize("rule, n, degree", [("gauss", 5, 9), ("simpson", 7, 3),
                                             ("paper", 4, 0)])
def test_quadrature_rules_integrate_polynomials(rule, n, degree):
    s, w = energy_nodes(rule, n)
    assert np.isclose(w.sum(), 1.0)
    assert np.isclose(w @ s**degree, 1.0 / (degree + 1))


def _fixed_trajectory(seed: int = 7) -> PolynomialTrajectory:
    """A rest-to-rest motion of degree 7, the same whatever tests ran before (its own
    generator: the module's RNG made it depend on the order tests ran in)."""
    c = hermite(np.stack([Q0, np.zeros(3), np.zeros(3)], axis=1),
                np.stack([GOAL, np.zeros(3), np.zeros(3)], axis=1), 5)
    c = np.hstack([c, np.zeros((3, 2))])
    c[:, 3:] += 0.2 * np.random.default_rng(seed).normal(size=(3, 5)) \
        * np.array([1, -3, 3, -1, 0])  # keep c(1)
    return PolynomialTrajectory(0.0, 2.0, c)


def test_dense_energy_matches_scipy_quad_of_pinocchio_power(baseline):
    trajectory = _fixed_trajectory()

    def absolute_power(t: float) -> float:
        return float(abs(power(baseline, *trajectory.state(t))[0]))

    exact, _ = quad(absolute_power, 0.0, 2.0, limit=400, epsabs=1e-12, epsrel=1e-10)
    grid = np.linspace(0.0, 2.0, 4001)
    assert np.isclose(absolute_energy(baseline, grid, *trajectory.state(grid)), exact, rtol=1e-5)
    config = lynx_config(degree=7, energy_quadrature="gauss", energy_samples=60,
                           power_smoothing=1e-6)
    planner = Planner(baseline, config)
    x = trajectory.coefficients[:, 2:].ravel()
    planned = float(planner.nlp.functions()[2](x, planner.parameters(
        Q0, np.zeros(3), 2.0, trajectory.position(2.0)[0], None))[0])
    assert np.isclose(planned, exact, rtol=2e-3)


def test_net_work_is_the_potential_energy_change(baseline, pin_model):
    jerk = MinimumJerk(Q0, GOAL, 2.0)
    grid = np.linspace(0.0, 2.0, 4001)
    data = pin_model.createData()
    rise = (pin.computePotentialEnergy(pin_model, data, GOAL)
            - pin.computePotentialEnergy(pin_model, data, Q0))
    assert np.isclose(net_work(baseline, grid, *jerk.state(grid)), rise, rtol=1e-6)
    # and bounds the absolute energy of any motion from Q0 at rest to GOAL (rise > 0:
    # integral |P| >= integral P = rise + final kinetic energy)
    trajectory = _fixed_trajectory()
    assert absolute_energy(baseline, grid, *trajectory.state(grid)) >= abs(rise) - 1e-9


def test_swaying_obstacle_defeats_constant_velocity_prediction():
    obstacle = SwayingObstacle((0.1, 0.4, 0.2), (0.2, -0.3, 0.3), 2.0, sway=(0.0, 0.0, 0.04))
    assert np.allclose(obstacle.position([0.0, 1.0, 2.0]),
                       [obstacle.start, 0.5 * (np.add(obstacle.start, obstacle.end)),
                        obstacle.end], atol=1e-12)
    seen, future = obstacle.sample_times[3:5], obstacle.sample_times[5:]
    error = predict_linear(seen, obstacle.position(seen), future) - obstacle.position(future)
    assert np.max(np.linalg.norm(error, axis=1)) > 0.01


def test_plan_command_with_degree_quadrature_and_sway(tmp_path):
    from harness.cli import main

    out = tmp_path / "plan.json"
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--degree", "5", "--energy-quadrature",
                 "gauss", "--energy-samples", "20", "--obstacle-sway", "0,0.04,0",
                 "--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    for key in ("coefficients", "t", "q", "qd", "qdd", "obstacle", "threshold", "energy",
                "min_clearance", "replans", "solve_ms"):
        assert key in plan
    assert np.asarray(plan["coefficients"]).shape[1:] == (3, 6)
    assert plan["replans"] >= 2  # the forecast is wrong at every sample near the arm
    assert plan["min_clearance"] >= plan["threshold"] - 2e-3
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--degree", "3", "--out", str(out)]) == 2


def test_executed_energy_integrates_each_segment_across_a_replan(baseline):
    """Two segments joined at a re-plan (position and velocity kept, acceleration changed:
    the power jumps): executed_energy against scipy's quad of |P| on each followed interval,
    and the trapezoid on one grid across the join, which misses by about half a step times
    the jump."""
    first = _fixed_trajectory()
    join = 0.7003  # between the grid's points
    q, qd, qdd = (v[0] for v in first.state(join))
    second = PolynomialTrajectory.from_free(join, 2.0 - join, q, qd,
                                            np.array([[1.0, -0.5, 0.2]] * 3))
    assert np.max(np.abs(second.state(join)[2][0] - qdd)) > 1.0  # the acceleration jumps
    segment = SimpleNamespace(trajectory=first), SimpleNamespace(trajectory=second)
    execution = SimpleNamespace(segments=segment)

    def absolute(trajectory, t: float) -> float:
        return float(abs(power(baseline, *trajectory.state(t))[0]))

    exact = sum(quad(lambda t, s=s: absolute(s, t), a, b, limit=400, epsabs=1e-12)[0]
                for s, a, b in ((first, 0.0, join), (second, join, 2.0)))
    grid = np.linspace(0.0, 2.0, 201)
    assert np.isclose(executed_energy(baseline, execution, grid), exact, rtol=1e-4)
    across = absolute_energy(baseline, grid, *sample_execution(execution, grid))
    assert abs(across - exact) > 10 * abs(executed_energy(baseline, execution, grid) - exact)
