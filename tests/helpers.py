"""Small helpers shared by several test modules."""

import dataclasses

import numpy as np
import pinocchio as pin

from harness.paper.planning.scenario import paper_config, paper_default_config, paper_scenario
from harness.robots.arm import Arm
from harness.robots.baseline import PinocchioModel
from identification.signals import multisine
from identification.torque_model import Motion
from planning.types import Segment


def lynx_config(**changes):
    """The paper's formulation on the Lynxmotion (harness.paper.planning.scenario.paper_config:
    its closed-form links, joint and torque limits) with these fields changed."""
    return paper_config(**changes)


def lynx_default_config(**changes):
    """What `plan` plans with by default (planning.config.true_energy_config) on the
    Lynxmotion of lynx_config, with these fields changed."""
    return paper_default_config(**changes)


def lynx_scenario(**changes):
    """The paper's scenario on the Lynxmotion with these fields changed."""
    return dataclasses.replace(paper_scenario(), **changes)


def central_difference(fun, x, h=1e-6):
    """Jacobian of fun at x by central differences, columns along the last axis."""
    columns = []
    for i in range(len(x)):
        e = np.zeros_like(x)
        e[i] = h
        columns.append((np.asarray(fun(x + e)) - np.asarray(fun(x - e))).ravel() / (2 * h))
    return np.stack(columns, axis=-1)


def perturbed_model(seed: int = 0, spread: float = 0.05, shift: float = 0.005) -> PinocchioModel:
    """A stand-in 'identified' model that differs from the Lynxmotion in structure: every
    body's mass scaled by its own factor in 1 +/- spread, its centre of mass moved up to
    `shift` m, its rotational inertia scaled per principal axis (a common scale of every
    inertia would scale the torque, and the optimal plan would be the same plan)."""
    rng = np.random.default_rng(seed)
    model = Arm.of("lynxmotion").pinocchio.copy()  # the Arm's model is shared: change a copy
    for j in range(1, model.njoints):
        inertia = model.inertias[j]
        axes = np.diag(1 + rng.uniform(-spread, spread, 3))
        model.inertias[j] = pin.Inertia(inertia.mass * (1 + rng.uniform(-spread, spread)),
                                        inertia.lever + rng.uniform(-shift, shift, 3),
                                        axes @ inertia.inertia @ axes)
    return PinocchioModel(model)


def random_crossing(planner, seed: int):
    """One random scenario of planning.scenarios (the obstacle crossing the planner's
    unobstructed optimum) and its obstacle forecast with the whole path known."""
    from planning.scenarios import random_scenarios
    from planning.types import ObstacleForecast

    config = planner.config

    def free_motion(start, goal, duration):
        return planner.solve(Segment(start, (0.0,) * len(start), 0.0, duration, goal)).trajectory

    case = random_scenarios(1, seed, free_motion, config.geometry, config.lower, config.upper)[0]
    t = case.obstacle.sample_times
    return case, ObstacleForecast(t, case.obstacle.position(t))


def segments(planner):
    """The segment planner (planning.planners) of a penalty-loop Planner's model and
    configuration, reusing its solvers: what Algorithm 2 takes."""
    from planning.planners import segment_planner

    return segment_planner(planner.model, planner.config, planner)


def lynxmotion_motion(n: int = 4000, seed: int = 0, duration: float = 20.0) -> Motion:
    """Wide multi-sine inside the Lynxmotion joint limits (q1 in [-pi/2, pi/2], q2 in
    [0, pi], q3 in [-pi, 0]) with a 0.1 rad margin."""
    centre = [0.0, np.pi / 2, -np.pi / 2]
    return multisine(n, 3, seed, centre, np.pi / 2 - 0.1, duration)


def fail_clarabel(monkeypatch) -> None:
    """Every cvxpy solve asked of Clarabel raises a SolverError; other solvers solve."""
    import cvxpy as cp
    solve = cp.Problem.solve

    def failing(self, *args, solver=None, **kwargs):
        if solver == cp.CLARABEL:
            raise cp.SolverError("Clarabel failed (forced for the test)")
        return solve(self, *args, solver=solver, **kwargs)

    monkeypatch.setattr(cp.Problem, "solve", failing)
