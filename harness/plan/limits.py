"""The limits and link capsules `torquebench plan` keeps, from its options."""

from __future__ import annotations

import dataclasses
import math

from harness.errors import UserError
from harness.robots.arm import Arm
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


def torque_limit(args, arm: Arm, dof: int) -> tuple[float, ...] | None:
    """--torque-limit (N m), else the arm's."""
    if args.torque_limit is None:
        return arm.torque_limit
    if args.torque_limit.strip().lower() == "none":
        return None
    limit = vector(args.torque_limit, "torque-limit", dof)
    if not all(v > 0 for v in limit):
        raise UserError(f"--torque-limit must be positive, got '{args.torque_limit}'")
    return limit


def link_geometry(args, arm: Arm, geometry: ArmGeometry) -> ArmGeometry:
    """geometry with the link capsules of --link-radius: 'collision', those fitted to the
    arm's meshes (harness.robots.capsules; the centre lines without any), else one radius
    (m) around every joint-origin segment (0: the centre lines); left out: 'collision'."""
    if args.link_radius is None or args.link_radius.strip().lower() == "collision":
        fitted = arm.capsules()
        return dataclasses.replace(geometry, covered=fitted.covered, ends=fitted.ends,
                                   radii=fitted.radii)
    radius = vector(args.link_radius, "link-radius", 1)[0]
    if radius < 0:
        raise UserError(f"--link-radius must be >= 0 m or 'collision', got '{args.link_radius}'")
    return dataclasses.replace(geometry, radii=(radius,) * len(geometry.links) if radius else ())


def rate_limits(args, arm: Arm, dof: int) -> dict:
    """velocity_limit and acceleration_limit of the configuration (rad/s, rad/s^2): the
    options', else the arm's velocity limits and none on the acceleration."""
    limits = {"velocity_limit": arm.velocity_limit, "acceleration_limit": None}
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
