"""What `torquebench plan` says besides the plan: why it writes none (one line), and that
it is compiling the planning problem."""

from __future__ import annotations

import dataclasses
import logging
import sys

import numpy as np

from planning.config import PlannerConfig, Scenario
from planning.penalty.solver import Planner
from planning.planners import uses_anytime


def infeasible(problems, config: PlannerConfig) -> str:
    """The error line of an execution that is not feasible; with the anytime SQP it says
    what its re-plans had: their quality is what that CPU buys on this machine
    (docs/realtime.md, 'harness.commands.plan')."""
    message = "no feasible plan: " + "; ".join(problems)
    if uses_anytime(config):
        clock = "CPU" if config.anytime.iteration_ms is None else "nominal time"
        message += (f" (the anytime SQP re-planned within {config.anytime.replan_budget_ms:g} ms of "
                    f"{clock}: a larger --replan-budget-ms or --replanner fatrop may find one)")
    return message


def torque_diagnosis(planner: Planner, scenario: Scenario) -> str | None:
    """A one-line reason when the torque limits are what make the goal unreachable: the
    torque-limited problem has no solution and the unobstructed optimum without limits
    needs more torque than a motor has."""
    config, model = planner.config, planner.model
    if config.torque_limit is None:
        return None
    args = (scenario.start, scenario.start_velocity, scenario.duration, scenario.goal)
    limited = planner.solve(*args)
    if limited.success and planner.torque_excess(limited.trajectory) <= 0:
        return None
    free = Planner(model, dataclasses.replace(config, torque_limit=None)).solve(*args)
    t = np.linspace(0.0, scenario.duration, 201)
    peak = np.abs(model.torque(*free.trajectory.state(t))).max(axis=0)
    limit = np.asarray(config.torque_limit)
    j = int(np.argmax(peak / limit))
    if peak[j] <= limit[j]:
        return None
    return (f"goal not reachable in {scenario.duration:g} s within the torque limits: the "
            f"best motion needs {peak[j]:.3g} N m on joint {j + 1} (limit {limit[j]:g} N m)")


class BuildNotice(logging.Handler):
    """Says once on stderr that the planning problem is being compiled (it can take a while
    on a new robot; planning.formulation.compiled logs each build), when stderr is a terminal
    (a script reading stderr gets the one-line errors only)."""

    def __init__(self, robot: str):
        super().__init__(logging.INFO)
        self.robot, self.said = robot, False

    def emit(self, record) -> None:
        if not self.said and sys.stderr.isatty():
            self.said = True
            print(f"torquebench: compiling the planning problem for {self.robot} (first time "
                  "only)...", file=sys.stderr, flush=True)
