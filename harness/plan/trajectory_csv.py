"""A control-rate trajectory (planning.control) written as CSV for a robot's controller."""

from __future__ import annotations

import numpy as np

from harness.io import atomic_write
from planning.control import ControlTrajectory

DEFAULT_RATE = 500.0  # Hz: `plan --trajectory` without --rate


def write_trajectory(path: str, trajectory: ControlTrajectory) -> None:
    """Write t,q1..qn,qd1..qdn,qdd1..qddn,tau1..taun (s, rad, rad/s, rad/s^2, N m) atomically,
    one row per control period, full precision."""
    atomic_write(path, lambda tmp: np.savetxt(tmp, trajectory.table(), delimiter=",",
                                              header=",".join(trajectory.header()),
                                              comments="", fmt="%.17g"))


def read_trajectory(path: str) -> tuple[list[str], np.ndarray]:
    """Header and rows of a CSV written by write_trajectory."""
    with open(path) as f:
        header = f.readline().strip().split(",")
    return header, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
