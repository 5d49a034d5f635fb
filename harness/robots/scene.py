"""A MuJoCo scene built around any arm (mujoco.MjSpec), for replaying plans.

The arm's model (robot_spec: the URDF's arm joints without meshes, or the MJCF)
gets what a replay needs, as the Lynxmotion's hand-written scene.xml has it: a floor, a
light, a camera looking at the arm, the moving obstacle as a mocap body with a sphere, one
motor per joint limited to the model's torque limits (gear 1), a site 'end_effector' at the
flange and a capsule 'link<j>' around every link the planner checks, on the planner's own
capsule axis (ArmGeometry.link_ends: body-fixed, fitted to the meshes, or the joint-origin
segment) with its radius (no contacts: they are for measuring distances, mj_geomDistance).
The timestep and integrator are the Lynxmotion's (0.5 ms, implicitfast), so every arm is
tracked at the same rate.
"""

from __future__ import annotations

import dataclasses
from functools import cache

import mujoco
import numpy as np

from harness.errors import UserError
from harness.robots.arm import Arm
from planning.formulation.kinematics import ArmGeometry

TIMESTEP = 0.0005  # s
OBSTACLE_RADIUS = 0.02  # m, drawn only: clearance is measured to the centre
LINK_RADIUS = 0.012  # m, the Lynxmotion's link capsules; drawn where the planner's links are lines
ZERO_LENGTH = 1e-6  # m: a link axis shorter than this is drawn as a sphere
FLANGE_SITE = "end_effector"


def robot_spec(arm: Arm) -> mujoco.MjSpec:
    """A copy of the arm's MuJoCo spec (Arm.spec: the file parsed once), to build on."""
    return arm.spec.copy()


@cache
def replay_scene(arm: Arm, radii: tuple[float, ...] = (),
                 geometry: ArmGeometry | None = None) -> mujoco.MjModel:
    """The arm's replay scene: its registered scene MJCF when it has one (the Lynxmotion's,
    arm.scene), else one built around it (build_scene) with the plan's link capsules."""
    if arm.scene is not None:
        return arm.scene
    return build_scene(arm, radii, geometry).compile()


