"""What the planner needs of a robot, read from its model: the kinematic chain as data
(planning.formulation.kinematics.ArmGeometry), its joint limits and its motors' torque limits.

Joint placements and axes come from the Pinocchio model (identification.library.chain);
the flange is the first of registry.FLANGES the model has (else the frame on the last
body farthest from its joint). Joint limits are MuJoCo's (an unlimited hinge gets
[-pi, pi]); torque limits are the MJCF motors' ctrlrange x gear when the model has one
motor per joint, else the URDF's effort limits.
"""

from __future__ import annotations

import dataclasses
from functools import cache
from pathlib import Path

import numpy as np
import pinocchio as pin

from harness.robots.plant import load_plant
from harness.robots.registry import (
    ROBOTS,
    flange_frame,
    get_robot,
    load_chain,
    load_mujoco,
    load_pinocchio,
    robot_entry,
)
from planning.config import PlannerConfig, Scenario, true_energy_config
from planning.formulation.kinematics import ArmGeometry


def robot_label(robot: str | Path) -> str:
    """What PLAN.json records: a registered name as is, a path made absolute."""
    return str(robot) if str(robot) in ROBOTS else str(Path(robot).resolve())


@cache
def arm_geometry(robot: str) -> ArmGeometry:
    """The robot's chain of joint placements, axes and flange (m), for planning."""
    chain = load_chain(robot)
    model = load_pinocchio(robot)
    last = model.njoints - 1
    frames = [f for f in model.frames if f.parentJoint == last]
    named = [f for f in frames if f.name == flange_frame(model)]
    # the named flange (a body in a URDF, a site in an MJCF), else the frame of the last
    # body farthest from its joint (the tip); none: the last joint's origin
    tips = named or sorted(frames, key=lambda f: np.linalg.norm(f.placement.translation))
    flange = np.asarray(tips[-1].placement.translation) if tips else np.zeros(3)
    bodies = []
    for j in range(1, model.njoints):
        names = [f.name for f in model.frames
                 if f.parentJoint == j and f.type == pin.FrameType.BODY]
        bodies.append(names[0] if names else model.names[j])
    return ArmGeometry.of(chain.rotations, chain.translations, chain.axes, flange,
                          robot_label(robot), bodies)


@cache
def collision_capsules(robot: str, default: float = 0.0) -> ArmGeometry:
    """The robot's arm_geometry with each link's capsule fitted to its URDF collision (else
    visual) geometry (harness.robots.capsules; a moving meshed body on a zero-length segment
    becomes a link); a link without any keeps its joint-origin segment and radius default
    (m); without any geometry (an MJCF, a URDF without meshes) the links stay the segments,
    with radius default (0: lines)."""
    from harness.robots.capsules import link_capsules
    from harness.robots.collision import robot_body_points

    geometry = arm_geometry(robot)
    lines = dataclasses.replace(geometry, radii=(default,) * len(geometry.links) if default
                                else ())
    meshes = {j: points for j, (_, points) in robot_body_points(robot).items()}
    if not meshes:
        return lines
    model = load_pinocchio(robot)
    # a meshed body on a zero-length segment is a link too (if it moves)
    extra = tuple(j - 1 for j in sorted(meshes) if (j - 1, j) not in geometry.links)
    grown = dataclasses.replace(geometry, covered=extra)
    geometry = dataclasses.replace(geometry, covered=tuple(
        i for i in extra if (i, i + 1) in grown.links))
    capsules = link_capsules(meshes, model, geometry)
    ends = tuple(origin if c is None else (tuple(map(float, c.a)), tuple(map(float, c.b)))
                 for c, origin in zip(capsules, geometry.origin_ends, strict=True))
    radii = tuple(default if c is None else c.radius for c in capsules)
    return dataclasses.replace(geometry, ends=ends, radii=radii)


def link_radii(robot: str, default: float = 0.0) -> tuple[float, ...]:
    """Each planner link's capsule radius (m) from collision_capsules."""
    return tuple(float(r) for r in collision_capsules(robot, default).link_radii)


