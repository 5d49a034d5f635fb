"""A robot's designed excitation (identification.excitation.design) and its CSV file.

The glue the design needs from the robot: its joint limits (MuJoCo's positions, the URDF's
speeds, the user's acceleration limit), the identification's columns (the robot's kinematic
base atoms with armature, viscous and Coulomb atoms, plus an offset per joint) and a
collision check. Collisions are checked on capsules along the planner's links (joint origin
to joint origin; the registry's robots lose their meshes when loaded): radius
CAPSULE_FRACTION of the arm's reach (at least the Lynxmotion's LINK_RADIUS), between links
that share no joint and do not touch at q = 0, and against the floor (z = 0 unless given; none
for an arm not standing on one, a humanoid's) for every link end a joint moves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from harness.data.excitation_file import Trajectory
from harness.data.generate import CONDITION_POINTS, SAMPLE_RATE, condition_number, default_excitation
from harness.errors import UserError
from harness.robots.arm import Arm
from harness.robots.scene import LINK_RADIUS
from identification.excitation.design import ExcitationDesign, ExcitationLimits, optimize_excitation
from identification.excitation.regressor import AtomRegressor

CAPSULE_FRACTION = 0.05  # of the reach: about the UR5's and the Panda's link radii
DEFAULT_ACCELERATION = 10.0  # rad/s^2
ITERATIONS = 60  # SLSQP's, at most: about two minutes for a 7-joint arm at 20 harmonics
# the highest harmonic near 1 Hz, generate's default excitation's top: at 0.5 Hz the error
# predicted on other motions was larger under both noise models, and slower excitations left
# inertia weak against torque noise (docs/identification.md, 'Top frequency')
TOP_FREQUENCY, HARMONICS, MAX_HARMONICS = 1.0, (5, 20), 20  # Hz, default range, most allowed


@dataclass(frozen=True)
class DesignedExcitation:
    """A robot's design, its written samples, and the conditions of the designed and of
    generate's default excitation on the same columns and duration."""

    design: ExcitationDesign
    trajectory: Trajectory
    condition: float
    default_condition: float
    limits: ExcitationLimits


def capsule_radius(arm: Arm) -> float:
    """The radius (m) of the capsules the design keeps apart (see the module docstring)."""
    return max(LINK_RADIUS, CAPSULE_FRACTION * float(sum(arm.geometry.link_lengths)))


def capsule_clearance(arm: Arm, floor: float | None = 0.0):
    """clearance(q (n, dof)) -> (n,): the smallest distance (m) between the arm's capsules
    and between them and the floor at height floor (m; None: no floor; see the module
    docstring); <= 0: touching."""
    geometry = arm.geometry
    links = np.array(geometry.links)
    radius = capsule_radius(arm)
    home = geometry.points(np.zeros(geometry.dof))
    pairs = [(a, b) for a in range(len(links)) for b in range(a + 1, len(links))
             if not set(links[a]) & set(links[b])
             and _segment_distance(home, links[a], links[b])[0] > 2 * radius]
    moving = _moving(geometry)

    def clearance(q: np.ndarray) -> np.ndarray:
        points = geometry.points(q)
        gap = np.full(len(points), np.inf) if floor is None else \
            np.min(points[:, moving, 2], axis=1) - floor - radius
        for a, b in pairs:
            gap = np.minimum(gap, _segment_distance(points, links[a], links[b]) - 2 * radius)
        return gap

    return clearance


def _segment_distance(points: np.ndarray, a, b) -> np.ndarray:
    """Distance (n,) between the segments points[:, a[0]]-points[:, a[1]] and likewise b."""
    p, q = points[:, a[0]], points[:, b[0]]
    d1, d2, r = points[:, a[1]] - p, points[:, b[1]] - q, p - q
    aa, ee = np.sum(d1 * d1, 1), np.sum(d2 * d2, 1)
    bb, c, f = np.sum(d1 * d2, 1), np.sum(d1 * r, 1), np.sum(d2 * r, 1)
    denom = np.maximum(aa * ee - bb * bb, 1e-18)
    s = np.clip((bb * f - c * ee) / denom, 0, 1)
    t = np.clip((bb * s + f) / np.maximum(ee, 1e-18), 0, 1)
    s = np.clip((bb * t - c) / np.maximum(aa, 1e-18), 0, 1)
    return np.linalg.norm(p + d1 * s[:, None] - q - d2 * t[:, None], axis=1)