def build_scene(arm: Arm, radii: tuple[float, ...] = (),
                geometry: ArmGeometry | None = None) -> mujoco.MjSpec:
    """The arm's spec with floor, light, camera, mocap obstacle, motors, flange site and
    link capsules added (see the module docstring): those of geometry (the planner's: its
    links, capsule axes and radii), else the arm's joint-origin segments with these radii
    (m); no radius or 0: LINK_RADIUS, drawn."""
    spec = robot_spec(arm)
    geometry = geometry or dataclasses.replace(arm.geometry, radii=tuple(radii))
    hinges = [j for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
    if len(hinges) != geometry.dof or len(spec.joints) != geometry.dof:
        raise UserError(f"robot {arm.label}: {len(spec.joints)} MuJoCo joints, the arm has "
                        f"{geometry.dof} revolute joints")
    spec.compiler.discardvisual = False  # the scene's geoms have no contacts: keep them
    spec.option.timestep = TIMESTEP
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.visual.global_.offwidth, spec.visual.global_.offheight = 640, 480
    _add_motors(spec, hinges, arm.torque_limit)
    _add_links(spec, hinges, geometry)
    _add_surroundings(spec, geometry)
    return spec


def _add_motors(spec: mujoco.MjSpec, hinges, limit: tuple[float, ...] | None) -> None:
    """One motor per joint, ctrlrange = +- the torque limit (unlimited if none is known)."""
    if len(spec.actuators):
        return  # an MJCF with its own motors keeps them
    for k, joint in enumerate(hinges):
        motor = spec.add_actuator(name=joint.name, target=joint.name,
                                  trntype=mujoco.mjtTrn.mjTRN_JOINT)
        motor.set_to_motor()
        if limit is not None:
            motor.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
            motor.ctrlrange = [-limit[k], limit[k]]


def link_axes(model: mujoco.MjModel, joints, geometry: ArmGeometry) -> tuple:
    """Each link's capsule axis (ArmGeometry.link_ends at q = 0) in the frame of the MuJoCo
    body its joint moves: the body ids (links,) and both ends (links, 3 each, m); joints:
    the arm's hinge joint ids in order."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    first, second = (ends[0] for ends in geometry.link_ends(np.zeros(geometry.dof)))
    bodies = np.array([model.jnt_bodyid[joints[i]] for i, _ in geometry.links], int)
    def local(ends: np.ndarray) -> np.ndarray:
        return np.array([data.xmat[body].reshape(3, 3).T @ (point - data.xpos[body])
                         for body, point in zip(bodies, ends, strict=True)]).reshape(-1, 3)

    return bodies, local(first), local(second)


def _add_links(spec: mujoco.MjSpec, hinges, geometry: ArmGeometry) -> None:
    """The flange site and one capsule per link (link_axes), at q = 0 expressed in the
    frame of the body that carries them."""
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    home = geometry.points(np.zeros(geometry.dof))[0]
    joints = [model.joint(j.name).id for j in hinges]
    last = model.jnt_bodyid[joints[-1]]
    names = {s.name for s in spec.sites}
    if FLANGE_SITE not in names:
        flange = data.xmat[last].reshape(3, 3).T @ (home[-1] - data.xpos[last])
        spec.body(model.body(last).name).add_site(name=FLANGE_SITE, pos=flange,
                                                  size=[0.005, 0, 0])
    geoms = {g.name for g in spec.geoms}
    for (i, _), body, a, b, radius in zip(geometry.links, *link_axes(model, joints, geometry),
                                          geometry.link_radii, strict=True):
        name = f"link{i + 1}"
        if name in geoms:
            continue
        # a link of zero length (two joint origins at one point, as on the UR3's wrist) is
        # the capsule's limit, a sphere: MuJoCo refuses a capsule between coincident points
        shape = dict(type=mujoco.mjtGeom.mjGEOM_SPHERE, pos=a) if \
            np.linalg.norm(np.subtract(b, a)) < ZERO_LENGTH else \
            dict(type=mujoco.mjtGeom.mjGEOM_CAPSULE, fromto=np.concatenate([a, b]))
        spec.body(model.body(body).name).add_geom(
            name=name, **shape, size=[radius or LINK_RADIUS, 0, 0], contype=0, conaffinity=0,
            mass=0, rgba=[0.8, 0.3, 0.2, 0.6])


def _add_surroundings(spec: mujoco.MjSpec, geometry: ArmGeometry) -> None:
    """Floor, light, mocap obstacle and a camera 1.3 reaches away looking at the arm."""
    reach = max(0.2, float(sum(geometry.link_lengths)))
    world = spec.worldbody
    world.add_light(pos=[0, 0, 2 * reach + 0.5], dir=[0, 0, -1], type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)
    world.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[2 * reach, 2 * reach, 0.05],
                   contype=0, conaffinity=0, rgba=[0.2, 0.3, 0.4, 1])
    obstacle = world.add_body(name="obstacle", mocap=True)
    obstacle.add_geom(name="obstacle", type=mujoco.mjtGeom.mjGEOM_SPHERE,
                      size=[OBSTACLE_RADIUS, 0, 0], contype=0, conaffinity=0,
                      rgba=[0.1, 0.1, 0.1, 0.8])
    target = np.array([0.0, 0.0, 0.4 * reach])
    eye = target + 1.3 * reach * np.array([0.6, -0.6, 0.45])
    world.add_camera(name="overview", pos=eye, quat=_look_at(eye, target))


def _look_at(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Quaternion of a camera at eye looking at target, z up (MuJoCo cameras look along -z)."""
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.column_stack([right, up, -forward]).ravel())
    return quat
