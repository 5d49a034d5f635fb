"""The homotopy class of a motion around the obstacle (de Groot, Ferranti, Gavrila &
Alonso-Mora, "Topology-Driven Parallel Trajectory Optimization in Dynamic Environments",
IEEE T-RO 2024, for an arm): which side each link passes the obstacle on.

For every link that comes within `near` of the threshold on the forecast, the side is read
at its closest approach: the direction from the obstacle's centre to the link's nearest
point, in a frame of the arm's own: radial (the horizontal direction from the arm's base to
the obstacle: "beyond" or "before" it), tangential ("left" or "right" of it, seen from the
base) and vertical ("above" or "below"). The side is the frame axis the direction lies
nearest, with its sign: a sign pattern reduced to its dominant term, so a motion that
passes the obstacle diagonally does not flip class with a millimetre's change. A class is
the tuple of (link, side) of the links that come near; the motions that keep every link
far from the obstacle share the empty class.

The sides alone read a base that turns away from the obstacle and waits like one that goes
straight on and lifts its links clear: both pass it on one side at their closest approach.
A motion that comes near therefore also carries its base's way (joint 1, about the
vertical): turned away when, before its closest approach, the base backs off against its way
to the goal (the motion's last sample) by more than TURN, a whole swing, not a millimetre's
(docs/realtime.md, 'The base's way')."""

from __future__ import annotations

import functools
import math

import casadi as ca
import numpy as np

from planning.formulation import compiled
from planning.formulation.clearance import link_offsets
from planning.formulation.kinematics import ArmGeometry

SIDES = (("beyond", "before"), ("left", "right"), ("above", "below"))
NEAR = 0.02  # m above the threshold within which a link's side counts: the links that bind
# rad the base must back off against its way to the goal to read turned away: the plans
# offered on the development scenario 4 (seed 9784) that turn away back off by 0.5 rad or
# more, those that go straight by none (docs/realtime.md, 'The base's way')
TURN = 0.4
BASE, AWAY = "base", "turned away"


def sides(geometry: ArmGeometry, q: np.ndarray, centres: np.ndarray, threshold: float,
          near: float = NEAR) -> tuple[tuple[int, str], ...]:
    """The class (link, side) of the poses q (n, dof) passing obstacle centres (n, 3) at
    the same times."""
    q, centres = np.atleast_2d(q), np.reshape(centres, (-1, 3))
    if not len(q):
        return ()
    offset = link_offsets(geometry, q, centres)  # (n, links, 3)
    distance = np.linalg.norm(offset, axis=-1)
    if geometry.radii:
        distance = distance - geometry.link_radii
    base = geometry.points(q[:1])[0, 0]
    found, closest = [], []
    for link in range(distance.shape[1]):
        k = int(np.argmin(distance[:, link]))
        if distance[k, link] <= threshold + near:
            found.append((link, _side(base, centres[k], offset[k, link])))
            closest.append((distance[k, link], k))
    return _with_base(geometry, tuple(found), closest, lambda: q[:, 0])


def turned_away(angles: np.ndarray, closest: int, turn: float = TURN) -> bool:
    """Whether a base whose angles (n,) run from the motion's start to its goal backs off
    against its way to the goal (start to last sample) by more than turn (rad) up to sample
    `closest` (the closest approach): a base that does not move counts its way as positive."""
    angles = np.asarray(angles, float)
    way = 1.0 if angles[-1] >= angles[0] else -1.0
    return float(np.max(-way * (angles[: closest + 1] - angles[0]), initial=0.0)) > turn


def _with_base(geometry: ArmGeometry, found: tuple, closest: list, angles) -> tuple:
    """found with the base's way appended when it turned away before the closest approach
    (closest: (clearance, sample) of each near link; angles() -> joint 1's angles (n,) at
    every sample), if the arm's joint 1 turns about the vertical."""
    if not found or not _base_turns(geometry):
        return found
    return found + ((BASE, AWAY),) if turned_away(angles(), min(closest)[1]) else found


@functools.cache
def _base_turns(geometry: ArmGeometry) -> bool:
    """Whether joint 1 turns about the vertical (its axis in the world within 8 degrees)."""
    axis = np.asarray(geometry.rotations[0]) @ np.asarray(geometry.axes[0])
    return abs(float(axis[2])) > math.cos(math.radians(8.0))


