"""What `torquebench plan` says besides the plan: why it writes none (one line), and that
it is compiling the planning problem."""

from __future__ import annotations

import dataclasses
import logging
import sys
import time
from functools import cache

import numpy as np
from scipy.optimize import linprog

from harness.plan.arm_config import OBSTACLE_PATH
from harness.robots.arm import Arm
from planning.config import JSON_NAMES, PlannerConfig, Scenario
from planning.formulation.clearance import link_clearances
from planning.formulation.limits import LIMIT_TOLERANCE
from planning.penalty.solver import Planner
from planning.planners import uses_anytime
from planning.result import torque_problems
from planning.types import Segment

PEAK_GRID = 2001  # points of [0, 1] at which peak_factor bounds the speed (a lower bound)


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


@cache
def peak_factor(degree: int, rest_at_goal: bool) -> float:
    """The least peak speed, in units of the mean speed, of a polynomial of this degree from
    rest (p(0) = p'(0) = 0) to p(1) = 1, at rest there too if rest_at_goal: a linear program
    on the speed at PEAK_GRID points, so a lower bound (1.5 at degree 4 from rest to rest:
    the cubic's)."""
    s, k = np.linspace(0.0, 1.0, PEAK_GRID), np.arange(2, degree + 1)
    speed = k * s[:, None] ** (k - 1)  # p'(s) per free coefficient
    ones = np.ones((PEAK_GRID, 1))
    equal = [np.r_[np.ones(len(k)), 0.0]] + ([np.r_[k, 0.0]] if rest_at_goal else [])
    result = linprog(np.r_[np.zeros(len(k)), 1.0], A_ub=np.block([[speed, -ones], [-speed, -ones]]),
                     b_ub=np.zeros(2 * PEAK_GRID), A_eq=np.array(equal),
                     b_eq=[1.0] + [0.0] * rest_at_goal,
                     bounds=[(None, None)] * len(k) + [(0.0, None)], method="highs")
    return float(result.fun) if result.success else 1.0


def _longer_duration(config: PlannerConfig, scenario: Scenario) -> str:
    shortest, j = velocity_duration(config, scenario)
    message = (f"a longer --duration may find one: joint {j + 1} at its velocity limit "
               f"{config.velocity_limit[j]:g} rad/s needs >= {shortest:.3g} s on a straight line")
    bound = polynomial_duration(config, scenario)
    if bound is not None:
        message += f", >= {bound[0]:.3g} s on the planner's degree-{config.degree} polynomial"
    return message


def polynomial_duration(config: PlannerConfig, scenario: Scenario) -> tuple[float, int] | None:
    """The shortest duration (s) in which the first plan, one polynomial of config.degree
    from the start at rest, can keep every joint within its velocity limit, and that joint;
    None without velocity limits or from a moving start."""
    straight = velocity_duration(config, scenario)  # the same factor on every joint
    if straight is None or np.any(np.asarray(scenario.start_velocity) != 0):
        return None
    return peak_factor(config.degree, config.rest_at_goal) * straight[0], straight[1]


def velocity_diagnosis(config: PlannerConfig, scenario: Scenario) -> str | None:
    """A one-line reason when the velocity limits make the goal unreachable in the duration:
    some joint would have to move faster than its limit on a straight line, or on the best
    polynomial the first plan can be (polynomial_duration)."""
    bounds = [b for b in (velocity_duration(config, scenario),
                          polynomial_duration(config, scenario)) if b is not None]
    # a plan may pass a limit by LIMIT_TOLERANCE: refuse only what exceeds it too
    if all(bound[0] <= scenario.duration * (1.0 + LIMIT_TOLERANCE) for bound in bounds):
        return None
    return (f"goal not reachable in {scenario.duration:g} s within the velocity limits: "
            + _longer_duration(config, scenario))


def uses_the_default_obstacle(arm: Arm, defaulted: bool) -> bool:
    """Whether a robot that registers no obstacle path plans past the paper scenario's
    (defaulted: the user gave neither --obstacle-from nor --obstacle-to)."""
    return defaulted and arm.entry.obstacle is None


def default_obstacle_notice(arm: Arm, defaulted: bool) -> str | None:
    """The line `plan` adds after a plan of another robot past the default obstacle path
    (defaulted: neither --obstacle-from nor --obstacle-to given): an obstacle placed for the
    Lynxmotion, which the plan's clearance is measured to."""
    if not uses_the_default_obstacle(arm, defaulted):
        return None
    start, end = OBSTACLE_PATH
    return ("note: the obstacle is the Lynxmotion paper scenario's default path, from "
            f"({', '.join(f'{v:g}' for v in start)}) to ({', '.join(f'{v:g}' for v in end)}) m, "
            f"not one placed for robot {arm.label}: give --obstacle-from and --obstacle-to to "
            "plan past yours")


