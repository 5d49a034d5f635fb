"""Named scenarios: the paper's, one whose obstacle crosses the optimal path, and one whose
obstacle also sways (constant-velocity prediction is never exact: repeated re-planning)."""

from __future__ import annotations

import numpy as np

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
