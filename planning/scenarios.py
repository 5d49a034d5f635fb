"""Scenarios built on a robot's motion: one whose obstacle crosses the optimal path, one whose
obstacle also sways (constant-velocity prediction is never exact: repeated re-planning), and
random ones (the paper's scenario: harness.paper.planning.scenario)."""

from __future__ import annotations

import numpy as np

from planning.config import Scenario
from planning.formulation.clearance import link_clearances
from planning.formulation.kinematics import ArmGeometry
from planning.formulation.obstacle import LinearObstacle, SwayingObstacle
from planning.formulation.trajectory import PolynomialTrajectory


def _link_ends(free: PolynomialTrajectory, geometry: ArmGeometry, t: float, link: int):
    """Both ends (3,) of link `link`'s capsule axis (index into geometry.links) of `free` at
    time t (s)."""
    a, b = geometry.link_ends(free.state(t)[0])
    return a[0, link], b[0, link]


def crossing_scenario(free: PolynomialTrajectory, geometry: ArmGeometry, base: Scenario,
                      t_cross: float = 1.0, sweep: tuple[float, float, float] = (0.0, 0.0, 0.5),
                      link: int = -1) -> Scenario:
    """base's motion with an obstacle that passes exactly through the
    middle of one moving link (default the last: the Lynxmotion's forearm) of the
    unobstructed optimum `free` at t_cross (s), moving at constant velocity `sweep` (m per
    motion duration) centred on t_cross."""
    crossing = 0.5 * np.add(*_link_ends(free, geometry, t_cross, link))
    frac = t_cross / base.duration
    start = crossing - frac * np.asarray(sweep)
    stop = crossing + (1 - frac) * np.asarray(sweep)
    obstacle = LinearObstacle(tuple(start), tuple(stop), base.duration)
    return Scenario(base.start, base.goal, base.duration, obstacle, base.start_velocity)


def swaying_scenario(free: PolynomialTrajectory, geometry: ArmGeometry, base: Scenario,
                     amplitude: float = 0.04, periods: float = 1.0, link: int = -1) -> Scenario:
    """The crossing scenario's obstacle swaying sideways (horizontal, perpendicular to the
    crossed link of `free` at the crossing) by `amplitude` (m), `periods` times over the
    motion; with whole periods it still passes through the link's middle at t = 1 s."""
    base = crossing_scenario(free, geometry, base=base, link=link)
    a, b = _link_ends(free, geometry, 1.0, link)
    along = b - a
    side = np.array([-along[1], along[0], 0.0])
    sway = amplitude * side / np.linalg.norm(side)
    obstacle = SwayingObstacle(base.obstacle.start, base.obstacle.end, base.duration,
                               sway=tuple(sway), periods=periods)
    return Scenario(base.start, base.goal, base.duration, obstacle, base.start_velocity)


def random_scenario(rng: np.random.Generator, free_motion, geometry: ArmGeometry, lower, upper,
                    threshold: float = 0.08, duration: float = 2.0) -> Scenario:
    """A scenario drawn from rng whose obstacle is active: start and goal uniform in the
    middle 80 % of each joint's range (>= 0.6 rad apart on joint 1), an obstacle that passes
    about 1.5 cm from the outer part of a moving link of the unobstructed optimum
    (`free_motion(start, goal, duration)` -> PolynomialTrajectory) at a random time in
    [0.3, 0.7] duration, moving at 0.1-0.4 m per motion in a random direction, and swaying
    0-4 cm at 0.5-2 periods per motion; redrawn until start and goal are clear of it and it
    stays clear of the points of the arm no joint moves (geometry.fixed_points: the
    Lynxmotion's shoulder; an obstacle that passes there leaves no feasible plan)."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    while True:
        start, goal = (lower + (upper - lower) * rng.uniform(0.1, 0.9, len(lower))
                       for _ in range(2))
        if abs(goal[0] - start[0]) < 0.6:
            continue
        free = free_motion(tuple(start), tuple(goal), duration)
        t_cross = duration * rng.uniform(0.3, 0.7)
        a, b = _link_ends(free, geometry, t_cross, int(rng.integers(len(geometry.links))))
        crossing = a + rng.uniform(0.4, 0.9) * (b - a)
        crossing = crossing + rng.normal(0.0, 0.015, 3)
        sweep = _direction(rng) * rng.uniform(0.1, 0.4)
        frac = t_cross / duration
        obstacle = SwayingObstacle(_floats(crossing - frac * sweep),
                                   _floats(crossing + (1 - frac) * sweep), duration,
                                   sway=_floats(_direction(rng) * rng.uniform(0.0, 0.04)),
                                   periods=float(rng.uniform(0.5, 2.0)))
        ends = np.asarray([start, goal])
        centres = obstacle.position(np.array([0.0, duration]))
        if link_clearances(geometry, ends, centres).min() > threshold + 0.02 and \
                _fixed_clearance(geometry, obstacle) > threshold + 0.02:
            return Scenario(_floats(start), _floats(goal), duration, obstacle)


def _fixed_clearance(geometry: ArmGeometry, obstacle) -> float:
    """Closest approach (m) of the obstacle's centre, at its sample times and t = 0, to the
    arm's fixed link ends (inf if none)."""
    fixed = geometry.points(np.zeros(geometry.dof))[0][list(geometry.fixed_points)]
    centres = obstacle.position(np.concatenate([[0.0], obstacle.sample_times]))
    return float(np.linalg.norm(centres[:, None, :] - fixed[None], axis=2).min(initial=np.inf))


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
