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
far from the obstacle share the empty class."""

from __future__ import annotations

import numpy as np

from planning.formulation.kinematics import ArmGeometry

SIDES = (("beyond", "before"), ("left", "right"), ("above", "below"))
NEAR = 0.02  # m above the threshold within which a link's side counts: the links that bind


def sides(geometry: ArmGeometry, q: np.ndarray, centres: np.ndarray, threshold: float,
          near: float = NEAR) -> tuple[tuple[int, str], ...]:
    """The class (link, side) of the poses q (n, dof) passing obstacle centres (n, 3) at
    the same times."""
    q, centres = np.atleast_2d(q), np.reshape(centres, (-1, 3))
    if not len(q):
        return ()
    a, b = geometry.link_ends(q)  # (n, links, 3)
    c = centres[:, None, :]
    ab, ac = b - a, c - a
    s = np.clip(np.einsum("nli,nli->nl", ac, ab) /
                np.maximum(np.einsum("nli,nli->nl", ab, ab), 1e-300), 0.0, 1.0)
    nearest = a + s[..., None] * ab  # (n, links, 3)
    offset = nearest - c
    distance = np.linalg.norm(offset, axis=-1)
    if geometry.radii:
        distance = distance - geometry.link_radii
    base = geometry.points(q[:1])[0, 0]
    found = []
    for link in range(distance.shape[1]):
        k = int(np.argmin(distance[:, link]))
        if distance[k, link] > threshold + near:
            continue
        radial = centres[k] - base
        radial[2] = 0.0
        norm = np.linalg.norm(radial)
        radial = radial / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])
        up = np.array([0.0, 0.0, 1.0])
        frame = np.stack([radial, np.cross(up, radial), up])
        components = frame @ offset[k, link]
        axis = int(np.argmax(np.abs(components)))
        found.append((link, SIDES[axis][0 if components[axis] >= 0 else 1]))
    return tuple(found)


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
    """Whether two classes are one way round: no link they both bring near passes on opposite
    sides (above and below, left and right, beyond and before), and they share a link near
    the obstacle, or neither brings one near. A link passing above in one and left in the
    other is one diagonal pass; two motions whose near links differ wholly go round
    differently."""
    if not first or not second:
        return not first and not second
    sides_of = dict(first)
    shared = [(link, side) for link, side in second if link in sides_of]
    return bool(shared) and all(OPPOSITE[side] != sides_of[link] for link, side in shared)


def label(found: tuple) -> str:
    """A class as words: "link 2 above, link 3 left" ("clear of the obstacle": none near)."""
    return ", ".join(f"link {link + 1} {side}" for link, side in found) or \
        "clear of the obstacle"
