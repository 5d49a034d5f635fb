"""What `torquebench plan` says besides the plan: why it writes none (one line), and that
it is compiling the planning problem."""

from __future__ import annotations

import dataclasses
import logging
import sys
import time

import numpy as np

from harness.robots.registry import DEFAULT_ROBOT
from planning.config import PlannerConfig, Scenario
from planning.formulation.clearance import link_clearances
from planning.penalty.solver import Planner
from planning.planners import uses_anytime

SMOOTH_MARGIN = 1.5  # a smooth rest-to-rest motion (a cubic) peaks at 1.5 x its mean velocity


def velocity_duration(config: PlannerConfig, scenario: Scenario) -> tuple[float, int] | None:
    """The shortest duration (s) the velocity limits allow, max over joints of
    |goal - start| / limit (no motion covers more than limit x duration), and that joint
    (0-based); None without velocity limits."""
    if config.velocity_limit is None:
        return None
    needed = (np.abs(np.subtract(scenario.goal, scenario.start))
              / np.asarray(config.velocity_limit, float))
    j = int(np.argmax(needed))
    return float(needed[j]), j


def _longer_duration(config: PlannerConfig, scenario: Scenario) -> str:
    shortest, j = velocity_duration(config, scenario)
    return (f"a longer --duration may find one: joint {j + 1} at its velocity limit "
            f"{config.velocity_limit[j]:g} rad/s needs >= {shortest:.3g} s, a smooth motion "
            f"about {SMOOTH_MARGIN * shortest:.3g} s")


def velocity_diagnosis(config: PlannerConfig, scenario: Scenario) -> str | None:
    """A one-line reason when the velocity limits make the goal unreachable in the duration:
    some joint would have to move faster than its limit even on a straight line."""
    bound = velocity_duration(config, scenario)
    if bound is None or bound[0] <= scenario.duration:
        return None
    return (f"goal not reachable in {scenario.duration:g} s within the velocity limits: "
            + _longer_duration(config, scenario))


def default_obstacle_diagnosis(config: PlannerConfig, scenario: Scenario, robot: str) -> str | None:
    """A one-line reason when the default obstacle path (the Lynxmotion paper scenario's,
    given no --obstacle-from/--obstacle-to) starts or ends within the threshold of another
    robot's links: that path means nothing for it."""
    obstacle, default = scenario.obstacle, Scenario().obstacle
    if str(robot) == DEFAULT_ROBOT or obstacle is None or (
            tuple(obstacle.start), tuple(obstacle.end)) != (default.start, default.end):
        return None
    ends = np.asarray([scenario.start, scenario.goal])
    clearance = [link_clearances(config.geometry, ends[[k]], obstacle.position(t)).min()
                 for k, t in ((0, 0.0), (1, scenario.duration))]
    if min(clearance) >= config.threshold:
        return None
    which = "start" if clearance[0] < config.threshold else "goal"
    return (f"the default obstacle path (the Lynxmotion paper scenario's) lies within the "
            f"threshold of robot {robot}'s links at the {which} (clearance {min(clearance):.4f} m "
            f"< {config.threshold:g} m): give --obstacle-from and --obstacle-to for this robot")


def infeasible(problems, config: PlannerConfig, scenario: Scenario | None = None) -> str:
    """The error line of an execution that is not feasible; when velocities exceed their
    limits it suggests a longer duration (given the scenario); with the anytime SQP it says
    what its re-plans had: their quality is what that CPU buys on this machine
    (docs/realtime.md, 'harness.commands.plan')."""
    message = "no feasible plan: " + "; ".join(problems)
    if (scenario is not None and config.velocity_limit is not None
            and any(" velocity " in p for p in problems)):
        message += f" (the velocity limits: {_longer_duration(config, scenario)})"
    elif uses_anytime(config):
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
    """Says on stderr, one line as each stage starts, what of the planner is being compiled
    and for how long compiling has gone on (it can take a while on a new robot;
    planning.formulation.compiled logs each build's start and end), and the total once the
    plan is written; only when stderr is a terminal (a script reading stderr gets the
    one-line errors only)."""

    SMALL_KB = 100  # builds of less C take under a second: not announced

    def __init__(self, robot: str, joints: int | None = None):
        super().__init__(logging.INFO)
        self.robot, self.joints = robot, joints
        self.began: float | None = None
        self.ended = 0.0

    def emit(self, record) -> None:
        stage = getattr(record, "stage", None)
        if stage is None or not sys.stderr.isatty():
            return
        now = time.perf_counter()
        if record.done:
            self.ended = now
            return
        if record.kilobytes < self.SMALL_KB:
            return
        first = self.began is None
        self.began = now if first else self.began
        when = "first time only, cached for later runs" if first else \
            f"{now - self.began:.0f} s"
        print(f"{self._head()}: {when}, {stage} ({record.kilobytes} kB of C at "
              f"{record.level})...", file=sys.stderr, flush=True)

    def finish(self) -> None:
        """The total time compiling took, if anything was compiled."""
        if self.began is not None and sys.stderr.isatty():
            print(f"{self._head()}: done in {self.ended - self.began:.0f} s", file=sys.stderr,
                  flush=True)

    def _head(self) -> str:
        joints = "" if self.joints is None else f" ({self.joints} joints)"
        return f"torquebench: compiling the planner for {self.robot}{joints}"
