"""`torquebench replay --plan PLAN.json [--plant MJCF] --out REPLAY.json [--video FILE.mp4]`."""

from __future__ import annotations

import math
from dataclasses import asdict
from pathlib import Path

from harness.io import read_json, write_json
from harness.robots.registry import DEFAULT_ROBOT

FEEDFORWARD = "pinocchio"  # closed-form model of the default robot


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "replay",
        help="execute a planned trajectory in MuJoCo and measure energy, clearance, tracking",
        description="Track PLAN.json on a MuJoCo plant through its actuators (Pinocchio "
        "feedforward + PD at the simulation timestep), moving the obstacle along its path.",
    )
    p.add_argument("--plan", required=True, help="PLAN.json written by `torquebench plan`")
    p.add_argument("--plant", default=None,
                   help="plant MJCF (default: the lynxmotion scene with its obstacle)")
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
    from harness.robots.baseline import PinocchioModel
    from harness.robots.registry import load_mujoco, load_pinocchio

    reference = plan_reference(read_plan(args.plan))
    plant = args.plant or DEFAULT_ROBOT
    model = load_mujoco(plant, scene=True)
    result, trace = replay(model, reference, PinocchioModel(load_pinocchio(DEFAULT_ROBOT)))
    write_json(args.out, result_json(result, str(plant)))
    if args.video:
        from harness.replay.video import render_video

        render_video(model, trace, args.video)
    return 0
