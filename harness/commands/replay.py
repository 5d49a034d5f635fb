"""`torquebench replay --plan PLAN.json [--plant MJCF] --out REPLAY.json [--video FILE.mp4]`."""

from __future__ import annotations

import math
from dataclasses import asdict
from pathlib import Path

from harness.errors import UserError
from harness.io import read_json, write_json
from harness.robots.registry import data_robot

FEEDFORWARD = "pinocchio"  # closed-form model of the robot


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "replay",
        help="execute a planned trajectory in MuJoCo and measure energy, clearance, tracking",
        description="Track PLAN.json on a MuJoCo plant through its actuators (Pinocchio "
        "feedforward + PD at the simulation timestep), moving the obstacle along its path.",
    )
    p.add_argument("--plan", required=True, help="PLAN.json written by `torquebench plan`")
    p.add_argument("--robot", default=None,
                   help="registered robot or URDF/MJCF path (default: the robot PLAN.json "
                        "records, else lynxmotion): its scene, built around it if it has none, "
                        "and its Pinocchio feedforward")
    p.add_argument("--plant", default=None,
                   help="plant MJCF (default: the robot's scene with floor, light, obstacle)")
    p.add_argument("--out", required=True, help="REPLAY.json to write")
    p.add_argument("--video", default=None, help="also render the replay to this mp4")
    p.set_defaults(func=run)


def read_plan(path: str | Path) -> dict:
    """The JSON object in a PLAN.json file (validated by plan_reference)."""
    return read_json(path, "plan")


def result_json(result, plant: str) -> dict:
    """REPLAY.json payload: the measured numbers plus how they were measured."""
    return {
        **asdict(result),
        "energy_error": result.energy_error if math.isfinite(result.energy_error) else None,
        "plant": plant,
        "feedforward": FEEDFORWARD,
        "units": {"energy": "J", "clearance": "m", "tracking": "rad", "torque": "N m"},
    }


def run(args) -> int:
    from harness.replay.reference import plan_reference
    from harness.replay.simulate import replay
    from harness.robots.arm import arm_geometry
    from harness.robots.baseline import PinocchioModel
    from harness.robots.registry import load_mujoco, load_pinocchio
    from harness.robots.scene import replay_scene

    plan = read_plan(args.plan)
    reference = plan_reference(plan)
    robot = data_robot(plan if isinstance(plan, dict) else {}, args.robot)
    model = load_mujoco(args.plant, scene=True) if args.plant else replay_scene(robot)
    geometry = arm_geometry(robot)
    if geometry.dof != reference.dof:
        raise UserError(f"the plan has {reference.dof} joints, robot {robot} has {geometry.dof}")
    if args.video:  # a video asked for and impossible: said before anything is written
        from harness.replay.video import rendering_problem

        problem = rendering_problem(model)
        if problem:
            raise UserError(f"cannot render the video {args.video}: {problem}")
    result, trace = replay(model, reference, PinocchioModel(load_pinocchio(robot)),
                           geometry=geometry)
    write_json(args.out, {**result_json(result, str(args.plant or robot)), "robot": robot,
                          "links": geometry.link_names,
                          "link_min_clearance": trace.clearance.min(axis=0)})
    if args.video:
        from harness.replay.video import render_video

        render_video(model, trace, args.video, required=True)
    return 0
