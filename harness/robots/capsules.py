"""Capsules fitted to a robot's link meshes: the planner's, the replay's and the scene's links.

Each link the planner checks (planning.formulation.kinematics.ArmGeometry.links, the body
joint i + 1 moves, bodies fixed to it included) gets the capsule of least volume found
around the points of its URDF collision geometry (harness.robots.collision; its visual
geometry where it has no collision elements): the axis starts as the points' principal
axis through their centroid, a Nelder-Mead search tilts and shifts it, and for each axis
the radius is the largest distance of a point to the axis line and the ends are the
shortest span holding every point (so the capsule contains the mesh by construction). The
axis ends are expressed in the frame of the joint moving the link (ArmGeometry.ends). A link
without readable geometry keeps the segment between its joint origins; a moving body whose
joint-origin segment has no length (the Panda's link 5, its forearm) becomes a link
(ArmGeometry.covered).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.optimize import minimize
from scipy.spatial import ConvexHull, QhullError

from planning.formulation.clearance import segment_distance
from planning.formulation.kinematics import ArmGeometry

TILT = 0.2  # rad-ish: the search's first steps of the axis direction
SHIFT = 0.05  # of the points' extent: the search's first steps of the axis position


@dataclass(frozen=True)
class Capsule:
    """A capsule: the axis a-b (3,) and the radius (m), in the frame its points were in."""

    a: np.ndarray
    b: np.ndarray
    radius: float

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Signed distance (m) of points (n, 3) to the surface (< 0 inside)."""
        return segment_distance(points, self.a, self.b) - self.radius

    @property
    def volume(self) -> float:
        """m^3."""
        length = float(np.linalg.norm(self.b - self.a))
        return float(np.pi * self.radius**2 * (length + 4 * self.radius / 3))


def _span(points: np.ndarray, origin: np.ndarray, axis: np.ndarray) -> Capsule:
    """The smallest capsule around points whose axis lies on the line origin + t axis."""
    offset = points - origin
    t = offset @ axis
    squared = np.maximum(np.einsum("ij,ij->i", offset, offset) - t * t, 0.0)
    radius = float(np.sqrt(squared.max()))
    half = np.sqrt(np.maximum(radius**2 - squared, 0.0))  # how far past t the end may stop
    low, high = float((t + half).min()), float((t - half).max())
    return Capsule(origin + low * axis, origin + high * axis, radius)


def fit_capsule(points: np.ndarray) -> Capsule:
    """The capsule of least volume found around points (n, 3) (module docstring); m."""
    points = np.asarray(points, float)
    try:
        points = points[ConvexHull(points).vertices]  # a convex capsule holding the hull holds all
    except (QhullError, ValueError):
        pass  # flat or too few points: all of them
    centre = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centre, full_matrices=False)
    axis = vt[0] * np.sign(vt[0][np.argmax(np.abs(vt[0]))])  # deterministic sign
    across = vt[1:3] if len(vt) == 3 else np.linalg.svd(axis[None])[2][1:3]
    extent = max(float(np.ptp(points, axis=0).max()), 1e-6)

    def capsule(x: np.ndarray) -> Capsule:
        direction = axis + x[0] * across[0] + x[1] * across[1]
        return _span(points, centre + extent * (x[2] * across[0] + x[3] * across[1]),
                     direction / np.linalg.norm(direction))

    simplex = np.vstack([np.zeros(4), np.diag([TILT, TILT, SHIFT, SHIFT])])
    best = minimize(lambda x: capsule(x).volume, np.zeros(4), method="Nelder-Mead",
                    options={"initial_simplex": simplex, "xatol": 1e-7, "fatol": 1e-12,
                             "maxiter": 4000})
    fitted = capsule(best.x if best.fun <= capsule(np.zeros(4)).volume else np.zeros(4))
    # the radius every point is within (rounding of the span's square roots)
    radius = max(fitted.radius, float(segment_distance(points, fitted.a, fitted.b).max()))
    return Capsule(fitted.a, fitted.b, radius)


def link_capsules(meshes: dict[int, np.ndarray], model: pin.Model, geometry: ArmGeometry
                  ) -> tuple[Capsule | None, ...]:
    """Per link of geometry.links, the capsule fitted to its body's points (per joint, as
    harness.robots.collision.body_points gives them) in
    the frame of the joint moving it (m), None without any; model: the arm's Pinocchio
    model the points were read with."""
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    origins, rotations = (x[0] for x in geometry.joint_frames(np.zeros(geometry.dof)))
    capsules: list[Capsule | None] = []
    for i, _ in geometry.links:
        points = meshes.get(i + 1)
        if points is None:
            capsules.append(None)
            continue
        placement = data.oMi[i + 1]
        world = points @ placement.rotation.T + placement.translation
        capsules.append(fit_capsule((world - origins[i]) @ rotations[i]))
    return tuple(capsules)


def fitted_geometry(geometry, model: pin.Model, body_points: dict, default: float = 0.0):
    """geometry (an ArmGeometry) with each link's capsule fitted to its bodies' points
    (Arm.body_points); a link without any keeps its joint-origin segment and radius default
    (m); without any points the links stay the segments, radius default (0: lines). A meshed
    body on a zero-length segment is a link too (if it moves)."""
    lines = dataclasses.replace(geometry, radii=(default,) * len(geometry.links)
                                if default else ())
    meshes = {j: points for j, (_, points) in body_points.items()}
    if not meshes:
        return lines
    extra = tuple(j - 1 for j in sorted(meshes) if (j - 1, j) not in geometry.links)
    grown = dataclasses.replace(geometry, covered=extra)
    geometry = dataclasses.replace(geometry, covered=tuple(
        i for i in extra if (i, i + 1) in grown.links))
    capsules = link_capsules(meshes, model, geometry)
    ends = tuple(origin if c is None else (tuple(map(float, c.a)), tuple(map(float, c.b)))
                 for c, origin in zip(capsules, geometry.origin_ends, strict=True))
    radii = tuple(default if c is None else c.radius for c in capsules)
    return dataclasses.replace(geometry, ends=ends, radii=radii)
