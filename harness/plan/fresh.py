"""Random scenarios of an arm (planning.scenarios.random_scenarios from its unobstructed
optimum): the scenarios no planner setting was chosen on, where the bench and the studies score
the planner apart from its development scenarios."""

from __future__ import annotations

import numpy as np

from harness.plan.arm_config import planner_config
from harness.robots.arm import Arm
from planning.penalty.solver import Planner
from planning.scenarios import random_scenarios
from planning.types import Segment


def arm_scenarios(arm: Arm, count: int, seed: int, span: float | None = None) -> list:
    """count random scenarios of arm from seed, from its unobstructed optimum; start and goal
    within +-span rad of zero (None: the joints' ranges)."""
    config = planner_config(arm)
    planner = Planner(arm.nominal, config)

    def free_motion(start, goal, duration):
        return planner.solve(Segment.from_rest(start, duration, goal)).trajectory

    lower, upper = np.asarray(config.lower), np.asarray(config.upper)
    if span is not None:  # start and goal within +-span: reachable in 2 s
        lower, upper = np.maximum(lower, -span), np.minimum(upper, span)
    return random_scenarios(count, seed, free_motion, config.geometry, lower, upper,
                            config.threshold)


def plan_options(scenario) -> tuple[str, ...]:
    """`torquebench plan`'s options that give the scenario (its start, goal, and swaying
    obstacle path), each number to 6 significant digits as a user would type it."""
    obstacle = scenario.obstacle
    vec = lambda v: ",".join(f"{x:.6g}" for x in v)  # noqa: E731
    return ("--start", vec(scenario.start), "--goal", vec(scenario.goal), "--obstacle-from",
            vec(obstacle.start), "--obstacle-to", vec(obstacle.end), "--obstacle-sway",
            vec(obstacle.sway), "--sway-periods", f"{obstacle.periods:.6g}")
