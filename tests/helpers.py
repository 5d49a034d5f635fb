"""Small helpers shared by several test modules."""

import numpy as np
import pinocchio as pin

from harness.robots.baseline import PinocchioModel
from harness.robots.registry import load_pinocchio


def central_difference(fun, x, h=1e-6):
    """Jacobian of fun at x by central differences, columns along the last axis."""
    columns = []
    for i in range(len(x)):
        e = np.zeros_like(x)
        e[i] = h
        columns.append((np.asarray(fun(x + e)) - np.asarray(fun(x - e))).ravel() / (2 * h))
    return np.stack(columns, axis=-1)


def heavier_model(scale: float) -> PinocchioModel:
    """A stand-in 'identified' model: the Lynxmotion arm with every link's inertia scaled."""
    model = load_pinocchio("lynxmotion")
    for j in range(1, model.njoints):
        inertia = model.inertias[j]
        model.inertias[j] = pin.Inertia(inertia.mass * scale, inertia.lever,
                                        inertia.inertia * scale)
    return PinocchioModel(model)


def random_crossing(planner, seed: int):
    """One random scenario of planning.scenarios (the obstacle crossing the planner's
    unobstructed optimum) and its obstacle forecast with the whole path known."""
    from planning.scenarios import random_scenarios
    from planning.solver import ObstacleForecast

    config = planner.config

    def free_motion(start, goal, duration):
        return planner.solve(start, (0.0,) * len(start), duration, goal).trajectory

    case = random_scenarios(1, seed, free_motion, config.geometry, config.lower, config.upper)[0]
    t = case.obstacle.sample_times
    return case, ObstacleForecast(t, case.obstacle.position(t))
