"""`torquebench replay --plan PLAN.json [--plant MJCF] --out REPLAY.json [--video FILE.mp4]`."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import asdict
from pathlib import Path

from harness.commands import SUMMARY, add_chain_option, chain_option
from harness.errors import UserError
from harness.io import read_json, write_json

FEEDFORWARD = "pinocchio"  # closed-form model of the robot


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "replay",
        help=SUMMARY["replay"],
        description="Track PLAN.json on a MuJoCo plant through its actuators (Pinocchio "
        "feedforward + PD at the simulation timestep), moving the obstacle along its path.",
    )
    p.add_argument("--plan", required=True, help="PLAN.json written by `torquebench plan`")
    p.add_argument("--robot", default=None,
                   help="registered robot or URDF/MJCF path (default: the robot PLAN.json "
                        "records, else lynxmotion): its scene, built around it if it has none, "
                        "and its Pinocchio feedforward")
    add_chain_option(p)
    p.add_argument("--plant", default=None,
                   help="what is simulated: an MJCF scene with its motors (as it is), a URDF or "
                        "MJCF of the robot with other dynamics (a scene built around it, its "
                        "Pinocchio model the feedforward), or a MODEL.json with per-body "
                        "parameters (the identified dynamics, friction laws MuJoCo lacks applied as "
                        "joint torques, its torque the feedforward); "
                        "default: the robot's scene with floor, light, obstacle")
    p.add_argument("--out", required=True, help="REPLAY.json to write")
    p.add_argument("--video", default=None, help="also render the replay to this mp4")
    p.set_defaults(func=run)


def read_plan(path: str | Path) -> dict:
    """The JSON object in a PLAN.json file (validated by plan_reference)."""
    return read_json(path, "plan")


def result_json(result, plant: str, feedforward: str = FEEDFORWARD) -> dict:
    """REPLAY.json payload: the measured numbers plus how they were measured."""
    return {
        **asdict(result),
        "energy_error": result.energy_error if math.isfinite(result.energy_error) else None,
        "plant": plant,
        "feedforward": feedforward,
        "units": {"energy": "J", "clearance": "m", "tracking": "rad", "torque": "N m"},
    }


def run(args) -> int:
    from harness.replay.plants import replay_plant
    from harness.replay.reference import plan_reference
    from harness.replay.simulate import replay
    from harness.robots.resolve import resolve_arm

    plan = read_plan(args.plan)
    reference = plan_reference(plan)
    arm = resolve_arm(args.robot, data=[(args.plan, plan)], chain=chain_option(args))
    geometry = arm.geometry
    radii = plan.get("link_radii")
    if isinstance(radii, list) and len(radii) == len(geometry.links) and any(radii):
        geometry = dataclasses.replace(geometry, radii=tuple(float(r) for r in radii))
    geometry = plan_capsules(plan.get("link_capsules"), geometry)
    plant = replay_plant(args.plant, arm, geometry.radii, geometry)
    model = plant.model
    if geometry.dof != reference.dof:
        raise UserError(f"the plan has {reference.dof} joints, robot {arm.label} has {geometry.dof}")
    if args.video:  # a video asked for and impossible: said before anything is written
        from harness.replay.video import rendering_problem

        problem = rendering_problem(model)
        if problem:
            raise UserError(f"cannot render the video {args.video}: {problem}")
    result, trace = replay(model, reference, plant.feedforward, geometry=geometry,
                           friction=plant.friction)
    write_json(args.out, {**result_json(result, plant.label, plant.feedforward_label),
                          # friction the plant's joints felt as applied torques (MuJoCo's
                          # joints have no such law): harness.replay.friction
                          "plant_friction": list(plant.friction.described) if plant.friction
                          else [],
                          "robot": arm.reference, "links": geometry.link_names,
                          "link_min_clearance": trace.clearance.min(axis=0),
                          # m, mj_geomDistance of each link capsule to the obstacle sphere
                          "link_min_surface_clearance": None if trace.surface is None
                          else trace.surface.min(axis=0),
                          # the links' geometry the capsules could not be fitted to (stderr too)
                          "unread_geometry": [u._asdict() for u in arm.unread_geometry]})
    if args.video:
        from harness.replay.video import render_video

        render_video(model, trace, args.video, required=True)
    print(summary(args.plan, arm.label, result, _plant_words(args.plant)))
    return 0


def _point(values) -> tuple[float, ...]:
    point = tuple(float(v) for v in values)
    if len(point) != 3 or not all(math.isfinite(v) for v in point):
        raise ValueError(values)
    return point


def plan_capsules(capsules, geometry):
    """geometry with the link capsules PLAN.json's `link_capsules` records (planning.result
    .capsules), as it is without them."""
    if not isinstance(capsules, list) or not capsules:
        return geometry
    bad = UserError("PLAN.json's link_capsules must be {joint, a, b, radius} objects (a, b: 3 "
                    "finite numbers, radius >= 0)")
    try:
        joints = [int(c["joint"]) for c in capsules]
        ends = tuple((_point(c["a"]), _point(c["b"])) for c in capsules)
        radii = tuple(float(c["radius"]) for c in capsules)
    except (KeyError, TypeError, ValueError):
        raise bad from None
    if not all(math.isfinite(r) and r >= 0 for r in radii):
        raise bad
    covered = tuple(j - 1 for j in joints if (j - 1, j) not in geometry.links)
    planned = dataclasses.replace(geometry, covered=covered, ends=ends, radii=radii)
    if list(planned.links) != [(j - 1, j) for j in joints]:
        raise UserError(f"PLAN.json's link_capsules (joints {joints}) are not links of "
                        f"{geometry.name}")
    return planned


def _plant_words(plant: str | None) -> str:
    """What the replay line says of a --plant: the dynamics it stands for."""
    if plant is None:
        return ""
    if Path(plant).suffix.lower() == ".json":
        return f"the dynamics {plant} identified"
    return f"the dynamics of {plant}"


def summary(plan: str, robot: str, result, plant: str = "") -> str:
    """The line `replay` prints: the robot the plan ran on (and the plant's dynamics where
    --plant gave them), energy against the plan's, clearance, tracking."""
    change = (f", {100 * result.energy_error:+.1f} %" if math.isfinite(result.energy_error)
              else "")
    clearance = result.min_clearance  # to the links' surfaces, as the plan measures it
    on = f"{robot} with {plant}" if plant else robot
    return (f"replayed {plan} on {on}: energy {result.energy:.4f} J (plan "
            f"{result.energy_planned:.4f} J{change}), min clearance {1000 * clearance:.1f} mm, "
            f"tracking rms {result.tracking_rms:.2e} rad")
