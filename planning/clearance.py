"""Distance from an obstacle centre to the arm's link segments (paper eq. 16, as segments).

The paper's code measured the distance to the infinite line through a link;
here it is the distance to the segment (shoulder-elbow, elbow-end effector),
via the clamped projection. The distance to a segment is continuously
differentiable away from the segment itself (the clamp only switches where
its derivative does not matter), which is enough for IPOPT with a quadratic
exterior penalty. Units: metres.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from planning.kinematics import ArmGeometry


def segment_distance(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance (n,) from points (n, 3) to segments a-b (n, 3 each); a zero-length segment
    is its point."""
    ab = b - a
    t = np.einsum("ij,ij->i", point - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    closest = a + np.clip(t, 0.0, 1.0)[:, None] * ab
    return np.linalg.norm(point - closest, axis=1)


def symbolic_segment_distance(point, a, b, length: float):
    """CasADi distance from point to segment a-b of known constant length (m)."""
    ab = b - a
    t = ca.fmin(ca.fmax(ca.dot(point - a, ab) / length**2, 0.0), 1.0)
    return ca.norm_2(point - a - t * ab)


def link_clearances(geometry: ArmGeometry, q: np.ndarray, obstacle: np.ndarray) -> np.ndarray:
    """Distances (n, 2) of obstacle centres (n, 3) to link 2 and link 3 at angles q (n, 3)."""
    shoulder, elbow, end = geometry.points(q)
    obstacle = np.broadcast_to(obstacle, elbow.shape)
    return np.stack(
        [segment_distance(obstacle, shoulder, elbow), segment_distance(obstacle, elbow, end)],
        axis=1,
    )


def symbolic_link_clearances(geometry: ArmGeometry, q, obstacle):
    """CasADi distances (link 2, link 3) of an obstacle centre at joint vector q."""
    elbow, end = geometry.symbolic_points(q)
    shoulder = ca.DM(geometry.shoulder)
    return (
        symbolic_segment_distance(obstacle, shoulder, elbow, geometry.l2),
        symbolic_segment_distance(obstacle, elbow, end, geometry.l3),
    )
