"""A URDF's <dynamics damping friction> (Unitree's Z1 from example-robot-data states 1-2 N m
of both on every joint). Viscous damping is in both engines: MuJoCo's passive force inside
mj_inverse, PinocchioModel's damping * qd beside the RNEA. Coulomb friction would be a
frictionloss soft constraint in MuJoCo only; the harness drops it from the arm's URDF, so the
two engines agree to rounding on an arm that declares both (3.6 % of the peak torque apart
with it kept, 16 % with the damping dropped too)."""

from __future__ import annotations

import numpy as np

from harness.identify.scoring import closed_form_gap, sines_motion
from harness.robots.arm import Arm
from harness.robots.registry import erd_robots_dir

Z1 = erd_robots_dir() / "z1_description" / "urdf" / "z1.urdf"


def test_damping_is_in_both_engines_and_coulomb_friction_in_neither():
    arm = Arm.of(Z1)
    model, mj = arm.pinocchio, arm.mujoco
    assert model.nv == mj.nv == 7  # six arm joints and the gripper's revolute jaw
    np.testing.assert_allclose(model.damping, [1, 2, 1, 1, 1, 1, 1])  # the file's own
    np.testing.assert_allclose(mj.dof_damping, model.damping)
    assert not np.any(model.friction) and not np.any(mj.dof_frictionloss)
    assert closed_form_gap(arm, sines_motion(arm, 400, 3)) <= 1e-9
