"""Named scenarios: the paper's, one whose obstacle crosses the optimal path, and one whose
obstacle also sways (constant-velocity prediction is never exact: repeated re-planning)."""

from __future__ import annotations

import numpy as np

from planning.config import Scenario
from planning.kinematics import ArmGeometry
from planning.obstacle import LinearObstacle, SwayingObstacle
from planning.trajectory import PolynomialTrajectory


def paper_scenario() -> Scenario:
    """q0 = (pi/2, pi/5, -pi/4) to (-pi/2, 2pi/5, -pi/3) in 2 s; obstacle as in the paper."""
    return Scenario()


def _link_ends(free: PolynomialTrajectory, geometry: ArmGeometry, t: float, link: int):
    """Both ends (3,) of link `link` (index into geometry.links) of `free` at time t (s)."""
    points = geometry.points(free.state(t)[0])[0]
    i, j = geometry.links[link]
    return points[i], points[j]


def crossing_scenario(free: PolynomialTrajectory, geometry: ArmGeometry, t_cross: float = 1.0,
                      sweep: tuple[float, float, float] = (0.0, 0.0, 0.5),
                      base: Scenario | None = None, link: int = -1) -> Scenario:
    """base's motion (default: the paper's) with an obstacle that passes exactly through the
    middle of one moving link (default the last: the Lynxmotion's forearm) of the
    unobstructed optimum `free` at t_cross (s), moving at constant velocity `sweep` (m per
    motion duration) centred on t_cross."""
    base = base or Scenario()
    crossing = 0.5 * np.add(*_link_ends(free, geometry, t_cross, link))
    frac = t_cross / base.duration
    start = crossing - frac * np.asarray(sweep)
    stop = crossing + (1 - frac) * np.asarray(sweep)
    obstacle = LinearObstacle(tuple(start), tuple(stop), base.duration)
    return Scenario(base.start, base.goal, base.duration, obstacle, base.start_velocity)


def swaying_scenario(free: PolynomialTrajectory, geometry: ArmGeometry, amplitude: float = 0.04,
                     periods: float = 1.0, base: Scenario | None = None,
                     link: int = -1) -> Scenario:
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
