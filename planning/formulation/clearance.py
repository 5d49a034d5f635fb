"""Distance from an obstacle centre to the arm's link segments (paper eq. 16, as segments).

The paper's code measured the distance to the infinite line through a link;
here it is the distance to the segment (each moving link's capsule axis,
planning.formulation.kinematics.ArmGeometry.link_ends: between consecutive joint origins and
to the flange, or body-fixed ends of a capsule fitted to the link's meshes; on the
Lynxmotion shoulder-elbow and elbow-end effector), minus the capsule's radius,
via the clamped projection. The distance to a segment is continuously
differentiable away from the segment itself (the clamp only switches where
its derivative does not matter), which is enough for IPOPT with a quadratic
exterior penalty. Units: metres.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from planning.formulation.kinematics import ArmGeometry


def segment_distance(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance (...) from points (..., 3) to segments a-b (..., 3 each, broadcast); a
    zero-length segment is its point."""
    ab, ap = b - a, point - a
    t = np.einsum("...i,...i->...", ap, ab) / np.maximum(np.einsum("...i,...i->...", ab, ab),
                                                          1e-300)
    return np.linalg.norm(ap - np.clip(t, 0.0, 1.0)[..., None] * ab, axis=-1)


def symbolic_segment_toward(point, a, b, length: float):
    """CasADi vector from the nearest point of segment a-b of known constant length (m; 0:
    the point a) to point."""
    if length == 0:
        return point - a
    ab = b - a
    t = ca.fmin(ca.fmax(ca.dot(point - a, ab) / length**2, 0.0), 1.0)
    return point - a - t * ab


def symbolic_segment_distance(point, a, b, length: float):
    """CasADi distance from point to segment a-b of known constant length (m; 0: the point
    a)."""
    return ca.norm_2(symbolic_segment_toward(point, a, b, length))


def link_offsets(geometry: ArmGeometry, q: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """(n, links, 3) from obstacle centres (n, 3) to each link's nearest point on its capsule
    axis at joint angles q (n, dof) (m)."""
    a, b = geometry.link_ends(q)
    c = np.reshape(centres, (-1, 1, 3))
    ab = b - a
    s = np.clip(np.einsum("nli,nli->nl", c - a, ab) /
                np.maximum(np.einsum("nli,nli->nl", ab, ab), 1e-300), 0.0, 1.0)
    return a + s[..., None] * ab - c


def link_clearances(geometry: ArmGeometry, q: np.ndarray, obstacle: np.ndarray) -> np.ndarray:
    """Distances (n, links) of obstacle centres (n, 3) or (3,) to each link of the arm
    (geometry.links: to its capsule's surface, geometry.radii) at joint angles q (n, dof)."""
    a, b = geometry.link_ends(q)
    centres = np.reshape(obstacle, (-1, 1, 3))  # (n or 1, 1, 3): one centre per row of q
    distance = segment_distance(centres, a, b)
    return distance - geometry.link_radii if geometry.radii else distance


def symbolic_link_clearances(geometry: ArmGeometry, q, obstacle) -> list:
    """CasADi distances of an obstacle centre to each link (its capsule's surface) at joint
    vector q."""
    return [symbolic_segment_distance(obstacle, a, b, length) - radius
            if radius else symbolic_segment_distance(obstacle, a, b, length)
            for (a, b), length, radius in zip(geometry.symbolic_link_ends(q),
                                              geometry.link_lengths, geometry.link_radii,
                                              strict=True)]


def guided_link_clearances(geometry: ArmGeometry, q, obstacle, normals) -> list:
    """symbolic_link_clearances, each link's distance replaced by its offset from the centre
    along its guidance normal where it has one (normals: 3 per link, unit or zero): n'(p - c)
    minus the radius, p the link's nearest point. n'(p - c) <= |p - c|, so a guided row that
    holds keeps the link clear, on n's side of the obstacle: the linear guidance that holds a
    plan in its class (planning.formulation.guidance)."""
    rows = []
    for link, ((a, b), length, radius) in enumerate(zip(
            geometry.symbolic_link_ends(q), geometry.link_lengths, geometry.link_radii,
            strict=True)):
        toward = symbolic_segment_toward(obstacle, a, b, length)
        normal = normals[3 * link: 3 * link + 3]
        along = ca.if_else(ca.dot(normal, normal) > 0.5, -ca.dot(normal, toward),
                           ca.norm_2(toward))
        rows.append(along - radius if radius else along)
    return rows


def clearance_site(geometry: ArmGeometry, dof: int, guided: bool) -> tuple[tuple, ca.SX]:
    """The symbols and expression of one pose's clearance rows (the elastic NLP's distances
    site): (q, centre) -> symbolic_link_clearances, or with guidance (q, centre, normals) ->
    guided_link_clearances (built only for a guided bank: its evaluations cost more)."""
    q, centre = ca.SX.sym("q", dof), ca.SX.sym("centre", 3)
    if not guided:
        return (q, centre), ca.vertcat(*symbolic_link_clearances(geometry, q, centre))
    normals = ca.SX.sym("normals", 3 * len(geometry.links))
    return (q, centre, normals), ca.vertcat(*guided_link_clearances(geometry, q, centre,
                                                                    normals))


def predicted_clearance(geometry: ArmGeometry, trajectory, forecast) -> float:
    """Smallest clearance (m) of a motion's links to an obstacle forecast
    (planning.types.ObstacleForecast) at its sample times."""
    q = trajectory.position(forecast.times)
    return float(link_clearances(geometry, q, forecast.centres).min())