def _side(base: np.ndarray, centre: np.ndarray, offset: np.ndarray) -> str:
    """The side a link passes the obstacle centred at `centre` on: offset (3,) from the
    centre to the link's nearest point, read in the frame of the horizontal from the arm's
    base to the centre (radial, tangential: up x radial, and up), reduced to its dominant
    axis."""
    x, y = float(centre[0] - base[0]), float(centre[1] - base[1])
    norm = math.hypot(x, y)
    x, y = (x / norm, y / norm) if norm > 1e-9 else (1.0, 0.0)
    components = (x * offset[0] + y * offset[1], -y * offset[0] + x * offset[1], offset[2])
    axis = max(range(3), key=lambda i: abs(components[i]))
    return SIDES[axis][0 if components[axis] >= 0 else 1]


def near_sides(geometry: ArmGeometry, links: np.ndarray, position, centres: np.ndarray,
               threshold: float, near: float = NEAR, angles=None) -> tuple:
    """`sides` from each link's clearances already known, links (n, links) at the n samples
    of centres (n, 3): each link's closest approach read off them, the arm's pose
    (position(k): q (dof,) at sample k) computed only at the samples where a link comes
    near, and joint 1's angles at every sample (angles() -> (n,); default: from position)
    only if one does (the same class as `sides` on every sample, to the clearances'
    rounding)."""
    if not len(links):
        return ()
    found, near_links, closest = [], [], np.argmin(links, axis=0)
    base, ends = _frame(geometry)
    radii = geometry.link_radii
    for link, k in enumerate(closest.tolist()):
        if links[k, link] > threshold + near:
            continue
        a, b = np.reshape(ends(position(k))[0], (2, -1, 3))[:, link]
        ab, centre = b - a, centres[k]
        s = min(max(float((centre - a) @ ab) / max(float(ab @ ab), 1e-300), 0.0), 1.0)
        offset = a + s * ab - centre
        if math.sqrt(float(offset @ offset)) - radii[link] <= threshold + near:
            found.append((link, _side(base, centre, offset)))
            near_links.append((float(links[k, link]), k))
    if angles is None:
        angles = lambda: np.array([position(k)[0] for k in range(len(links))])  # noqa: E731
    return _with_base(geometry, tuple(found), near_links, angles)


@functools.cache
def _frame(geometry: ArmGeometry) -> tuple:
    """The arm's base (joint 1's origin: no joint moves it) and its link ends as a function
    of q (dof,) -> (2 * links * 3,): every link's a ends, then its b ends (CasADi, built once
    per arm)."""
    q = ca.SX.sym("q", geometry.dof)
    ends = geometry.symbolic_link_ends(q)
    function = ca.Function("link_ends", [q], [ca.vertcat(*[a for a, _ in ends],
                                                         *[b for _, b in ends])])
    return geometry.points(np.zeros((1, geometry.dof)))[0, 0], compiled.Buffered(function)


def motion_class(geometry: ArmGeometry, trajectory, forecast, threshold: float,
                 t_begin: float | None = None, near: float = NEAR) -> tuple:
    """The class of a motion (planning.formulation.trajectory) on an obstacle forecast
    (planning.types.ObstacleForecast) from t_begin (default: the motion's start) on."""
    if forecast is None:
        return ()
    times = np.asarray(forecast.times, float)
    start = trajectory.t_begin if t_begin is None else t_begin
    keep = (times > start + 1e-12) & (times <= trajectory.t_end + 1e-12)
    if not np.any(keep):
        return ()
    return sides(geometry, trajectory.position(times[keep]),
                 np.asarray(forecast.centres)[keep], threshold, near)


OPPOSITE = {side: pair[1 - k] for pair in SIDES for k, side in enumerate(pair)}


def same_class(first: tuple, second: tuple) -> bool:
    """Whether two classes are one way round: the base turned away in both or in neither, no
    link they both bring near passes on opposite sides (above and below, left and right,
    beyond and before), and they share a link near the obstacle, or neither brings one near.
    A link passing above in one and left in the other is one diagonal pass; two motions
    whose near links differ wholly go round differently."""
    if ((BASE, AWAY) in first) != ((BASE, AWAY) in second):
        return False
    first, second = _links(first), _links(second)
    if not first or not second:
        return not first and not second
    sides_of = dict(first)
    shared = [(link, side) for link, side in second if link in sides_of]
    return bool(shared) and all(OPPOSITE[side] != sides_of[link] for link, side in shared)


def _links(found: tuple) -> tuple:
    return tuple(entry for entry in found if entry[0] != BASE)


def label(found: tuple) -> str:
    """A class as words: "link 2 above, link 3 left", ", base turned away" after them if it
    did ("clear of the obstacle": none near)."""
    words = [f"link {link + 1} {side}" for link, side in _links(found)]
    return ", ".join(words + [f"{BASE} {AWAY}"] * ((BASE, AWAY) in found)) or \
        "clear of the obstacle"