def joint_limits(robot: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Lower and upper joint limits (rad) from the robot's MuJoCo model."""
    lower, upper = load_plant(robot).limits()
    return tuple(map(float, lower)), tuple(map(float, upper))


def motor_torque_limit(robot: str) -> tuple[float, ...] | None:
    """|tau_i| bound (N m) of each joint from the robot's MJCF motors (ctrlrange x gear), in
    joint order; None if a motor is unlimited or the motors do not map 1:1 to joints."""
    model = load_mujoco(robot)
    joints = model.actuator_trnid[:, 0]
    if model.nu == 0 or model.nu != model.njnt or sorted(joints) != list(range(model.njnt)) \
            or not all(model.actuator_ctrllimited):
        return None
    reach = np.abs(model.actuator_ctrlrange).min(axis=1) * np.abs(model.actuator_gear[:, 0])
    limit = np.empty(model.njnt)
    limit[joints] = reach
    return tuple(float(v) for v in limit)


def torque_limit(robot: str) -> tuple[float, ...] | None:
    """The motors' limits (MJCF), else the model's effort limits (URDF); None if unknown."""
    motors = motor_torque_limit(robot)
    if motors is not None or load_mujoco(robot).nu > 0:
        return motors
    effort = np.asarray(load_pinocchio(robot).effortLimit, float)
    if not np.all(np.isfinite(effort) & (effort > 0)):
        return None
    return tuple(float(v) for v in effort)


def velocity_limit(robot: str) -> tuple[float, ...] | None:
    """|qd_i| bound (rad/s) of each joint from the URDF's <limit velocity>; None unless every
    joint has a finite positive one (an MJCF has none)."""
    velocity = np.asarray(load_pinocchio(robot).velocityLimit, float)
    if not np.all(np.isfinite(velocity) & (velocity > 0)):
        return None
    return tuple(float(v) for v in velocity)


def planner_config(robot: str, **changes) -> PlannerConfig:
    """The default planner configuration on robot, what `plan` and the bench plan with: the
    true energy, several starts and the arrival at rest of planning.config.true_energy_config
    (planning.config's own defaults are the paper's), the robot's links, joint and torque
    limits, and the solver its registry entry names (IPOPT unless said: on the UR5's
    crossing, compiled NLP, fatrop's cold solve stopped at its 300-iteration cap and half its
    warm re-plans at 60, each then rescued by IPOPT; IPOPT alone: 18 + 6 iterations cold, 4-7
    per re-plan)."""
    lower, upper = joint_limits(robot)
    base = dict(geometry=arm_geometry(robot), lower=lower, upper=upper,
                torque_limit=torque_limit(robot))
    return true_energy_config(**{**base, **changes}).with_penalty(
        solver=robot_entry(robot).solver)


def bench_motion(robot: str, duration: float = 2.0) -> tuple[Scenario, int]:
    """The robot's planning motion (registry entry; else from 30 % to 70 % of every joint's
    range) at rest, without obstacle, and the index (into the geometry's links) of the link
    an obstacle should cross: the registered body's, else the last link."""
    geometry = arm_geometry(robot)
    entry = get_robot(robot) if robot in ROBOTS else None
    if entry is not None and entry.motion is not None:
        start, goal, body = entry.motion
    else:
        lower, upper = (np.maximum(np.asarray(b), -np.pi) if k == 0 else
                        np.minimum(np.asarray(b), np.pi) for k, b in enumerate(joint_limits(robot)))
        start, goal, body = tuple(lower + 0.3 * (upper - lower)), \
            tuple(lower + 0.7 * (upper - lower)), ""
    owners = [geometry.bodies[i] for i, _ in geometry.links]
    link = owners.index(body) if body in owners else len(owners) - 1
    dof = geometry.dof
    return Scenario(tuple(map(float, start)), tuple(map(float, goal)), duration, None,
                    (0.0,) * dof), link