def default_obstacle_diagnosis(config: PlannerConfig, scenario: Scenario, arm: Arm,
                               defaulted: bool) -> str | None:
    """A one-line reason when the default obstacle path (the Lynxmotion paper scenario's,
    defaulted: given no --obstacle-from/--obstacle-to) starts or ends within the threshold
    of another robot's links: that path means nothing for it."""
    if not uses_the_default_obstacle(arm, defaulted) or scenario.obstacle is None:
        return None
    obstacle = scenario.obstacle
    ends = np.asarray([scenario.start, scenario.goal])
    clearance = [link_clearances(config.geometry, ends[[k]], obstacle.position(t)).min()
                 for k, t in ((0, 0.0), (1, scenario.duration))]
    if min(clearance) >= config.threshold:
        return None
    which = "start" if clearance[0] < config.threshold else "goal"
    return (f"the default obstacle path (the Lynxmotion paper scenario's) lies within the "
            f"threshold of robot {arm.label}'s links at the {which} (clearance {min(clearance):.4f} m "
            f"< {config.threshold:g} m): give --obstacle-from and --obstacle-to for this robot")


def infeasible(problems, config: PlannerConfig, scenario: Scenario | None = None,
               both: bool = False) -> str:
    """The error line of an execution that is not feasible; when velocities exceed their
    limits it suggests a longer duration (given the scenario); with the anytime SQP it says
    what its re-plans had: their quality is what that CPU buys on this machine
    (docs/realtime.md, 'harness.commands.plan'), and whether the penalty loop was tried too
    (both: planning.planners.executed's either)."""
    message = "no feasible plan: " + "; ".join(problems)
    if (scenario is not None and config.velocity_limit is not None
            and any(" velocity " in p for p in problems)):
        message += f" (the velocity limits: {_longer_duration(config, scenario)})"
    elif uses_anytime(config):
        clock = "CPU" if config.anytime.iteration_ms is None else "nominal time"
        hint = ("a larger --replan-budget-ms may find one; the penalty loop's execution "
                "(--replanner fatrop) did not keep the threshold either" if both else
                "a larger --replan-budget-ms or --replanner fatrop may find one")
        message += (f" (the anytime SQP re-planned within {config.anytime.replan_budget_ms:g} ms of "
                    f"{clock}: {hint})")
    return message


def torque_diagnosis(planner: Planner, scenario: Scenario) -> str | None:
    """A one-line reason when the torque limits are what make the goal unreachable: the
    torque-limited problem has no solution and the unobstructed optimum without limits
    needs more torque than a motor has."""
    config, model = planner.config, planner.model
    if config.torque_limit is None:
        return None
    segment = Segment.of(scenario)
    limited = planner.solve(segment)
    # within the limits as a plan's result counts them (a plan that passes between the NLP's
    # samples by less than planning.result's tolerance reaches the goal)
    t = np.linspace(0.0, scenario.duration, 201)
    if limited.success and not torque_problems(
            np.abs(model.torque(*limited.trajectory.state(t))).max(axis=0), config.torque_limit):
        return None
    free = Planner(model, dataclasses.replace(config, torque_limit=None)).solve(segment)
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
        self.seconds = 0.0  # compiling, all stages, on any stderr (compiled_note)
        self._stage_began: float | None = None

    def emit(self, record) -> None:
        stage = getattr(record, "stage", None)
        if stage is None:
            return
        now = time.perf_counter()
        if record.done and self._stage_began is not None:
            self.seconds += now - self._stage_began
        self._stage_began = None if record.done else now
        if not sys.stderr.isatty():
            return
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

    def compiled_note(self) -> str:
        """'' when nothing was compiled, else what compiling took of this run (the first plan
        on a robot compiles its planner once; later plans load it)."""
        if self.seconds <= 0:
            return ""
        return (f"; compiling the planner took {self.seconds:.1f} s of this run (the first "
                f"plan for {self.robot}: later plans reuse it)")

    def _head(self) -> str:
        joints = "" if self.joints is None else f" ({self.joints} joints)"
        return f"torquebench: compiling the planner for {self.robot}{joints}"


def fallback_note(asked: str, used: str, followed: bool) -> None:
    """One note on stderr when the execution with re-plans is the other re-planner's
    (planning.planners.executed, either): the one asked for did not keep the threshold."""
    if used != asked and not followed:
        print(f"note: the {JSON_NAMES[asked]} re-planner's execution did not keep the "
              f"threshold; this plan is the {JSON_NAMES[used]} re-planner's (its re-plans "
              f"are not bounded in time; --replanner {JSON_NAMES[asked]} to get the error)",
              file=sys.stderr)


def search_failure_note(failures: int) -> None:
    """One note on stderr when global searches in the other process failed (--realtime):
    the re-plans went on without them (PLAN.json's global_search.failures)."""
    if failures:
        print(f"note: {failures} global search{'es' if failures > 1 else ''} in the other "
              f"process failed; the re-plans went on without {'them' if failures > 1 else 'it'} "
              "(PLAN.json's global_search.failures)", file=sys.stderr)


def first_plan_note(fallback: str | None) -> None:
    """One note on stderr when the first plan is the other method's (planning.offline): the
    method planning the segments found no feasible first plan."""
    if fallback:
        print(f"note: the first plan is the {fallback} method's: the re-planner's own first "
              "plan was not feasible (PLAN.json's first_plan_fallback)", file=sys.stderr)
