"""Forward kinematics of the simplified 3-DOF Lynxmotion arm, paper eqs. (9) and (10).

Distal DH: joint 1 turns about the vertical axis, joints 2 and 3 lift the
links; positions in metres, angles in radians. The same formulas serve numpy
arrays (vectorized over samples) and CasADi expressions (for the planner).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np


@dataclass(frozen=True)
class ArmGeometry:
    """Link lengths of the arm in metres (d1 shoulder height, l2 upper arm, l3 forearm)."""

    d1: float = 0.086
    l2: float = 0.146
    l3: float = 0.187

    @property
    def shoulder(self) -> np.ndarray:
        """Shoulder position P1 (m); it does not move."""
        return np.array([0.0, 0.0, self.d1])

    def points(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Shoulder, elbow, end effector (each (n, 3), m) at joint angles q of shape (n, 3)."""
        q = np.atleast_2d(q)
        elbow, end = _points(q[:, 0], q[:, 1], q[:, 2], self, np.cos, np.sin)
        shoulder = np.broadcast_to(self.shoulder, elbow.shape)
        return shoulder, elbow, end

    def symbolic_points(self, q) -> tuple[ca.SX, ca.SX]:
        """Elbow and end effector (3 x 1 CasADi) at a CasADi joint vector q."""
        elbow, end = _points(q[0], q[1], q[2], self, ca.cos, ca.sin)
        return elbow, end


def _points(q1, q2, q3, geometry: ArmGeometry, cos, sin):
    """Elbow P2 (eq. 10) and end effector P3 (eq. 9) with the given cos/sin."""
    reach2 = geometry.l2 * cos(q2)
    reach3 = reach2 + geometry.l3 * cos(q2 + q3)
    height2 = geometry.d1 + geometry.l2 * sin(q2)
    height3 = height2 + geometry.l3 * sin(q2 + q3)
    if isinstance(q1, np.ndarray):
        elbow = np.stack([reach2 * cos(q1), reach2 * sin(q1), height2], axis=-1)
        end = np.stack([reach3 * cos(q1), reach3 * sin(q1), height3], axis=-1)
        return elbow, end
    elbow = ca.vertcat(reach2 * cos(q1), reach2 * sin(q1), height2)
    end = ca.vertcat(reach3 * cos(q1), reach3 * sin(q1), height3)
    return elbow, end
