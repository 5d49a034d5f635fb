"""The paper's planning problem: its Lynxmotion arm (links, joint and torque limits from
Arm.of("lynxmotion"), the closed-form kinematics of planning.formulation.kinematics.
paper_arm) and its scenario (the arm's registered motion in 2 s past the paper's obstacle
path). planning has no robot's defaults: whatever plans the paper's problem takes them
from here."""

from __future__ import annotations

from harness.plan.arm_config import motion_scenario, planner_config
from harness.robots.arm import Arm
from planning.config import PlannerConfig, Scenario

PAPER_ROBOT = "lynxmotion"


def paper_scenario() -> Scenario:
    """q0 = (pi/2, pi/5, -pi/4) to (-pi/2, 2pi/5, -pi/3) in 2 s from rest; the obstacle from
    (0.15, 0.40, 0.22) to (0.18, -0.35, 0.28) m, as in the paper."""
    return motion_scenario(Arm.of(PAPER_ROBOT))


def paper_config(**changes) -> PlannerConfig:
    """The paper's formulation (PlannerConfig's defaults: eq. 18 with N = 10, quartic joint
    polynomials, the penalty loop) on the Lynxmotion: its links, joint and torque limits."""
    arm = Arm.of(PAPER_ROBOT)
    lower, upper = arm.joint_limits
    return PlannerConfig(**{**dict(geometry=arm.geometry, lower=lower, upper=upper,
                                   torque_limit=arm.torque_limit), **changes})


def paper_default_config(**changes) -> PlannerConfig:
    """What `plan` plans with by default on the Lynxmotion (harness.plan.arm_config.
    planner_config)."""
    return planner_config(Arm.of(PAPER_ROBOT), **changes)
