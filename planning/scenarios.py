"""Named scenarios: the paper's, one whose obstacle crosses the optimal path, and one whose
obstacle also sways (constant-velocity prediction is never exact: repeated re-planning)."""

from __future__ import annotations

import numpy as np

from planning.clearance import link_clearances
from planning.config import Scenario
from planning.obstacle import LinearObstacle, SwayingObstacle
from planning.trajectory import PolynomialTrajectory


def paper_scenario() -> Scenario:
    """q0 = (pi/2, pi/5, -pi/4) to (-pi/2, 2pi/5, -pi/3) in 2 s; obstacle as in the paper."""
    return Scenario()


def crossing_scenario(free: PolynomialTrajectory, geometry, t_cross: float = 1.0,
                      sweep: tuple[float, float, float] = (0.0, 0.0, 0.5)) -> Scenario:
    """The paper's motion with an obstacle that passes exactly through the middle of the
    forearm (elbow-end effector) of the unobstructed optimum `free` at t_cross (s),
    moving at constant velocity `sweep` (m per motion duration) centred on t_cross."""
    base = Scenario()
    _, elbow, end = geometry.points(free.state(t_cross)[0])
    crossing = 0.5 * (elbow[0] + end[0])
    frac = t_cross / base.duration
    start = crossing - frac * np.asarray(sweep)
    stop = crossing + (1 - frac) * np.asarray(sweep)
    obstacle = LinearObstacle(tuple(start), tuple(stop), base.duration)
    return Scenario(base.start, base.goal, base.duration, obstacle)


def swaying_scenario(free: PolynomialTrajectory, geometry, amplitude: float = 0.04,
                     periods: float = 1.0) -> Scenario:
    """The crossing scenario's obstacle swaying sideways (horizontal, perpendicular to the
    forearm of `free` at the crossing) by `amplitude` (m), `periods` times over the motion;
    with whole periods it still passes through the forearm's middle at t = 1 s."""
    base = crossing_scenario(free, geometry)
    _, elbow, end = geometry.points(free.state(1.0)[0])
    forearm = (end - elbow)[0]
    side = np.array([-forearm[1], forearm[0], 0.0])
    sway = amplitude * side / np.linalg.norm(side)
    obstacle = SwayingObstacle(base.obstacle.start, base.obstacle.end, base.duration,
                               sway=tuple(sway), periods=periods)
    return Scenario(base.start, base.goal, base.duration, obstacle)


def random_scenario(rng: np.random.Generator, free_motion, geometry, lower, upper,
                    threshold: float = 0.08, duration: float = 2.0) -> Scenario:
    """A scenario drawn from rng whose obstacle is active: start and goal uniform in the
    middle 80 % of each joint's range (>= 0.6 rad apart on joint 1), an obstacle that passes
    within 3 cm of the middle part of a link of the unobstructed optimum
    (`free_motion(start, goal, duration)` -> PolynomialTrajectory) at a random time in
    [0.3, 0.7] duration, moving at 0.1-0.4 m per motion in a random direction, and swaying
    0-4 cm at 0.5-2 periods per motion; redrawn until start and goal are clear of it."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    while True:
        start, goal = (lower + (upper - lower) * rng.uniform(0.1, 0.9, len(lower))
                       for _ in range(2))
        if abs(goal[0] - start[0]) < 0.6:
            continue
        free = free_motion(tuple(start), tuple(goal), duration)
        t_cross = duration * rng.uniform(0.3, 0.7)
        points = geometry.points(free.position(t_cross))
        link = rng.integers(1, 3)  # 1: upper arm, 2: forearm
        along = rng.uniform(0.4, 0.9)
        crossing = points[link - 1][0] + along * (points[link][0] - points[link - 1][0])
        crossing = crossing + rng.normal(0.0, 0.015, 3)
        sweep = _direction(rng) * rng.uniform(0.1, 0.4)
        frac = t_cross / duration
        obstacle = SwayingObstacle(_floats(crossing - frac * sweep),
                                   _floats(crossing + (1 - frac) * sweep), duration,
                                   sway=_floats(_direction(rng) * rng.uniform(0.0, 0.04)),
                                   periods=float(rng.uniform(0.5, 2.0)))
        ends = np.asarray([start, goal])
        centres = obstacle.position(np.array([0.0, duration]))
        if link_clearances(geometry, ends, centres).min() > threshold + 0.02:
            return Scenario(_floats(start), _floats(goal), duration, obstacle)


def random_scenarios(count: int, seed: int, free_motion, geometry, lower, upper,
                     threshold: float = 0.08) -> list[Scenario]:
    """`count` scenarios of random_scenario from one seed."""
    rng = np.random.default_rng(seed)
    return [random_scenario(rng, free_motion, geometry, lower, upper, threshold)
            for _ in range(count)]


def _direction(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def _floats(v) -> tuple[float, ...]:
    return tuple(float(x) for x in v)
