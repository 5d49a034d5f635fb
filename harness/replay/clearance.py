"""Link-obstacle clearance measured on a MuJoCo plant.

Two measures, both in m, over every link the planner checks (planning.formulation.kinematics:
segments between consecutive joint origins and to the flange, those that move):
- centre-to-segment: distance from the obstacle centre to each link segment, its ends
  read from MuJoCo (joint anchors `xanchor`, the flange site 'end_effector'; or, where the
  planner's capsules have body-fixed axes, ArmGeometry.ends, those ends carried by the
  joint's body: harness.robots.scene.link_axes), minus the capsule's radius: the planner's
  own measure; on the Lynxmotion link 2 (shoulder->elbow) and link 3 (elbow->end
  effector), the paper's D1, D2 (eq. 16, with the projection clamped to the segment);
- surface: MuJoCo's `mj_geomDistance` between the link capsules 'link<j>' and the
  obstacle sphere 'obstacle' (centre distance minus radii), when the scene has them.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from harness.errors import UserError
from harness.robots.scene import link_axes
from planning.formulation.clearance import segment_distance
from planning.formulation.kinematics import ArmGeometry, paper_arm

FLANGE_SITE = "end_effector"
OBSTACLE = "obstacle"
SURFACE_CUTOFF = 1.0  # m: mj_geomDistance reports distances up to this bound


def _id(model: mujoco.MjModel, kind: mujoco.mjtObj, name: str) -> int:
    return mujoco.mj_name2id(model, kind, name)


@dataclass(frozen=True)
class ClearanceProbe:
    """Where to look on a plant: link points (joint anchors, flange site), the links as
    index pairs into them, optional geoms for surfaces."""

    joints: tuple[int, ...]  # hinge joint ids, in the arm's joint order
    flange_site: int
    segments: tuple[tuple[int, int], ...]  # index pairs into (joint anchors..., flange)
    link_geoms: tuple[int, ...]  # capsule geom ids ('link<j>'), may be empty
    obstacle_geom: int  # -1 if the plant has no obstacle sphere
    obstacle_mocap: int  # -1 if the plant has no mocap obstacle body
    radii: tuple[float, ...] = ()  # m, each link's capsule (the planner's): none, lines
    # body-fixed capsule axes (ArmGeometry.ends): body ids (links,), ends (links, 3) in m;
    # None: the segments between the link points
    axes: tuple | None = None

    @classmethod
    def of(cls, model: mujoco.MjModel, geometry: ArmGeometry | None = None) -> ClearanceProbe:
        """The probe of the arm `geometry` (default: the paper's Lynxmotion) on model."""
        geometry = geometry or paper_arm()
        joints = tuple(int(j) for j in range(model.njnt)
                       if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE)
        if len(joints) != geometry.dof:
            raise UserError(f"plant has {len(joints)} hinge joints, the arm {geometry.dof}")
        flange = _id(model, mujoco.mjtObj.mjOBJ_SITE, FLANGE_SITE)
        if flange < 0:
            raise UserError(f"plant has no site '{FLANGE_SITE}' at the flange for clearance")
        geoms = tuple(_id(model, mujoco.mjtObj.mjOBJ_GEOM, f"link{i + 1}")
                      for i, _ in geometry.links)
        obstacle_geom = _id(model, mujoco.mjtObj.mjOBJ_GEOM, OBSTACLE)
        body = _id(model, mujoco.mjtObj.mjOBJ_BODY, OBSTACLE)
        mocap = int(model.body_mocapid[body]) if body >= 0 else -1
        axes = link_axes(model, joints, geometry) if geometry.ends else None
        return cls(joints, flange, tuple(geometry.links),
                   geoms if min(geoms) >= 0 else (), obstacle_geom, mocap, tuple(geometry.radii),
                   axes)

    def points(self, data: mujoco.MjData) -> np.ndarray:
        """Link points (dof + 1, 3) in m at the current kinematics."""
        return np.vstack([data.xanchor[list(self.joints)], data.site_xpos[self.flange_site]])

    @property
    def has_surface(self) -> bool:
        return bool(self.link_geoms) and self.obstacle_geom >= 0 and self.obstacle_mocap >= 0

    def move_obstacle(self, data: mujoco.MjData, centre: np.ndarray) -> None:
        """Put the mocap obstacle at centre (m); a plant without one is left alone."""
        if self.obstacle_mocap >= 0:
            data.mocap_pos[self.obstacle_mocap] = centre

    def centre_distances(self, data: mujoco.MjData, centre: np.ndarray) -> np.ndarray:
        """Distance (m) from centre to each link segment (to its capsule's surface where the
        planner's links have radii) at the current kinematics."""
        if self.axes is None:
            points = self.points(data)
            a = points[[i for i, _ in self.segments]]
            b = points[[j for _, j in self.segments]]
        else:
            bodies, first, second = self.axes
            rotations, origins = data.xmat[bodies].reshape(-1, 3, 3), data.xpos[bodies]
            a = origins + np.einsum("lij,lj->li", rotations, first)
            b = origins + np.einsum("lij,lj->li", rotations, second)
        distance = segment_distance(np.broadcast_to(centre, a.shape), a, b)
        return distance - np.asarray(self.radii) if self.radii else distance

    def surface_distances(self, model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
        """Signed surface distance (m) from each link capsule to the obstacle sphere."""
        fromto = np.zeros(6)
        return np.array([
            mujoco.mj_geomDistance(model, data, g, self.obstacle_geom, SURFACE_CUTOFF, fromto)
            for g in self.link_geoms
        ])
