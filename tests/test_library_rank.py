"""Base atoms a fit can tell apart: the xArm7's URDF (example-robot-data) writes its joint
frames with pi/2 rounded, which leaves its armature2 and Izz2' atoms independent by 3.9e-6
only. Kept as two atoms, a sparse fit at 2 % noise gave them -260 and +260 and missed joint
2 by 31.9x the oracle on another motion; the library folds such a pair (RANK_TOL)."""

from __future__ import annotations

import numpy as np

from harness.robots.arm import Arm
from harness.robots.registry import erd_robots_dir
from identification.library.kinematic import N_STATES, RANK_TOL, random_states

XARM7 = str(erd_robots_dir() / "xarm_description" / "urdf" / "xarm7.urdf")


def test_no_two_base_atoms_of_the_xarm7_are_nearly_one():
    library = Arm.of(XARM7).library
    atoms = library.evaluate(*random_states(library.dof, N_STATES, seed=3))
    flat = atoms.reshape(-1, atoms.shape[2])
    flat = flat / np.linalg.norm(flat, axis=0)
    singular = np.linalg.svd(flat, compute_uv=False)
    assert singular[-1] / singular[0] > RANK_TOL  # 1.6e-6 with the pair kept
    # the folded atoms still span every candidate atom (the consistent fit reads them)
    assert library.fold.shape == (atoms.shape[2], 13 * library.dof)