def default_harmonics(duration: float) -> int:
    """Harmonics whose highest is near TOP_FREQUENCY over a period of duration s, within
    HARMONICS."""
    return int(np.clip(round(duration * TOP_FREQUENCY), *HARMONICS))


def excitation_limits(arm: Arm, acceleration: float) -> ExcitationLimits:
    lo, hi = arm.position_limits
    return ExcitationLimits(lo, hi, arm.speed_bounds, np.full(arm.dof, acceleration))


def design_for(arm: Arm, duration: float, rate: float, acceleration: float = DEFAULT_ACCELERATION,
               seed: int = 0, iterations: int = ITERATIONS,
               harmonics: int | None = None, criterion: str = "information",
               floor: float | None = 0.0, progress=None) -> DesignedExcitation:
    """The arm's designed excitation sampled at rate (Hz) over [0, duration] s, ends
    included (both at rest), with `harmonics` (default default_harmonics(duration)), optimal
    for `criterion` (identification.excitation.criteria.CRITERIA), every moving link above
    the floor at height floor (m; None: no floor); progress(iteration, iterations) after each
    of the optimizer's iterations; UserError on bad input or if it cannot be made
    collision-free."""
    for name, value in (("--duration", duration), ("--rate", rate), ("--accel-limit", acceleration)):
        if not np.isfinite(value) or value <= 0:
            raise UserError(f"{name} must be a finite number > 0, got {value:g}")
    if floor is not None and not np.isfinite(floor):
        raise UserError(f"--floor must be a finite height (m) or 'none', got {floor:g}")
    if duration * rate < 2:
        raise UserError(f"--duration x --rate must give at least 2 samples, got {duration * rate:g}")
    harmonics = default_harmonics(duration) if harmonics is None else harmonics
    if not 1 <= harmonics <= MAX_HARMONICS:
        raise UserError(f"--harmonics must be between 1 and {MAX_HARMONICS}, got {harmonics}")
    limits = excitation_limits(arm, acceleration)
    regressor = AtomRegressor(arm.library)
    clearance = capsule_clearance(arm, floor)
    try:
        design = optimize_excitation(limits, duration, regressor, clearance, seed,
                                     harmonics=harmonics, iterations=iterations,
                                     criterion=criterion, progress=progress,
                                     # checked at the samples written (a design pressed to its
                                     # limits may pass 1000 points and miss between them)
                                     check_points=max(1000, int(round(duration * rate))))
    except ValueError as exc:
        raise UserError(f"robot {arm.label}: {exc}") from None
    t = np.arange(int(round(duration * rate)) + 1) / rate
    trajectory = Trajectory(t, *design.excitation.evaluate(t))
    states = (trajectory.q, trajectory.qd, trajectory.qdd)
    if np.any(clearance(trajectory.q) <= 0) or limits.violation(*states) > 1e-9:
        raise UserError(f"robot {arm.label}: the designed excitation touches a link or a limit at "
                        "the written samples; try another --seed or a longer --duration")
    grid = np.linspace(0.0, duration, CONDITION_POINTS, endpoint=False)
    default, _ = default_excitation(arm, max(int(round(duration * SAMPLE_RATE)), 10), seed)
    return DesignedExcitation(design, trajectory,
                              condition_number(arm, *design.excitation.evaluate(grid)),
                              condition_number(arm, *default.evaluate(grid)), limits)


def floor_below_home(arm: Arm, floor: float | None) -> float | None:
    """The height (m) of the lowest moving link end at q = 0 when it lies below the floor by
    more than the capsule radius (the arm at home is not standing on that floor: a humanoid's
    arm, one hung from a ceiling), else None."""
    if floor is None:
        return None
    geometry = arm.geometry
    lowest = float(np.min(geometry.points(np.zeros((1, geometry.dof)))[0, _moving(geometry), 2]))
    return lowest if lowest < floor - capsule_radius(arm) else None


def _moving(geometry) -> list[int]:
    """The link end points a joint moves (those the floor must stay below)."""
    return sorted(set(np.array(geometry.links).ravel()) - set(geometry.fixed_points))
