"""The limits and link capsules `torquebench plan` keeps, from its options."""

from __future__ import annotations

import dataclasses
import math

from harness.errors import UserError
from harness.robots import arm
from planning.formulation.kinematics import ArmGeometry


def vector(text: str, name: str, length: int = 3) -> tuple[float, ...]:
    try:
        values = tuple(float(x) for x in text.split(","))
    except ValueError:
        raise UserError(f"--{name} must be {length} comma-separated numbers, got '{text}'") from None
    if len(values) != length or not all(math.isfinite(v) for v in values):
        raise UserError(f"--{name} must be {length} finite comma-separated numbers, got '{text}'")
    return values


def vector_text(values) -> str:
    """The comma-separated text `vector` reads back."""
    return ",".join(repr(float(v)) for v in values)


def torque_limit(args, dof: int) -> tuple[float, ...] | None:
    """--torque-limit (N m), else the robot's."""
    if args.torque_limit is None:
        return arm.torque_limit(args.robot)
    if args.torque_limit.strip().lower() == "none":
        return None
    limit = vector(args.torque_limit, "torque-limit", dof)
    if not all(v > 0 for v in limit):
        raise UserError(f"--torque-limit must be positive, got '{args.torque_limit}'")
    return limit


def link_geometry(args, geometry: ArmGeometry) -> ArmGeometry:
    """geometry with the link capsules of --link-radius: 'collision', those fitted to the
    robot's meshes (harness.robots.capsules; the centre lines without any), else one radius
    (m) around every joint-origin segment (0: the centre lines)."""
    if args.link_radius.strip().lower() == "collision":
        fitted = arm.collision_capsules(args.robot)
        return dataclasses.replace(geometry, covered=fitted.covered, ends=fitted.ends,
                                   radii=fitted.radii)
    radius = vector(args.link_radius, "link-radius", 1)[0]
    if radius < 0:
        raise UserError(f"--link-radius must be >= 0 m or 'collision', got '{args.link_radius}'")
    return dataclasses.replace(geometry, radii=(radius,) * len(geometry.links) if radius else ())


def rate_limits(args, dof: int) -> dict:
    """velocity_limit and acceleration_limit of the configuration (rad/s, rad/s^2)."""
    limits = {"velocity_limit": arm.velocity_limit(args.robot), "acceleration_limit": None}
    for name, key in (("velocity-limit", "velocity_limit"), ("accel-limit", "acceleration_limit")):
        text = getattr(args, key if name == "velocity-limit" else "accel_limit")
        if text is None:
            continue
        if text.strip().lower() == "none":
            limits[key] = None
            continue
        values = vector(text, name, 1 if "," not in text else dof)
        if not all(v > 0 for v in values):
            raise UserError(f"--{name} must be positive, got '{text}'")
        limits[key] = values * dof if len(values) == 1 else values
    return limits
