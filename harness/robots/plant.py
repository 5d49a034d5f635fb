"""A plant: the MuJoCo model that produces data, with its joint limits and Pinocchio twin."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin

from harness.errors import UserError
from harness.robots.registry import check_open_chain, load_mujoco, load_pinocchio


@dataclass(frozen=True)
class Plant:
    """MuJoCo model of the data-producing robot; `name` is what the user passed."""

    name: str
    model: mujoco.MjModel

    @property
    def dof(self) -> int:
        return self.model.nv

    def limits(self) -> tuple[np.ndarray, np.ndarray]:
        """Joint position limits (rad); unlimited hinges get [-pi, pi]."""
        ids = self.model.dof_jntid
        limited = self.model.jnt_limited[ids].astype(bool)
        lo = np.where(limited, self.model.jnt_range[ids, 0], -np.pi)
        hi = np.where(limited, self.model.jnt_range[ids, 1], np.pi)
        return lo, hi

    def velocity_limits(self) -> np.ndarray:
        """Joint speed limits (rad/s) from the URDF's <limit velocity> (Pinocchio's
        velocityLimit); inf where none is declared (0, non-finite or huge)."""
        v = np.asarray(self.pinocchio().velocityLimit, float)
        return np.where(np.isfinite(v) & (v > 0) & (v < 1e10), v, np.inf)

    def pinocchio(self) -> pin.Model:
        """The plant's rigid-body model in Pinocchio (registry URDF or parsed MJCF); UserError
        if Pinocchio cannot read it: the excitation design, the estimated-state report and every
        model of the plant need it, so there is no silent states-only fallback."""
        model = load_pinocchio(self.name)
        if model.nv != self.dof:
            raise UserError(f"plant {self.name}: Pinocchio reads {model.nv} joints, MuJoCo {self.dof}")
        return model


def load_plant(name_or_path: str | Path) -> Plant:
    """Load a plant by registry name or MJCF path; only hinge/slide joints of an open chain
    are supported."""
    model = load_mujoco(name_or_path)
    if model.nq != model.nv or model.nv == 0:
        raise UserError(f"plant {name_or_path}: needs 1-DOF joints only (nq={model.nq}, nv={model.nv})")
    check_open_chain(model, name_or_path)
    return Plant(str(name_or_path), model)
