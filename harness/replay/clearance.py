"""Link-obstacle clearance measured on a MuJoCo plant.

Two measures, both in m:
- centre-to-segment: distance from the obstacle centre to the link segments
  shoulder->elbow (link 2) and elbow->end effector (link 3), the paper's D1, D2
  (eq. 16, with the projection clamped to the segment);
- surface: MuJoCo's `mj_geomDistance` between the link capsules 'link2',
  'link3' and the obstacle sphere 'obstacle' (centre distance minus radii).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from harness.errors import UserError
from planning.clearance import segment_distance

LINK_SITES = (("shoulder", "elbow"), ("elbow", "end_effector"))
LINK_GEOMS = ("link2", "link3")
OBSTACLE = "obstacle"
SURFACE_CUTOFF = 1.0  # m: mj_geomDistance reports distances up to this bound


def _id(model: mujoco.MjModel, kind: mujoco.mjtObj, name: str) -> int:
    return mujoco.mj_name2id(model, kind, name)


@dataclass(frozen=True)
class ClearanceProbe:
    """Where to look on a plant: link segments from sites, optional geoms for surfaces."""

    segments: tuple[tuple[int, int], ...]  # site id pairs
    link_geoms: tuple[int, ...]  # capsule geom ids ('link2', 'link3'), may be empty
    obstacle_geom: int  # -1 if the plant has no obstacle sphere
    obstacle_mocap: int  # -1 if the plant has no mocap obstacle body

    @classmethod
    def of(cls, model: mujoco.MjModel) -> ClearanceProbe:
        site = mujoco.mjtObj.mjOBJ_SITE
        segments = tuple((_id(model, site, a), _id(model, site, b)) for a, b in LINK_SITES)
        if any(i < 0 for pair in segments for i in pair):
            raise UserError("plant has no sites 'shoulder', 'elbow', 'end_effector' for clearance")
        geoms = tuple(_id(model, mujoco.mjtObj.mjOBJ_GEOM, g) for g in LINK_GEOMS)
        obstacle_geom = _id(model, mujoco.mjtObj.mjOBJ_GEOM, OBSTACLE)
        body = _id(model, mujoco.mjtObj.mjOBJ_BODY, OBSTACLE)
        mocap = int(model.body_mocapid[body]) if body >= 0 else -1
        return cls(segments, geoms if min(geoms) >= 0 else (), obstacle_geom, mocap)

    @property
    def has_surface(self) -> bool:
        return bool(self.link_geoms) and self.obstacle_geom >= 0 and self.obstacle_mocap >= 0

    def move_obstacle(self, data: mujoco.MjData, centre: np.ndarray) -> None:
        """Put the mocap obstacle at centre (m); a plant without one is left alone."""
        if self.obstacle_mocap >= 0:
            data.mocap_pos[self.obstacle_mocap] = centre

    def centre_distances(self, data: mujoco.MjData, centre: np.ndarray) -> np.ndarray:
        """Distance (m) from centre to each link segment at the current kinematics."""
        a = np.stack([data.site_xpos[i] for i, _ in self.segments])
        b = np.stack([data.site_xpos[j] for _, j in self.segments])
        return segment_distance(np.broadcast_to(centre, a.shape), a, b)

    def surface_distances(self, model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
        """Signed surface distance (m) from each link capsule to the obstacle sphere."""
        fromto = np.zeros(6)
        return np.array([
            mujoco.mj_geomDistance(model, data, g, self.obstacle_geom, SURFACE_CUTOFF, fromto)
            for g in self.link_geoms
        ])
