"""Each body's bounding ellipsoid, for plausible identified bodies (identification.ellipsoids).

A body's ellipsoid is the smallest one holding its links' collision geometry (else their
visual geometry) from the URDF, in its joint's frame, where the standard parameters are.
A body without geometry the harness can read (none in the file, an MJCF, meshes it cannot
read: Arm.unread_geometry names them) gets one around the segment from its joint to its
child joint, a quarter of the segment thick (at least MIN_RADIUS); a last body without
geometry a sphere of MIN_RADIUS about its nominal centre of mass. Each is grown about its
centre until it holds the URDF's own body (a bound the robot's file breaks is a wrong
bound, and generated data are that body's); the consistent fit grows it again to hold its
prior's body.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pinocchio as pin

from identification.ellipsoids import Ellipsoid, enclosing, holding
from identification.physical import pseudo_inertia

MIN_RADIUS = 0.05  # m: a link without geometry is still this thick


def _frame(axis: np.ndarray) -> np.ndarray:
    """A rotation whose first column is the unit vector axis."""
    other = np.eye(3)[np.argmin(np.abs(axis))]
    second = np.cross(axis, other)
    second /= np.linalg.norm(second)
    return np.column_stack([axis, second, np.cross(axis, second)])


def segment_ellipsoid(model: pin.Model, joint: int) -> Ellipsoid:
    """The ellipsoid of a body without geometry (module docstring)."""
    children = [k for k in range(joint + 1, model.njoints) if model.parents[k] == joint]
    if not children:
        return Ellipsoid(np.asarray(model.inertias[joint].lever, float).copy(),
                         np.full(3, MIN_RADIUS), np.eye(3), "sphere about the last body's centre of mass")
    end = np.asarray(model.jointPlacements[children[0]].translation, float)
    length = float(np.linalg.norm(end))
    radius = max(MIN_RADIUS, 0.25 * length)
    axes = _frame(end / length) if length > 1e-9 else np.eye(3)
    return Ellipsoid(end / 2, np.array([length / 2 + radius, radius, radius]), axes,
                     "about the segment to the child joint")


def arm_ellipsoids(model: pin.Model, found: dict) -> tuple[Ellipsoid, ...]:
    """Per body of the arm's Pinocchio model, its bounding ellipsoid (its source says where
    from); found: the bodies' geometry points (Arm.body_points)."""
    ellipsoids = []
    for joint in range(1, model.njoints):
        bound = segment_ellipsoid(model, joint) if joint not in found else replace(
            enclosing(found[joint][1]),
            source=f"smallest holding the links' {found[joint][0]} geometry")
        body = np.array(pseudo_inertia(model.inertias[joint].toDynamicParameters()))
        ellipsoids.append(holding(bound, body, "the URDF's body"))
    return tuple(ellipsoids)
